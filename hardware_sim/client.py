"""The closed-loop client: plan -> move -> touch -> observe, until done.

The loop (:func:`run_recognition`) talks to two boundaries only:

- a :class:`RecognitionService`, the planner side: "what next?" and "here is
  what the probe found". :class:`InProcessService` calls the planner library
  directly (``planner.recognition.session.Session`` + ``planner.planning.forecast.plan_session``);
  :class:`hardware_sim.http_service.HttpService` asks a running service through
  the generated client (``hardware_sim.api_client``);
- a :class:`hardware_sim.protocol.Probe`, the hardware side.

World frame, lengths in the object files' unit, angles in radians.

>>> from hardware_sim.presets import build_arm
>>> from hardware_sim.world import World
>>> from planner.models.library import object_from_dict
>>> sq = object_from_dict({"name": "sq", "outline": [[-10, -10], [10, -10], [10, 10], [-10, 10]]})
>>> ws = Workspace((0, 0), 100)
>>> world = World(sq, 0, Pose(5.0, -3.0, 0.3), ws)
>>> service = InProcessService([sq], SensorBounds(), ws, StrategyConfig(name="pdm"))
>>> rec = run_recognition(service, build_arm(world, "ideal", seed=1), max_touches=6)
>>> rec.status, rec.touches
('localized', 2)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from hardware_sim.protocol import Probe
from planner.codec import observation_from_dict, observation_to_dict
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.types import (
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    StablePose,
    Workspace,
)

__all__ = [
    "Advice",
    "Estimate",
    "InProcessService",
    "Recognition",
    "RecognitionService",
    "Step",
    "Update",
    "outline_distance",
    "run_recognition",
]

DONE = ("localized", "inconsistent")


@dataclass(frozen=True)
class Advice:
    """The planner's answer to "what next?": session `status`, the best `path`
    (None when there is nothing to do or nothing informative), its predicted
    `p_distinguishing` (None for the opening probe, before any hypothesis),
    planning time `plan_ms`, `truncated` (the budget stopped the search),
    the planner's `note`, `expected_remaining`, the expected touches still
    needed when taking the path, itself included (None when unknown), and
    `p_forecast`, the recognition's own forecast of P(DM) (None when not made), and
    `stopped_by` (``"work"``, ``"time"``: what ended the plan early; None: nothing)."""

    status: str
    path: SensingPath | None
    p_distinguishing: float | None
    plan_ms: float
    truncated: bool = False
    note: str | None = None
    expected_remaining: float | None = None
    p_forecast: float | None = None
    stopped_by: str | None = None


@dataclass(frozen=True)
class Update:
    """The session after an observation: `status`, number of `hypotheses` and of
    equivalence `classes` left."""

    status: str
    hypotheses: int
    classes: int


@dataclass(frozen=True)
class Estimate:
    """One hypothesis as a client sees it: object, stable pose index, pose
    (model -> world), pose error disk diameter `eps_t` (length), probability,
    equivalence class, and the bound |dt| on the translation (length; None when
    not known)."""

    object: str
    stable_pose: int
    pose: Pose
    eps_t: float
    probability: float
    equivalence_class: int
    translation: float | None = None


class RecognitionService(Protocol):
    """The planner side of the loop (in process, or over HTTP)."""

    def advise(self, sensor_position: Sequence[float]) -> Advice:
        """Plan the next sensing path from the sensor's place on the safe circle."""
        ...

    def observe(self, observation: Observation) -> Update:
        """Add one executed path and what it met."""
        ...

    def estimates(self, limit: int | None = None) -> list[Estimate]:
        """Current hypotheses, most probable first."""
        ...

    def answer_bound(self) -> float | None:
        """The diameter of the error disk the session reports with its answer: the
        most probable class' bound (``localization.bound.eps_t``), which covers
        every member's and, for a class of one, is its own; None without one."""
        ...

    def answer(self, limit: int | None = None) -> tuple[list[Estimate], float | None]:
        """:meth:`estimates` and :meth:`answer_bound` of one state of the session
        (over HTTP, one request)."""
        ...


class InProcessService:
    """:class:`RecognitionService` calling the planner library in this process.

    Holds the (immutable) session and swaps it for the next on each observation.
    `rng` drives the planner's random choices (candidate subsampling, ties, the
    ``random`` strategy) across the whole recognition. With `seed` instead, each
    plan draws from ``default_rng([seed, version])``, version = 1 + observations so
    far: the stream the HTTP service uses for a session whose strategy has that
    `seed`, so both give the same plans.
    """

    def __init__(
        self,
        models: Sequence[ObjectModel],
        bounds: SensorBounds,
        workspace: Workspace,
        strategy: StrategyConfig | None = None,
        recognition: RecognitionConfig | None = None,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
    ) -> None:
        if rng is not None and seed is not None:
            raise ValueError("give rng or seed, not both")
        self.session = Session(models, bounds, workspace, recognition)
        self.strategy = strategy or StrategyConfig()
        self.seed = seed
        self.rng = rng if rng is not None else np.random.default_rng(0)

    def advise(self, sensor_position: Sequence[float]) -> Advice:
        s = self.session
        rng = self.rng
        if self.seed is not None:
            rng = np.random.default_rng([self.seed, 1 + len(s.observations)])
        result = plan_session(s, sensor_position, self.strategy, rng)
        best = result.best
        return Advice(
            status=result.status,
            path=None if best is None else best.path,
            p_distinguishing=None if best is None or not s.hypotheses else best.p_distinguishing,
            plan_ms=result.elapsed_ms,
            truncated=result.truncated,
            note=result.note,
            expected_remaining=None if best is None else best.expected_remaining,
            p_forecast=None if best is None else best.p_forecast,
            stopped_by=result.stopped_by,
        )

    def observe(self, observation: Observation) -> Update:
        # what a service would store: the same normalization (directions, normals to unit
        # length), so the in-process loop and the HTTP loop see identical observations
        stored = observation_from_dict(observation_to_dict(observation))
        self.session = self.session.observe(stored)
        hyps = self.session.hypotheses
        return Update(self.session.status, len(hyps), len({h.equivalence_class for h in hyps}))

    def answer_bound(self) -> float | None:
        bound = self.session.localization.bound
        return None if bound is None else float(bound.eps_t)

    def answer(self, limit: int | None = None) -> tuple[list[Estimate], float | None]:
        return self.estimates(limit), self.answer_bound()

    def estimates(self, limit: int | None = None) -> list[Estimate]:
        hyps = self.session.hypotheses[:limit]
        return [
            Estimate(
                h.object,
                h.stable_pose,
                h.pose,
                h.error_bound.eps_t,
                h.probability,
                h.equivalence_class,
                h.error_bound.translation,
            )
            for h in hyps
        ]


@dataclass(frozen=True)
class Step:
    """One probe of a recognition: the `advice` it followed, the `observation`
    it produced, the session `update` after it, and the move's `distance`
    (length) and `time` (s)."""

    advice: Advice
    observation: Observation
    update: Update
    distance: float
    time: float

    @property
    def distinguishing(self) -> bool:
        """True when one equivalence class was left after this touch (a DM),
        whether or not its bound is yet within the session's accuracy."""
        return self.update.classes == 1


@dataclass(frozen=True)
class Recognition:
    """A whole recognition: final `status` (localized, inconsistent, ambiguous
    when stopped by the touch limit, stuck when no informative path was left),
    the `steps`, the final `estimates` (most probable first), and `bound`, the
    diameter of the error disk the session reports with its answer (the most
    probable class' bound, :meth:`RecognitionService.answer_bound`)."""

    status: str
    steps: tuple[Step, ...]
    estimates: tuple[Estimate, ...]
    bound: float | None = None

    @property
    def touches(self) -> int:
        """Probes executed (misses included)."""
        return len(self.steps)

    @property
    def distance(self) -> float:
        return float(sum(s.distance for s in self.steps))

    @property
    def time(self) -> float:
        return float(sum(s.time for s in self.steps))


def run_recognition(
    service: RecognitionService,
    probe: Probe,
    max_touches: int,
    on_step: Callable[[Step], None] | None = None,
) -> Recognition:
    """Plan, move, touch, observe until `localized`, `inconsistent`, no path, or
    `max_touches` probes. Never prints; the caller reports the steps (`on_step` is
    called with each one as soon as it is done)."""
    if max_touches < 1:
        raise ValueError("max_touches must be >= 1")
    steps: list[Step] = []
    status = "awaiting_contact"
    while len(steps) < max_touches:
        advice = service.advise(probe.position)
        if advice.status in DONE:
            status = advice.status
            break
        if advice.path is None:
            status = "stuck"
            break
        result = probe.execute(advice.path)
        update = service.observe(result.observation)
        steps.append(Step(advice, result.observation, update, result.distance, result.time))
        if on_step is not None:
            on_step(steps[-1])
        status = update.status
        if status in DONE:
            break
    estimates, bound = service.answer(limit=None)
    return Recognition(status, tuple(steps), tuple(estimates), bound)


def outline_distance(
    models: Sequence[ObjectModel], estimate: Estimate, name: str, stable_pose: int, pose: Pose
) -> float:
    """Hausdorff distance (length) between the boundaries of the estimate's posed
    outline and the true one, holes included (symmetric equivalents give 0); inf
    for another object. Measured along the boundaries, not between vertex sets: a
    curved part turned by part of a face's angle keeps its outline while its
    vertices move."""
    import shapely

    by_name = {m.name: m for m in models}
    if estimate.object != name:
        return math.inf

    def polygon(stable: StablePose, at: Pose) -> shapely.Polygon:
        return shapely.Polygon(at.apply(stable.outline), [at.apply(h) for h in stable.holes])

    est = polygon(by_name[name].stable_poses[estimate.stable_pose], estimate.pose)
    true = polygon(by_name[name].stable_poses[stable_pose], pose)
    # every face split in 20 for the measure
    return float(shapely.hausdorff_distance(est.boundary, true.boundary, densify=0.05))
