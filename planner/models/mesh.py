"""3-D objects standing on a table, probed at one height (DESIGN §4.13, thesis §6.3).

A watertight triangle mesh is dropped on a table: each stable pose (with its
quasi-static probability, from :func:`trimesh.poses.compute_stable_poses`) is
sliced by the horizontal plane ``z = height`` above the table, and the slice
becomes one 2-D stable pose of an :class:`~planner.types.ObjectModel`. Every
outline face also records ``normal_z``, the vertical component of the outward
unit normal of the 3-D face it was cut from (0 for a vertical wall, positive
when the wall leans back so that its normal points up).

Frames: the posed mesh has the table at ``z = 0`` with z up; the 2-D model
frame is that frame's (x, y) shifted so that the origin is the slice's area
centroid (holes subtracted). Lengths are in the mesh's unit. Slices of
different poses that are congruent by an in-plane rotation and translation
(with matching ``normal_z``) are one 2-D model: they are merged and their
probabilities summed. Mirror images stay separate, since no rigid motion on
the table turns one into the other.

Nothing here reads or writes files; :mod:`planner.models.mesh_files` does.

>>> import trimesh
>>> model = object_from_mesh(trimesh.creation.box((40, 60, 100)), 8.0, "box")
>>> [round(p.probability, 3) for p in model.stable_poses]
[0.562, 0.316, 0.122]
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
import trimesh

from planner.errors import InvalidModelError, ModelFileError
from planner.geometry import point_segment_distance, polygon_centroid, signed_area
from planner.models.congruence import COLLINEAR_TOLERANCE, congruent
from planner.models.mesh_limits import MeshLimits
from planner.models.near_congruence import nearly_congruent
from planner.models.outlines import make_stable_pose, with_slices
from planner.types import ObjectModel, StablePose

__all__ = [
    "COLLINEAR_TOLERANCE",
    "MERGE_SHARE",
    "MESH_FILE_TYPES",
    "MeshLimits",
    "MeshSlice",
    "congruent",
    "drop_collinear",
    "import_mesh_bytes",
    "object_from_mesh",
    "parse_mesh_bytes",
    "slice_pose",
    "stable_poses",
]


#: Slices of two stable poses within this share of the slice's size of each other
#: (after a rotation) are one pose: the facets of one curved face of a tessellated
#: solid (:mod:`planner.models.near_congruence`).
MERGE_SHARE = 0.01

#: File types :func:`parse_mesh_bytes` accepts (trimesh's triangle-mesh formats).
MESH_FILE_TYPES = frozenset({"glb", "gltf", "obj", "off", "ply", "stl"})


@dataclass(frozen=True, eq=False)
class MeshSlice:
    """The slice of one posed mesh at one height, in the 2-D model frame.

    `outline` (N, 2) is counter-clockwise, each of `holes` clockwise, both
    centred on the area centroid; `normal_z` holds one value per face in face
    order (outline faces, then each hole's; face i runs from vertex i to i+1);
    `offset` (2,) is the centroid in the posed frame, so that a model point p
    sits at ``p + offset`` (height ``z = height``) above the table.
    """

    outline: np.ndarray
    holes: tuple[np.ndarray, ...]
    normal_z: np.ndarray
    offset: np.ndarray

    @property
    def rings(self) -> list[np.ndarray]:
        return [self.outline, *self.holes]


class _SplitSliceError(InvalidModelError):
    """A slice in several pieces: no single outline describes that stable pose."""


def parse_mesh_bytes(data: bytes, file_type: str) -> trimesh.Trimesh:
    """Decode a triangle mesh held in memory (an upload, or a file's bytes).

    `file_type` is one of :data:`MESH_FILE_TYPES` (case and a leading dot are
    ignored). Raises :class:`~planner.errors.ModelFileError` naming the problem
    when the bytes hold no triangles or cannot be decoded.

    >>> box = trimesh.creation.box((1, 2, 3))
    >>> parse_mesh_bytes(box.export(file_type="stl"), ".STL").faces.shape
    (12, 3)
    """
    kind = str(file_type).strip().lower().lstrip(".")
    if kind not in MESH_FILE_TYPES:
        raise ModelFileError(
            f"unsupported mesh type {file_type!r}; use one of {sorted(MESH_FILE_TYPES)}",
            field="file_type",
        )
    if not isinstance(data, bytes | bytearray) or not data:
        raise ModelFileError("is empty", field="file")
    try:
        mesh = trimesh.load_mesh(io.BytesIO(bytes(data)), file_type=kind, process=True)
    except Exception as exc:  # trimesh raises many kinds on malformed input
        raise ModelFileError(f"cannot decode {kind} mesh: {exc}", field="file") from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ModelFileError(f"holds no triangles (not a {kind} triangle mesh?)", field="file")
    return mesh


def _check_mesh(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A closed, consistently wound, outward-facing copy of `mesh`, or an error."""
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InvalidModelError("must be a triangle mesh with at least one face", field="mesh")
    if not np.all(np.isfinite(mesh.vertices)):
        raise InvalidModelError("vertex coordinates must be finite", field="mesh")
    if not mesh.is_watertight:
        # a closed surface uses every edge in exactly two faces: one face marks the
        # border of a hole, more than two a non-manifold seam
        _, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
        raise InvalidModelError(
            f"is not watertight ({int(np.sum(counts == 1))} edges border a hole in the "
            f"surface, {int(np.sum(counts > 2))} are shared by more than two faces): "
            "its volume, centre of mass and slices are undefined",
            field="mesh",
        )
    if not mesh.is_winding_consistent:
        raise InvalidModelError(
            "has inconsistent face winding (some faces point inwards)", field="mesh"
        )
    checked = mesh.copy()
    if checked.volume < 0:
        # all faces wound inwards: flip them so that normals point out of the solid
        checked.invert()
    if not checked.volume > 0:
        raise InvalidModelError("encloses no volume", field="mesh")
    return checked


def stable_poses(
    mesh: trimesh.Trimesh, *, sigma: float = 0.0, n_samples: int = 1, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Stable resting poses of a solid of uniform density and their probabilities.

    Returns ``(transforms, probabilities)``: (n, 4, 4) homogeneous transforms
    that put the mesh on the table (z up, lowest point at ``z = 0``) and the
    quasi-static probability of landing in each when dropped at random, most
    probable first. `sigma` (length squared) and `n_samples` sample the centre
    of mass around the true one with a fixed `seed`; the defaults use the true
    centre of mass, which is deterministic.
    """
    return _stable_poses(_check_mesh(mesh), sigma=sigma, n_samples=n_samples, seed=seed)


def _stable_poses(
    checked: trimesh.Trimesh, *, sigma: float, n_samples: int, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    transforms, probabilities = trimesh.poses.compute_stable_poses(
        checked, sigma=sigma, n_samples=n_samples, seed=seed
    )
    return np.asarray(transforms, dtype=float), np.asarray(probabilities, dtype=float)


def drop_collinear(ring: np.ndarray, tol: float) -> np.ndarray:
    """Remove the vertices of a closed ring lying within `tol` (length) of the
    line through their two neighbours; the cyclic order of the others is kept.
    When the first vertex goes, the ring starts at the kept vertex before it.

    >>> drop_collinear(np.array([[0, 0], [1, 0], [2, 0], [2, 2], [0, 2]]), 1e-9).tolist()
    [[0, 0], [2, 0], [2, 2], [0, 2]]
    >>> drop_collinear(np.array([[1, 0], [2, 0], [2, 2], [0, 2], [0, 0]]), 1e-9).tolist()
    [[0, 0], [2, 0], [2, 2], [0, 2]]
    """
    ring = np.asarray(ring)
    first = ring[0]
    while len(ring) > 3:
        prev, nxt = np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0)
        chord = nxt - prev
        # distance of v from the line prev-next: |(next - prev) x (v - prev)| / |next - prev|
        cross = chord[:, 0] * (ring - prev)[:, 1] - chord[:, 1] * (ring - prev)[:, 0]
        span = np.hypot(chord[:, 0], chord[:, 1])
        flat = np.abs(cross) <= tol * np.maximum(span, tol)
        # never remove two neighbours at once (a removal moves its neighbours'
        # lines): even indices go first, odd ones only between kept vertices
        even = np.arange(len(ring)) % 2 == 0
        remove = flat & (even | ~(np.roll(flat, 1) | np.roll(flat, -1)))
        if len(ring) % 2:
            # the last and first indices are both even and neighbours
            remove[-1] &= not remove[0]
        if not remove.any() or len(ring) - int(remove.sum()) < 3:
            break
        ring = ring[~remove]
    if not np.array_equal(ring[0], first):
        # the first vertex went: start at the kept vertex that preceded it
        ring = np.roll(ring, 1, axis=0)
    return ring


def _orient(ring: np.ndarray, counter_clockwise: bool) -> np.ndarray:
    """The ring in the asked turning sense, keeping its first vertex first."""
    if (signed_area(ring) > 0) == counter_clockwise:
        return ring
    # reverse the closed ring v0, v1, ..., v(n-1) into v0, v(n-1), ..., v1
    return np.roll(ring[::-1], 1, axis=0)


def _face_normal_z(
    rings: Sequence[np.ndarray], segments: np.ndarray, segment_nz: np.ndarray
) -> np.ndarray:
    """Per outline face, the length-weighted mean `normal_z` of the mesh cut
    segments (S, 2, 2) lying on it (each segment goes to its nearest face)."""
    starts = np.concatenate(rings)
    ends = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    middle = segments.mean(axis=1)
    # distance of each segment midpoint (S, 1) to each face (1, F)
    distance = point_segment_distance(middle[:, None, :], starts[None], ends[None])
    face = np.argmin(distance, axis=1)
    weight = np.hypot(*(segments[:, 1] - segments[:, 0]).T)
    total = np.bincount(face, weights=weight, minlength=len(starts))
    # normal_z(f) = sum_s w_s nz_s / sum_s w_s over segments s on face f
    weighted = np.bincount(face, weights=weight * segment_nz, minlength=len(starts))
    lonely = total <= 0
    if lonely.any():
        # a face no segment chose (degenerate): take the segment nearest its midpoint
        mid = (starts[lonely] + ends[lonely]) / 2
        near = np.argmin(np.hypot(*(middle[None] - mid[:, None]).transpose(2, 0, 1)), axis=1)
        weighted[lonely], total[lonely] = segment_nz[near], 1.0
    return np.clip(weighted / total, -1.0, 1.0)


def slice_pose(
    mesh: trimesh.Trimesh,
    transform: np.ndarray,
    height: float,
    *,
    pose: int = 0,
    tol: float = COLLINEAR_TOLERANCE,
) -> MeshSlice:
    """Slice `mesh`, put on the table by `transform` (4, 4), at `height` above it.

    The cut is one outline with any number of holes; collinear vertices (within
    `tol` times the slice's size) are dropped. Raises
    :class:`~planner.errors.InvalidModelError` naming `height` and the pose
    index `pose` when the plane misses the object or cuts it into separate
    pieces or open curves.
    """
    height = _check_height(height)
    posed = mesh.copy()
    posed.apply_transform(np.asarray(transform, dtype=float))
    top = float(posed.bounds[1, 2])
    lines, face_index = trimesh.intersections.mesh_plane(
        posed, plane_normal=[0.0, 0.0, 1.0], plane_origin=[0.0, 0.0, height], return_faces=True
    )
    if len(lines) == 0 or height >= top:
        raise InvalidModelError(
            f"the plane at height {height:g} misses stable pose {pose}, which stands "
            f"{top:.6g} tall: choose a height between 0 and {top:.6g}",
            field="height",
        )
    path = trimesh.load_path(lines)
    curves = [np.asarray(c, dtype=float)[:, :2] for c in path.discrete]
    if not all(len(c) > 3 and np.allclose(c[0], c[-1]) for c in curves):
        raise InvalidModelError(
            f"the slice of stable pose {pose} at height {height:g} has open curves",
            field="height",
        )
    rings = [c[:-1] for c in curves]
    scale = float(np.ptp(np.concatenate(rings), axis=0).max())
    rings = [drop_collinear(r, tol * scale) for r in rings]
    # nesting depth of each ring: how many other rings contain one of its vertices
    polygons = [shapely.Polygon(r) for r in rings]
    depth = np.array(
        [
            sum(p.contains(shapely.Point(r[0])) for j, p in enumerate(polygons) if j != i)
            for i, r in enumerate(rings)
        ]
    )
    if int(np.sum(depth == 0)) != 1 or np.any(depth > 1):
        raise _SplitSliceError(
            f"the slice of stable pose {pose} at height {height:g} falls into "
            f"{int(np.sum(depth % 2 == 0))} separate pieces; a stable pose must be one "
            "outline (with holes): choose another height",
            field="height",
        )
    outline = _orient(rings[int(np.argmax(depth == 0))], counter_clockwise=True)
    holes = tuple(
        _orient(r, counter_clockwise=False) for r, d in zip(rings, depth, strict=True) if d == 1
    )
    offset = polygon_centroid(outline, holes)
    outline, holes = outline - offset, tuple(h - offset for h in holes)
    normal_z = _face_normal_z(
        [outline, *holes], lines[:, :, :2] - offset, posed.face_normals[face_index, 2]
    )
    return MeshSlice(outline=outline, holes=holes, normal_z=normal_z, offset=offset)


def _check_height(height: float) -> float:
    try:
        value = float(height)
    except (TypeError, ValueError) as exc:
        raise InvalidModelError("must be a number", field="height") from exc
    if not math.isfinite(value) or value <= 0:
        raise InvalidModelError(
            f"must be a finite number > 0 (above the table), got {height!r}", field="height"
        )
    return value


def object_from_mesh(
    mesh: trimesh.Trimesh,
    height: float,
    name: str,
    max_poses: int | None = None,
    *,
    seed: int = 0,
    limits: MeshLimits | None = None,
    heights: Sequence[float] = (),
) -> ObjectModel:
    """The object model of a solid standing on a table, probed at `height`, and
    at each of `heights` as well (DESIGN §4.13: slices at several heights, the
    first at `height`, the default).

    Computes the stable poses and their probabilities, slices each at `height`
    (mesh units above the table), merges poses whose slices are congruent, or
    within `MERGE_SHARE` of the slice's size of it (the facets of one curved face
    of a tessellated solid; the merged pose then keeps no out-of-plane normals),
    probabilities summed, keeps the `max_poses` most probable (all when None)
    and renormalizes their probabilities to sum to 1. A pose whose slice falls
    into separate pieces (an L resting on the tips of its arms) has no single
    outline and is left out like a pose beyond `max_poses`; when every pose is
    split, or the plane misses any pose, the height is refused. Raises
    :class:`~planner.errors.InvalidModelError` naming the field (`mesh`,
    `height`, `name`, `max_poses`) when an input cannot give a model. `limits`
    bound the work before it is done (:class:`MeshLimits`; None: unbounded).
    With `heights`, every kept pose is also sliced there, in the model frame of
    its slice at `height`; poses are then not merged (equal poses give one
    equivalence class in a session all the same), and a height above some pose's
    top is refused.

    >>> box = trimesh.creation.box((40, 60, 100))
    >>> model = object_from_mesh(box, 8.0, "box", max_poses=2)
    >>> [sorted(np.ptp(p.outline, axis=0).tolist()) for p in model.stable_poses]
    [[60.0, 100.0], [40.0, 100.0]]
    """
    height = _check_height(height)
    extra = _extra_heights(height, heights)
    if not isinstance(name, str) or not name.strip() or len(name) > 200:
        raise InvalidModelError(
            "must be a non-empty string of at most 200 characters", field="name"
        )
    if max_poses is not None and (
        isinstance(max_poses, bool) or not isinstance(max_poses, int) or max_poses < 1
    ):
        raise InvalidModelError(f"must be an integer >= 1, got {max_poses!r}", field="max_poses")
    limits = limits or MeshLimits()
    limits.check_triangles(mesh)
    checked = _check_mesh(mesh)
    limits.check_hull(checked)
    transforms, probabilities = _stable_poses(checked, sigma=0.0, n_samples=1, seed=seed)
    slices: dict[int, MeshSlice] = {}
    split: list[_SplitSliceError] = []
    for i in limits.sliced(probabilities):
        transform = transforms[i]
        try:
            slices[i] = slice_pose(checked, transform, height, pose=i)
        except _SplitSliceError as exc:
            split.append(exc)
    if not slices:
        raise split[0]
    upper = {i: [slice_pose(checked, transforms[i], z, pose=i) for z in extra] for i in slices}

    def same(a: int, b: int) -> str | None:
        # with several heights, poses stay apart (congruent at one height is not at all)
        if extra:
            return None
        if congruent(slices[a], slices[b]):
            return "exact"
        size = float(np.hypot(*slices[a].outline.T).max())
        return "near" if nearly_congruent(slices[a], slices[b], MERGE_SHARE * size) else None

    # group congruent slices; the first (most probable) of a group represents it;
    # a group holding tessellation variants keeps no out-of-plane normals (they differ)
    groups: list[list[int]] = []
    varied: list[bool] = []
    for i in slices:
        home = next(((k, how) for k, g in enumerate(groups) if (how := same(g[0], i))), None)
        if home is None:
            groups.append([i])
            varied.append(False)
        else:
            groups[home[0]].append(i)
            varied[home[0]] |= home[1] == "near"
    merged = np.array([probabilities[g].sum() for g in groups])
    order = np.argsort(-merged, kind="stable")[: max_poses or len(groups)]
    # P(pose | kept) = P(pose) / sum of P over the kept poses
    kept = merged[order] / merged[order].sum()
    poses = [
        _pose(k, slices[groups[g][0]], upper[groups[g][0]], float(p), height, extra, varied[g])
        for k, (g, p) in enumerate(zip(order, kept, strict=True))
    ]
    return ObjectModel(name=name, stable_poses=tuple(poses))


def _pose(
    k: int,
    first: MeshSlice,
    upper: list[MeshSlice],
    probability: float,
    height: float,
    extra: list[float],
    varied: bool = False,
) -> StablePose:
    """Stable pose `k` of the model: its slice at `height` and, at each of the
    `extra` heights, its `upper` slice in the frame of the first (a model point p
    is the posed point p + first.offset at every height); without out-of-plane
    normals when it stands for `varied` tessellation variants."""
    pose = make_stable_pose(
        first.outline,
        first.holes,
        min(probability, 1.0),
        None if varied else first.normal_z.tolist(),
        field=f"stable_poses[{k}].outline",
    )
    if not extra:
        return pose
    layers = []
    for j, u in enumerate(upper):
        shift = u.offset - first.offset
        layers.append(
            make_stable_pose(
                u.outline + shift,
                [h + shift for h in u.holes],
                pose.probability,
                u.normal_z.tolist(),
                field=f"stable_poses[{k}].slices[{j + 1}].outline",
            )
        )
    return with_slices(
        [(height, pose), *zip(extra, layers, strict=True)], field=f"stable_poses[{k}].slices"
    )


def _extra_heights(height: float, heights: Sequence[float]) -> list[float]:
    """The probing heights besides the default one, checked, in the order given."""
    out: list[float] = []
    for z in heights:
        value = _check_height(z)
        if all(abs(value - other) > 1e-6 * max(1.0, other) for other in [height, *out]):
            out.append(value)
    return out


def import_mesh_bytes(
    data: bytes,
    file_type: str,
    height: float,
    name: str,
    max_poses: int | None = None,
    limits: MeshLimits | None = None,
    heights: Sequence[float] = (),
) -> ObjectModel:
    """Decode a mesh held in memory (an HTTP upload) and build its object model.

    See :func:`parse_mesh_bytes` for `file_type` and :func:`object_from_mesh`
    for the rest; raises :class:`~planner.errors.ModelFileError` for bytes that
    are no mesh and :class:`~planner.errors.InvalidModelError` for a mesh that
    gives no model.
    """
    height = _check_height(height)
    mesh = parse_mesh_bytes(data, file_type)
    return object_from_mesh(mesh, height, name, max_poses, limits=limits, heights=heights)
