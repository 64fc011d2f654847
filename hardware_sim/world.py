"""The simulated world: one true object lying in one stable pose at one pose.

It executes sensing paths against the truth by ray casting and reports the first
contact, perturbed anywhere inside bounded errors (the ideal probe of DESIGN §5;
the arm and strain-gauge sensor models build on it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from planner.geometry import cast_rays
from planner.models.prior import draw_poses, draw_stable_poses
from planner.models.tip import cast_ball
from planner.types import (
    Contact,
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    StablePose,
    Workspace,
)

__all__ = ["PLACEMENTS", "World", "random_world"]

#: Where :func:`random_world` puts the object in the safe circle.
PLACEMENTS = ("anywhere", "centred")


@dataclass(frozen=True)
class World:
    """A true object, its stable pose and pose, and the safe circle around it."""

    model: ObjectModel
    pose_index: int
    pose: Pose
    workspace: Workspace

    @property
    def stable(self) -> StablePose:
        return self.model.stable_poses[self.pose_index]

    def posed_faces(self, height: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World face starts, ends and outward normals of the outline at probing
        `height` (None: the default height)."""
        faces = self.stable.layer(height).faces
        rot = self.pose.rotation()
        return self.pose.apply(faces.start), self.pose.apply(faces.end), faces.normal @ rot.T

    def polygon(self, height: float | None = None) -> shapely.Polygon:
        """The posed outline at probing `height` (None: the default height)."""
        layer = self.stable.layer(height)
        return shapely.Polygon(
            self.pose.apply(layer.outline), [self.pose.apply(h) for h in layer.holes]
        )

    def first_contact(self, path: SensingPath) -> tuple[np.ndarray, int] | None:
        """Exact first contact point and face index (of the layer at the path's
        height) along `path`, or None on a miss."""
        start, end, _ = self.posed_faces(path.height)
        origin, direction = np.asarray(path.origin), np.asarray(path.direction)
        dist, face = cast_rays(
            origin[None], direction[None], np.array([path.length]), start[None], end[None]
        )
        if face[0] < 0:
            return None
        return origin + dist[0] * direction, int(face[0])

    def ball_contact(
        self, path: SensingPath, radius: float
    ) -> tuple[np.ndarray, np.ndarray, int] | None:
        """Where a ball tip of `radius` whose centre runs along `path` stops: its
        centre, the surface point it touches and that point's face, or None on a miss.

        The exact grown outline (:func:`planner.models.tip.cast_ball`). A ball
        that meets a vertex rolls off it onto the neighbouring face whose normal
        the path pushes against most (DESIGN §5: vertex contacts slide onto a
        face): it rests touching the vertex, centred on that face's normal.
        """
        start, end, normal = self.posed_faces(path.height)
        hit = cast_ball(path.origin, path.direction, path.length, start, end, normal, radius)
        if hit is None:
            return None
        t, face, vertex = hit
        d = np.asarray(path.direction, dtype=float)
        if vertex < 0:
            centre = np.asarray(path.origin, dtype=float) + t * d
            return centre, centre - radius * normal[face], face
        # the faces ending and starting at the vertex; the one facing the path most
        face = min((face, vertex), key=lambda f: float(d @ normal[f]))
        point = start[vertex]
        return point + radius * normal[face], point, face

    def execute(
        self,
        path: SensingPath,
        bounds: SensorBounds | None = None,
        rng: np.random.Generator | None = None,
        edge_share: float = 0.0,
    ) -> tuple[Observation, int | None]:
        """Run a path; the contact is perturbed uniformly inside the bounds. With a
        ball tip (`bounds.tip_radius`) the contact is the ball's centre
        (:meth:`ball_contact`), perturbed likewise.

        With `edge_share` > 0, that share of the perturbations lies exactly on the
        bounds' edges (|position error| = eps_d, |normal error| = phi), the worst
        case for soundness tests. Returns the observation and the true face index
        (among the stable pose's `all_faces`, as the recognition's assignments).
        """
        bounds = bounds or SensorBounds()
        r = bounds.tip_radius
        if r > 0:  # a ball tip reports its centre
            ball = self.ball_contact(path, r)
            hit = None if ball is None else (ball[0], ball[2])
        else:
            hit = self.first_contact(path)
        if hit is None:
            return Observation(path, None), None
        point, face = hit
        rng = rng or np.random.default_rng(0)
        eps_d, phi = bounds.position_error, bounds.normal_error
        on_edge = rng.random() < edge_share
        radius = eps_d * (1.0 if on_edge else math.sqrt(rng.random()))
        a = rng.uniform(-math.pi, math.pi)
        point = point + radius * np.array([math.cos(a), math.sin(a)])
        on_edge = rng.random() < edge_share
        delta = phi * rng.choice([-1.0, 1.0]) if on_edge else rng.uniform(-phi, phi)
        normal = self.posed_faces(path.height)[2][face]
        angle = math.atan2(normal[1], normal[0]) + delta
        contact = Contact((float(point[0]), float(point[1])), (math.cos(angle), math.sin(angle)))
        return Observation(path, contact), face + self.stable.layer_start(path.height)

    def hitting_path(self, rng: np.random.Generator) -> SensingPath:
        """A path from a random point of the safe circle aimed at a random point of the object."""
        poly = self.polygon()
        minx, miny, maxx, maxy = poly.bounds
        while True:
            aim = np.array([rng.uniform(minx, maxx), rng.uniform(miny, maxy)])
            if poly.contains(shapely.Point(aim)):
                break
        return path_towards(self.workspace, rng.uniform(-math.pi, math.pi), aim)


def path_towards(workspace: Workspace, angle: float, aim: np.ndarray) -> SensingPath:
    """The path from the safe circle point at `angle` (radians) through `aim`, to the far side."""
    center = np.asarray(workspace.center)
    origin = center + workspace.radius * np.array([math.cos(angle), math.sin(angle)])
    direction = np.asarray(aim, dtype=float) - origin
    return SensingPath(tuple(origin), tuple(direction), 2.0 * workspace.radius)


def random_world(
    models: list[ObjectModel],
    workspace: Workspace,
    rng: np.random.Generator,
    placement: str = "anywhere",
) -> World:
    """A true world drawn from the planner's prior (:mod:`planner.models.prior`): object by
    its prior, stable pose by its probability, orientation uniform. `placement`
    ``anywhere``: position uniform among those keeping the object inside the safe
    circle (the planner's assumption, so its probabilities can be checked against
    frequencies); ``centred``: the outline's centroid at the circle's centre (the
    thesis' simulations, §4.3.6, where the object's place was known and only the
    probing direction random)."""
    if placement not in PLACEMENTS:
        raise ValueError(f"placement must be one of {list(PLACEMENTS)}")
    ((i, pose_index),) = draw_stable_poses(models, 1, rng)
    model = models[i]
    stable = model.stable_poses[pose_index]
    theta_a, t_a = draw_poses(stable, workspace, 1, rng)
    theta, center = float(theta_a[0]), t_a[0]
    if placement == "centred":  # v_world = R v + t with R centroid + t = centre
        center = np.asarray(workspace.center) - Pose(0.0, 0.0, theta).apply([stable.centroid])[0]
    return World(model, pose_index, Pose(float(center[0]), float(center[1]), theta), workspace)
