"""Frozen value types shared by the whole planner.

Conventions (DESIGN §2): one consistent length unit (whatever the object files
use), angles in radians, world frame x right / y up, rotations
counter-clockwise positive, and a pose maps model to world as
``v_world = R(theta) v_model + t``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from planner import geometry
from planner.errors import InvalidObservationError
from planner.memo import cached_property

__all__ = [
    "Accuracy",
    "Contact",
    "ErrorBound",
    "Faces",
    "Hypothesis",
    "InterpretationId",
    "ObjectModel",
    "Observation",
    "Pose",
    "PosePrior",
    "SensingPath",
    "SensorBounds",
    "StablePose",
    "Workspace",
]

Vec2 = tuple[float, float]

#: Relative tolerance within which a path's height names a slice's height.
HEIGHT_TOLERANCE = 1e-6


def _finite_vec(value: Sequence[float], name: str) -> Vec2:
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError) as exc:
        raise InvalidObservationError("must be two numbers", field=name) from exc
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InvalidObservationError("must be finite (no NaN or infinity)", field=name)
    return (x, y)


def _unit_vec(value: Sequence[float], name: str) -> Vec2:
    x, y = _finite_vec(value, name)
    if x == 0 and y == 0:
        raise InvalidObservationError("must not be the zero vector", field=name)
    norm = math.hypot(x, y)
    if norm < 1e-150:  # tiny or subnormal: bring it to about 1 first so it keeps its way
        scale = max(abs(x), abs(y))
        x, y = x / scale, y / scale
        norm = math.hypot(x, y)
    return (x / norm, y / norm)


@dataclass(frozen=True)
class Pose:
    """Rigid 2-D transform from model to world: ``v_world = R(theta) v_model + (x, y)``.

    >>> Pose(1.0, 2.0, math.pi / 2).apply([[1.0, 0.0]]).round(12).tolist()
    [[1.0, 3.0]]
    """

    x: float
    y: float
    theta: float

    @property
    def translation(self) -> np.ndarray:
        return np.array([self.x, self.y])

    def rotation(self) -> np.ndarray:
        return geometry.rotation_matrix(self.theta)

    def apply(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """Map model points (N, 2) to the world frame."""
        return np.asarray(points, dtype=float) @ self.rotation().T + self.translation

    def inverse_apply(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """Map world points (N, 2) to the model frame."""
        return (np.asarray(points, dtype=float) - self.translation) @ self.rotation()


@dataclass(frozen=True)
class SensorBounds:
    """Bounded measurement error: contact position within `position_error` (length)
    of the truth, measured normal within `normal_error` (radians) of the true one.
    With a ball tip of `tip_radius` (length, DESIGN §4.14) the contact reported is
    the ball's centre, and the position bound is the centre's."""

    position_error: float = 0.0
    normal_error: float = 0.0
    tip_radius: float = 0.0

    def __post_init__(self) -> None:
        for name in ("position_error", "normal_error", "tip_radius"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise InvalidObservationError("must be a finite number >= 0", field=name)
        if self.normal_error >= math.pi / 4:
            raise InvalidObservationError("must be below pi/4 radians", field="normal_error")


@dataclass(frozen=True)
class PosePrior:
    """What is known of the pose before touching (a fixture, a camera, the previous
    part): the object's area centroid lies within `radius` of `center` (world frame,
    length unit), and its rotation within [theta_lo, theta_hi] (radians, counter-
    clockwise; `theta_hi - theta_lo` at most 2 pi). Either part may be None. Inside
    it every pose is as likely as before; outside it none is considered.

    >>> PosePrior((0.0, 0.0), 10.0).admits_centroid(3.0, 4.0)
    True
    """

    center: Vec2 | None = None
    radius: float | None = None
    theta: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if (self.center is None) != (self.radius is None):
            raise InvalidObservationError(
                "give the region's center and radius together", field="prior.region"
            )
        if self.center is not None:
            object.__setattr__(self, "center", _finite_vec(self.center, "prior.region.center"))
            if not (self.radius is not None and math.isfinite(self.radius) and self.radius > 0):
                raise InvalidObservationError(
                    "must be a finite number > 0", field="prior.region.radius"
                )
        if self.theta is not None:
            lo, hi = (float(v) for v in self.theta)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi <= lo + 2 * math.pi):
                raise InvalidObservationError(
                    "must be [lo, hi] radians with lo <= hi <= lo + 2 pi", field="prior.theta"
                )
            object.__setattr__(self, "theta", (lo, hi))

    def admits_centroid(self, x: float, y: float, slack: float = 0.0) -> bool:
        """Is a centroid at (x, y) within the region (widened by `slack`)?"""
        if self.center is None or self.radius is None:
            return True
        return math.hypot(x - self.center[0], y - self.center[1]) <= self.radius + slack


@dataclass(frozen=True)
class Accuracy:
    """What `localized` requires of the pose (DESIGN §2, §6): the bound on the
    translation at most `translation` (length) and on the rotation at most
    `rotation` (radians). :meth:`default_for` gives one fitted to the sensor."""

    translation: float
    rotation: float

    def __post_init__(self) -> None:
        for name in ("translation", "rotation"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0:
                raise InvalidObservationError(
                    "must be a finite number > 0", field=f"accuracy.{name}"
                )

    @classmethod
    def default_for(cls, sensor: SensorBounds, diameter: float) -> Accuracy:
        """The default for a sensor and the largest object's effective diameter
        (twice its farthest vertex from the centroid): ``5 eps_d + 2%`` of the
        diameter, and ``2 phi + 0.02`` rad. Five position errors is what two or
        three well-placed touches bound the translation to; twice the normal
        error is the rotation any two normals leave; the 2% keep exact sensing
        from asking for the impossible.

        >>> a = Accuracy.default_for(SensorBounds(1.0, math.radians(3)), 100.0)
        >>> round(a.translation, 3), round(math.degrees(a.rotation), 2)
        (7.0, 7.15)
        """
        return cls(5 * sensor.position_error + 0.02 * diameter, 2 * sensor.normal_error + 0.02)

    def admits(self, bound: ErrorBound, *, rotation_free: bool = False) -> bool:
        """True when `bound` is within this accuracy (its translation alone when the
        rotation is free: a round outline's, which no touch can measure)."""
        turned = rotation_free or bound.rotation <= self.rotation
        return bound.translation <= self.translation and turned


@dataclass(frozen=True)
class Workspace:
    """The safe circle: known to contain the object; every sensing path starts on it."""

    center: Vec2 = (0.0, 0.0)
    radius: float = 200.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _finite_vec(self.center, "workspace.center"))
        if not math.isfinite(self.radius) or self.radius <= 0:
            raise InvalidObservationError("must be a finite number > 0", field="workspace.radius")


@dataclass(frozen=True)
class SensingPath:
    """A straight sensing path: from `origin` along the unit `direction` for `length`,
    at probing `height` above the table (DESIGN §4.13; None: the default height,
    where each stable pose's first slice was cut)."""

    origin: Vec2
    direction: Vec2
    length: float
    height: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", _finite_vec(self.origin, "path.origin"))
        object.__setattr__(self, "direction", _unit_vec(self.direction, "path.direction"))
        if not math.isfinite(self.length) or self.length <= 0:
            raise InvalidObservationError("must be a finite number > 0", field="path.length")
        if self.height is not None:
            if not math.isfinite(self.height):
                raise InvalidObservationError("must be a finite number", field="path.height")
            object.__setattr__(self, "height", float(self.height))

    def point_at(self, distance: float) -> np.ndarray:
        return np.asarray(self.origin) + distance * np.asarray(self.direction)

    @property
    def end(self) -> np.ndarray:
        return self.point_at(self.length)


@dataclass(frozen=True)
class Contact:
    """A touch: world contact point and measured outward unit surface normal.

    `normal_z` is the optional out-of-plane component of the 3-D normal (objects
    standing on a table, DESIGN §4.13)."""

    point: Vec2
    normal: Vec2
    normal_z: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _finite_vec(self.point, "contact.point"))
        object.__setattr__(self, "normal", _unit_vec(self.normal, "contact.normal"))
        if self.normal_z is not None and not (
            math.isfinite(self.normal_z) and -1.0 <= self.normal_z <= 1.0
        ):
            raise InvalidObservationError("must lie in [-1, 1]", field="contact.normal_z")

    @property
    def normal_angle(self) -> float:
        return math.atan2(self.normal[1], self.normal[0])


@dataclass(frozen=True)
class Observation:
    """One executed sensing path and what it met (`contact is None`: a miss)."""

    path: SensingPath
    contact: Contact | None = None

    def behind_origin(self) -> float:
        """How far the contact lies behind the path's origin (0 for a miss or a
        contact ahead of it). A measured contact may lie up to the position error
        behind it, where the part lies that close to the origin; the session that
        knows its sensor refuses more (:meth:`~planner.recognition.session.Session.observe`)."""
        if self.contact is None:
            return 0.0
        offset = np.asarray(self.contact.point) - np.asarray(self.path.origin)
        return max(0.0, -float(offset @ np.asarray(self.path.direction)))


@dataclass(frozen=True, eq=False)
class Faces:
    """The faces (edges) of one stable pose's outline and holes, in model frame.

    Arrays of length F: `start`, `end` (F, 2), outward unit `normal` (F, 2),
    `offset` d = n·v, `length`, `angle` = atan2 of the normal, `ring` (0 for the
    outline, i for hole i)."""

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    length: np.ndarray
    angle: np.ndarray
    ring: np.ndarray

    def __len__(self) -> int:
        return len(self.length)

    @property
    def direction(self) -> np.ndarray:
        return (self.end - self.start) / self.length[:, None]


@dataclass(frozen=True, eq=False)
class StablePose:
    """One outline of an object (counter-clockwise, holes clockwise) and its prior.

    Build it with :func:`planner.models.outlines.make_stable_pose`, which validates and
    orients the rings; `normal_z` (one value per face, or None) is the
    out-of-plane normal component of the 3-D face each outline face was cut from.

    Probing heights (DESIGN §4.13): the outline is the slice at `height` (None: a
    prism, the same outline at every height), and `slices` are the pose's
    outlines at other heights, each a StablePose of its own without slices.
    Layer 0 is this outline, layer k the k-th slice; `faces` are layer 0's, and
    `all_faces` every layer's in layer order (what the interpretation tree
    assigns contacts to, `face_layer` saying whose each face is).
    """

    outline: np.ndarray
    holes: tuple[np.ndarray, ...] = ()
    probability: float = 1.0
    normal_z: np.ndarray | None = None
    height: float | None = None
    slices: tuple[StablePose, ...] = ()

    @cached_property
    def faces(self) -> Faces:
        return Faces(**geometry.ring_faces([self.outline, *self.holes]))

    @property
    def layers(self) -> tuple[StablePose, ...]:
        """The outline at each probing height: this one, then the slices."""
        return (self, *self.slices)

    @property
    def heights(self) -> tuple[float, ...] | None:
        """The heights of the layers, or None for a prism (any height)."""
        if self.height is None:
            return None
        return tuple(float(p.height) for p in self.layers)  # type: ignore[arg-type]

    def layer_index(self, height: float | None) -> int:
        """Which layer a path at `height` meets (None: the default, layer 0).
        Refuses a height the pose has no slice at."""
        heights = self.heights
        if height is None or heights is None:
            return 0
        for k, z in enumerate(heights):
            if abs(z - height) <= HEIGHT_TOLERANCE * max(1.0, abs(z)):
                return k
        said = ", ".join(f"{z:g}" for z in heights)
        raise InvalidObservationError(
            f"no slice at height {height:g} (this stable pose's: {said})", field="path.height"
        )

    def layer(self, height: float | None) -> StablePose:
        """The outline a path at `height` meets, as a StablePose without slices."""
        return self.layers[self.layer_index(height)]

    @cached_property
    def all_faces(self) -> Faces:
        if not self.slices:
            return self.faces
        parts = [p.faces for p in self.layers]
        rings = np.cumsum([0] + [int(f.ring.max()) + 1 for f in parts[:-1]])
        merged = {
            name: np.concatenate([getattr(f, name) for f in parts])
            for name in ("start", "end", "normal", "offset", "length", "angle")
        }
        merged["ring"] = np.concatenate([f.ring + r for f, r in zip(parts, rings, strict=True)])
        return Faces(**merged)

    def layer_start(self, height: float | None) -> int:
        """Where the faces of the layer at `height` start among `all_faces`."""
        return int(np.count_nonzero(self.face_layer < self.layer_index(height)))

    @cached_property
    def face_layer(self) -> np.ndarray:
        """(F_all,) the layer of each of `all_faces`."""
        return np.concatenate([np.full(len(p.faces), k) for k, p in enumerate(self.layers)])

    @cached_property
    def all_normal_z(self) -> np.ndarray | None:
        """`normal_z` over `all_faces` (None unless every layer has it)."""
        if any(p.normal_z is None for p in self.layers):
            return None
        return np.concatenate([p.normal_z for p in self.layers])  # type: ignore[misc]

    @cached_property
    def extent(self) -> np.ndarray:
        """The outer vertices of every layer (model frame): what bounds how far any
        point of the pose lies from a reference point."""
        return np.concatenate([p.outline for p in self.layers])

    @cached_property
    def face_ends(self) -> np.ndarray:
        """(F,) for each face of `all_faces`, the face that starts where it ends (the
        next face of its ring): a face's end vertex is ``all_faces.start[face_ends]``."""
        ring = self.all_faces.ring
        out = np.arange(len(ring))
        for r in np.unique(ring):
            at = np.flatnonzero(ring == r)
            out[at] = np.roll(at, -1)
        return out

    @cached_property
    def centroid(self) -> np.ndarray:
        """Area centroid of the outline with holes (model frame)."""
        return geometry.polygon_centroid(self.outline, self.holes)

    @cached_property
    def radius(self) -> float:
        """Distance of the farthest vertex (of any layer) from the model origin."""
        return float(np.max(np.hypot(*self.extent.T)))

    @cached_property
    def centroid_radius(self) -> float:
        """Distance of the farthest vertex (of any layer) from the centroid."""
        return float(np.max(np.hypot(*(self.extent - self.centroid).T)))

    @cached_property
    def shape(self):  # shapely.Polygon, built lazily
        import shapely

        return shapely.Polygon(self.outline, [h for h in self.holes])

    def coordinates_equal(self, other: StablePose, tol: float = 0.0) -> bool:
        if self.outline.shape != other.outline.shape or len(self.holes) != len(other.holes):
            return False
        if self.heights != other.heights or not all(
            a.coordinates_equal(b, tol) for a, b in zip(self.slices, other.slices, strict=True)
        ):
            return False
        rings = zip([self.outline, *self.holes], [other.outline, *other.holes], strict=True)
        return all(a.shape == b.shape and np.allclose(a, b, atol=tol, rtol=0) for a, b in rings)


@dataclass(frozen=True, eq=False)
class ObjectModel:
    """A named object with one or more stable poses and an optional prior weight."""

    name: str
    stable_poses: tuple[StablePose, ...]
    prior: float | None = None

    def same_geometry(self, other: ObjectModel) -> bool:
        return len(self.stable_poses) == len(other.stable_poses) and all(
            a.coordinates_equal(b) and math.isclose(a.probability, b.probability)
            for a, b in zip(self.stable_poses, other.stable_poses, strict=True)
        )


@dataclass(frozen=True)
class ErrorBound:
    """Pose error bound: |dt| of the pose translation, |dtheta| (radians), and
    `eps_t`, the diameter of the error disk swept along the posed outline."""

    translation: float
    rotation: float
    eps_t: float


class InterpretationId(NamedTuple):
    """Which interpretation of the tree a hypothesis was posed from: the `group`
    (object and stable pose) and the `row` of its face assignment in that group.
    The samples of one slide family (DESIGN §4.6) share it."""

    group: int
    row: int


@dataclass(frozen=True)
class Hypothesis:
    """One interpretation of the contacts: object, stable pose, face per contact
    (None = spurious), pose with its error bound, and probability; `interpretation`
    says which interpretation of the tree it was posed from."""

    object: str
    stable_pose: int
    assignment: tuple[int | None, ...]
    pose: Pose
    error_bound: ErrorBound
    probability: float
    equivalence_class: int = 0
    interpretation: InterpretationId = field(default=InterpretationId(-1, -1), compare=False)
