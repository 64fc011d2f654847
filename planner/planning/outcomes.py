"""Predicted outcome of each sensing path for each hypothesis (DESIGN §4.11).

Everything here is in the world frame, lengths in the object files' unit, angles
in radians (counter-clockwise positive). The pipeline is three numpy passes:

1. :func:`pose_hypotheses` packs the posed faces of all hypotheses into padded
   arrays (H hypotheses x F faces);
2. :func:`predict_outcomes` casts every candidate path against every posed
   hypothesis at once (chunked over candidates): first hit (point, face normal)
   or miss, and the ways the outcome is uncertain (vertex, grazing, near miss,
   contact at the very end of the path);
3. :func:`planner.planning.confusability.class_survivors` compares the outcomes
   of every pair of hypotheses on every path within the §4.11 tolerances and
   gives the survivor sets over equivalence classes as bitsets
   (:class:`SurvivorTable`). Slot points lie on the path, so a match is an
   overlap of intervals along it and of normal arcs:
   sorted interval ends answer all pairs at once with unions of bitsets, and
   only slots near a tie (or off the path) are compared one by one
   (:mod:`planner.planning.matching`). The hypothesis-level matrix
   (:func:`~planner.planning.confusability.confusability`) comes from the same pass.

Posed hypotheses live in :mod:`planner.planning.posed_set`, the casting in
:mod:`planner.planning.casting` and candidate paths in
:mod:`planner.planning.candidates` (the general set from
:mod:`planner.planning.candidate_generation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from planner.errors import PlannerError
from planner.geometry import LENGTH_SLACK
from planner.planning.casting import cast_paths
from planner.planning.posed_set import PosedSet
from planner.types import SensorBounds

__all__ = ["OutcomeConfig", "Outcomes", "predict_outcomes"]


@dataclass(frozen=True)
class OutcomeConfig:
    """Tolerances of the outcome model beyond the sensor and pose error bounds.

    `grazing_angle` (radians): a hit whose path meets the face within this angle
    (plus the hypothesis' rotation bound) of parallel is grazing. `contact_patch`
    (length): half-size of the sensed patch (the thesis' finite data site), added
    to the vertex and near-miss zones. `chunk_elements` bounds the size of the
    intermediate arrays (candidates x hypotheses x faces) of one chunk.
    """

    grazing_angle: float = 0.1
    contact_patch: float = 0.0
    chunk_elements: int = 1_000_000

    def __post_init__(self) -> None:
        if not (math.isfinite(self.grazing_angle) and 0 <= self.grazing_angle < math.pi / 2):
            raise PlannerError("must lie in [0, pi/2)", field="outcome.grazing_angle")
        if not (math.isfinite(self.contact_patch) and self.contact_patch >= 0):
            raise PlannerError("must be a finite number >= 0", field="outcome.contact_patch")
        if self.chunk_elements < 1:
            raise PlannerError("must be >= 1", field="outcome.chunk_elements")


@dataclass(frozen=True, eq=False)
class Outcomes:
    """Predicted outcome of C paths on H hypotheses (world frame).

    Nominal outcome: `hit`, `distance` along the path (inf on a miss), `point`
    and `normal` (C, H, 2; NaN on a miss), `face` (-1 on a miss), `travel` (how
    far the sensor moves: the hit distance, or the path length on a miss).
    Uncertainty flags (C, H): `vertex` (hit within tolerance of a vertex),
    `grazing` (path nearly parallel to the face hit), `near_miss` (a miss that
    passes within the vertex zone of a face it may meet: slot 1 spans every such
    stretch of it), `end_of_path` (hit within tolerance of the path's end: it may
    be a miss), `shallow` (the path cuts so little of the outline that the
    recognition, which lets a path run into an outline by its tolerances, may let
    it pass: it may be a miss), `close_pass` (before its hit the path passes within
    the vertex zone of another vertex: it may be met there first), `stretch` (past
    the hit the path stays shallow enough for a contact and passes near other
    faces, or stays so for long: slot 0 then spans that stretch with the normals of
    those faces, or any normal), `open_stretch` (a stretch that may meet a face of
    any normal: it was still shallow at its last point).

    Outcome slots (C, H, 4) list everything the outcome could turn out to be:
    slot 0 the nominal outcome, slot 1 a hit near the nominal point (or near the
    closest approach of a near miss or of a close pass) whose normal may lie
    anywhere in the cone `slot_angle +- slot_spread` between the faces meeting at
    the vertex, slot 2 the path slipping past the contact (the next hit further on,
    or a miss; a vertex hit's close pass takes it when it is free), slot 3 a
    slipping path meeting a face it passes near further on.
    `slot_slack` widens the point tolerance of grazing hits, whose contact
    slides along the path by `tolerance / |cos(incidence)|`. `slot_distance`
    is how far along the path a slot's point lies (NaN for a miss) and
    `slot_offset` how far off the path, to its left (only a near miss's closest
    approach lies off it); `heading` (C,) is each path's direction angle.
    """

    hit: np.ndarray
    distance: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    face: np.ndarray
    travel: np.ndarray
    vertex: np.ndarray
    grazing: np.ndarray
    near_miss: np.ndarray
    end_of_path: np.ndarray
    shallow: np.ndarray
    close_pass: np.ndarray
    stretch: np.ndarray
    open_stretch: np.ndarray
    slot_valid: np.ndarray
    slot_hit: np.ndarray
    slot_point: np.ndarray
    slot_angle: np.ndarray
    slot_spread: np.ndarray
    slot_slack: np.ndarray
    slot_distance: np.ndarray
    slot_offset: np.ndarray
    heading: np.ndarray

    @classmethod
    def concat(cls, parts: list[Outcomes]) -> Outcomes:
        """The outcomes of several groups of paths, one after the other (one group
        as it is: outcomes are never written to once cast)."""
        if len(parts) == 1:
            return parts[0]
        return cls(
            **{f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls)}
        )

    @property
    def uncertain(self) -> np.ndarray:
        """(C, H) bool: the outcome may be something other than the nominal one."""
        return self.uncertain_on(slice(None))

    def uncertain_on(self, paths: int | slice | np.ndarray) -> np.ndarray:
        """:attr:`uncertain` of the paths `paths` only (rows of the flags)."""
        flags = ("vertex", "grazing", "near_miss", "end_of_path", "shallow", "close_pass")
        out = self.stretch[paths].copy()
        for name in flags:
            out |= getattr(self, name)[paths]
        return out


def _tolerances(posed: PosedSet, sensor: SensorBounds, config: OutcomeConfig) -> dict:
    floor = LENGTH_SLACK * posed.scale
    # how far the true outline may lie from the posed one: half the error disk
    geometric = posed.eps_t / 2 + config.contact_patch + floor
    return {
        "geometric": geometric,
        # a contact this close to a vertex may be on either face (or slip off)
        "vertex": geometric + sensor.position_error,
        # |dir . n| below this: the path meets the face nearly parallel
        "graze_sin": np.sin(np.minimum(config.grazing_angle + posed.rotation, math.pi / 2)),
    }


def predict_outcomes(
    posed: PosedSet,
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> Outcomes:
    """Cast C paths (origins (C, 2), unit directions (C, 2), lengths (C,)) against
    every posed hypothesis, in numpy passes chunked over the paths.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.planning.posed_set import pose_hypotheses
    >>> from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose
    >>> square = ObjectModel("sq", (make_stable_pose([[-1, -1], [1, -1], [1, 1], [-1, 1]]),))
    >>> h = Hypothesis("sq", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 1.0)
    >>> out = predict_outcomes(pose_hypotheses([h], {"sq": square}),
    ...     np.array([[5.0, 0.0]]), np.array([[-1.0, 0.0]]), np.array([10.0]), SensorBounds())
    >>> out.point[0, 0].tolist(), out.normal[0, 0].tolist()
    ([1.0, 0.0], [1.0, 0.0])
    """
    config = config or OutcomeConfig()
    origins = np.asarray(origins, dtype=float).reshape(-1, 2)
    directions = np.asarray(directions, dtype=float).reshape(-1, 2)
    lengths = np.asarray(lengths, dtype=float).reshape(-1)
    tol = _tolerances(posed, sensor, config)
    return Outcomes(
        **cast_paths(
            posed,
            origins,
            directions,
            lengths,
            (tol["geometric"], tol["vertex"], tol["graze_sin"]),
            config.chunk_elements,
        )
    )
