"""Event-sourced recognition session: observations -> state -> plan.

The ordered observations (with the object set, sensor bounds, safe circle and
configuration) are the source of truth; the weighted hypothesis set is derived
from them and cached. :meth:`Session.observe` returns a new session that extends
the interpretation tree of its parent incrementally; :meth:`Session.undo` drops
the last observation.

>>> from planner.models.library import object_from_dict
>>> from planner.types import Contact, Observation, SensingPath
>>> square = object_from_dict({"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
>>> s = Session([square], workspace=Workspace((0, 0), 10))
>>> s.status
'awaiting_contact'
>>> s = s.observe(Observation(SensingPath((0, -10), (0, 1), 20), Contact((0, -1), (0, -1))))
>>> s = s.observe(Observation(SensingPath((10, 0), (-1, 0), 20), Contact((1, 0), (1, 0))))
>>> s.status, len(s.hypotheses), len({h.equivalence_class for h in s.hypotheses})
('localized', 4, 1)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from typing import Literal

import numpy as np

from planner.arrays import row_labels
from planner.errors import InvalidObservationError
from planner.geometry import LENGTH_SLACK
from planner.memo import cached_property
from planner.models.congruence import shape_labels
from planner.models.heights import check_height, probing_heights
from planner.models.round import round_within
from planner.models.simplify import simplify_models, widened
from planner.models.tip import surface_bounds, surface_contact
from planner.recognition.class_join import join_classes
from planner.recognition.config import RecognitionConfig
from planner.recognition.derived import (
    Derived,
    derive_together,
    derived_state,
    empty_state,
    interpretation_labels,
)
from planner.recognition.equivalence import (
    SAMPLE_SPACING,
    SYMMETRY_FLOOR,
    PosedRings,
    equivalence_classes,
    none_can_share,
)
from planner.recognition.evaluate import PoseSamples, evaluate_groups
from planner.recognition.localization import Localization, answer_bound, class_bound
from planner.recognition.tree import Group, TreeLevel, extend, face_of, make_groups
from planner.types import (
    Accuracy,
    ErrorBound,
    Hypothesis,
    InterpretationId,
    ObjectModel,
    Observation,
    Pose,
    SensorBounds,
    StablePose,
    Workspace,
)

__all__ = ["Localization", "Session", "Status"]

Status = Literal["awaiting_contact", "ambiguous", "localized", "inconsistent"]


class Session:
    """A recognition in progress. Immutable: `observe` and `undo` return new sessions."""

    def __init__(
        self,
        models: Sequence[ObjectModel],
        sensor: SensorBounds | None = None,
        workspace: Workspace | None = None,
        config: RecognitionConfig | None = None,
        observations: Iterable[Observation] = (),
        *,
        accuracy: Accuracy | None = None,
        _parent: Session | None = None,
    ) -> None:
        if not models:
            raise InvalidObservationError("a session needs at least one object", field="objects")
        names = [m.name for m in models]
        if len(set(names)) != len(names):
            raise InvalidObservationError("object names must be unique", field="objects")
        self.sensor = sensor or SensorBounds()
        #: the objects as given; `models` are what the session works with: finely
        #: drawn outlines simplified within the sensor's bounds (DESIGN §4.1), and
        #: `deviation` how far those stray from the given ones
        self.given_models: tuple[ObjectModel, ...] = tuple(models)
        if _parent is not None:
            self.models, self.deviation = _parent.models, _parent.deviation
        else:
            self.models, self.deviation = simplify_models(self.given_models, self.sensor)
        #: the sensor bounds against the worked outlines (widened by `deviation`)
        self.working_sensor = widened(self.sensor, self.deviation)
        # the recognition's view of the contacts: on the surface, with a ball tip's
        # centre moved back by its radius (DESIGN §4.14)
        self.bounds = surface_bounds(self.working_sensor)
        self.workspace = workspace or Workspace()
        self.config = config or RecognitionConfig()
        self.observations: tuple[Observation, ...] = tuple(observations)
        self._parent = _parent
        self._groups: list[Group] = (
            _parent._groups if _parent is not None else make_groups(list(self.models))
        )
        #: which groups' stable poses are one shape (only those share a class)
        self._shapes: np.ndarray = (
            _parent._shapes
            if _parent is not None
            else shape_labels([g.stable for g in self._groups])
        )
        self.length_scale = max(g.stable.centroid_radius for g in self._groups)
        self.accuracy = accuracy or self._default_accuracy()
        # what a parent session holds it has checked; a session built from a log checks all
        held = len(_parent.observations) if _parent is not None else 0
        for observation in self.observations[held:]:
            self._check(observation)

    def _check(self, observation: Observation) -> None:
        """Refuse a path height some object has no slice at, and a contact lying
        behind the path's origin by more than the position error (a part within
        the error of the origin may put a measured contact there)."""
        check_height(self.models, observation.path.height)
        length = max(1.0, observation.path.length)
        slack = self.working_sensor.position_error + LENGTH_SLACK * length
        if observation.behind_origin() > slack:
            raise InvalidObservationError(
                "contact lies behind the path origin by more than the position error",
                field="contact.point",
            )

    def _default_accuracy(self) -> Accuracy:
        """:meth:`Accuracy.default_for` the sensor; with the thesis' fixed error disk,
        which never shrinks, nothing beyond one class (as the thesis asked)."""
        diameter = 2 * self.length_scale
        if self.config.bound_mode == "thesis":
            return Accuracy(diameter, math.pi)
        return Accuracy.default_for(self.bounds, diameter)

    # -- events -----------------------------------------------------------------
    def observe(self, observation: Observation) -> Session:
        """The session after one more observation (the tree is extended, not rebuilt).
        Refuses a path height some object has no slice at."""
        return self._after(observation, self.config)

    def predict(self, observation: Observation) -> Session:
        """The session after an observation a plan predicts (:mod:`planner.planning.
        forecast`): as :meth:`observe`, its weights without the residual fitness
        (a third of an update). What a prediction asks (which interpretations
        survive, their classes, the bound) depends on it only through the order in
        which the equivalence picks its leaders."""
        return self._after(observation, dataclasses.replace(self.config, residual_fitness=False))

    def predict_many(self, observations: Sequence[Observation]) -> list[Session | None]:
        """:meth:`predict` of each observation (None where it is not a valid one),
        the contacts among them checked in one evaluation
        (:func:`~planner.recognition.derived.derive_together`): the same sessions,
        without the fixed cost of an evaluation each."""
        out: list[Session | None] = []
        for observation in observations:
            try:
                out.append(self.predict(observation))
            except InvalidObservationError:
                out.append(None)
        hits = [s for s in out if s is not None and s.observations[-1].contact is not None]
        if len(hits) > 1:
            first = hits[0]
            levels, states = derive_together(
                self._groups, self._derived.ahead, list(first.surface_observations[:-1]),
                [s.surface_observations[-1] for s in hits], first.bounds, first.workspace,
                first.config, first.length_scale,
            )  # fmt: skip
            for s, level, state in zip(hits, levels, states, strict=True):
                s.__dict__["_extended"], s.__dict__["_derived"] = level, state
        return out

    def _after(self, observation: Observation, config: RecognitionConfig) -> Session:
        return Session(
            self.given_models,
            self.sensor,
            self.workspace,
            config,
            (*self.observations, observation),
            accuracy=self.accuracy,
            _parent=self,
        )

    def undo(self) -> Session:
        """The session without its last observation."""
        if not self.observations:
            raise InvalidObservationError("there is no observation to undo", field="observations")
        if self._parent is not None:
            return self._parent
        return Session(
            self.given_models,
            self.sensor,
            self.workspace,
            self.config,
            self.observations[:-1],
            accuracy=self.accuracy,
        )

    def __getstate__(self) -> dict:
        """Pickled without the parent chain (a restored session undoes by replaying)."""
        state = dict(self.__dict__)
        state["_parent"] = None
        state.pop("_extended", None)  # the tree before the checks: only the update needs it
        return state

    @property
    def models_by_name(self) -> dict[str, ObjectModel]:
        return {m.name: m for m in self.models}

    @property
    def contacts(self) -> list:
        """The contacts as reported (a ball tip's centre)."""
        return [o.contact for o in self.observations if o.contact is not None]

    @cached_property
    def surface_observations(self) -> tuple[Observation, ...]:
        """The observations as the recognition sees them: each contact on the
        surface (:func:`~planner.models.tip.surface_contact`), within `bounds`."""
        r = self.sensor.tip_radius
        if r == 0:
            return self.observations
        return tuple(
            o if o.contact is None else Observation(o.path, surface_contact(o.contact, r))
            for o in self.observations
        )

    # -- derived state ------------------------------------------------------------
    @cached_property
    def _extended(self) -> TreeLevel | None:
        """The interpretation tree grown by the last observation, before any
        interpretation is checked (None without observations): table lookups only."""
        parent_level: TreeLevel | None
        if self._parent is not None:
            parent_level = self._parent._derived.ahead
        elif not self.observations:
            parent_level = None
        else:
            prefix = Session(self.given_models, self.sensor, self.workspace, self.config)
            for obs in self.observations[:-1]:
                prefix = prefix.observe(obs)
            parent_level = prefix._derived.ahead
        if parent_level is None:  # no observation at all
            return None
        last = self.observations[-1]
        if last.contact is None:
            return parent_level
        contacts = [o.contact for o in self.surface_observations if o.contact is not None]
        return extend(
            parent_level, self._groups, contacts, self.bounds, self.config, last.path.height
        )

    @property
    def interpretation_work(self) -> int:
        """What checking the interpretations the last observation leaves will cost,
        known before any is checked: each row of the tree is fitted, bounded and
        checked against every contact, and a row that leaves the pose free to slide
        is sampled (up to ``max_family_samples``), so rows x (contacts + samples).
        About 5-10 microseconds a unit on a 2-core machine."""
        if not self.observations:
            return 0
        # a checked (or restored) session counts the interpretations the checks left
        level = self._derived.level if "_derived" in self.__dict__ else self._extended
        contacts = sum(1 for o in self.observations if o.contact is not None)
        rows = sum(len(r) for r in level.rows)  # type: ignore[union-attr]
        return rows * (contacts + self.config.max_family_samples)

    @cached_property
    def _derived(self) -> Derived:
        level = self._extended
        if level is None:  # no observation at all
            return empty_state(self._groups)
        found = evaluate_groups(
            self._groups,
            level.rows,
            list(self.surface_observations),
            self.bounds,
            self.workspace,
            self.config,
            self.length_scale,
        )
        return derived_state(self._groups, level, found)

    @property
    def hypothesis_count(self) -> int:
        """How many hypotheses the observations leave, known before their classes
        are found (the interpretation tree and the pose fits only): what bounds the
        cost of :attr:`hypotheses`."""
        return sum(len(c.weight) for c in self._derived.candidates)

    @cached_property
    def class_count(self) -> int:
        """How many equivalence classes the hypotheses form: as many as hypotheses
        when no two can share one (:func:`~planner.recognition.equivalence.
        none_can_share`, without measuring their outlines: most of a plan's
        predicted sessions), else counted from :attr:`hypotheses`."""
        n = self.hypothesis_count
        if n > 1 and "_ranked" not in self.__dict__ and self._apart:
            return n
        return len({h.equivalence_class for h in self.hypotheses})

    @cached_property
    def _apart(self) -> bool:
        """No two hypotheses can share a class (:func:`~planner.recognition.
        equivalence.none_can_share` at one probing height: apart there, apart)."""
        cands = [c for c in self._derived.candidates if len(c.weight)]
        z = probing_heights(self.models)[0]
        return none_can_share(
            [self._stable(c, z) for c in cands], [c.theta for c in cands],
            [c.t for c in cands], interpretation_labels(cands),
            self._shapes[[c.group for c in cands]], self.symmetry_tolerance,
        )  # fmt: skip

    @property
    def hypotheses(self) -> list[Hypothesis]:
        """Weighted hypotheses, most probable first, with equivalence classes."""
        return self._ranked[0]

    @property
    def joined_classes(self) -> frozenset[int]:
        """The classes (as numbered in :attr:`hypotheses`) that leaders split and a
        join made one (:mod:`planner.recognition.class_join`): their members lie
        within ``tau`` of the leader, not ``tau / 2``."""
        return self._ranked[1]

    @cached_property
    def _ranked(self) -> tuple[list[Hypothesis], frozenset[int]]:
        cands = [c for c in self._derived.candidates if len(c.weight)]
        if not cands:
            return [], frozenset()
        weight = np.concatenate([c.weight for c in cands])
        total = weight.sum()
        prob = weight / total if total > 0 else np.full(len(weight), 1 / len(weight))
        classes, wide = self._equivalence(cands, prob)
        class_prob = np.bincount(classes, weights=prob)
        rank = np.empty(len(class_prob), np.int64)
        rank[np.argsort(-class_prob, kind="stable")] = np.arange(len(class_prob))
        out = []
        level = self._derived.level
        # Python numbers first: one conversion per array, not one per element
        probs, labels = prob.tolist(), rank[classes].tolist()
        i = 0
        for c in cands:
            group = self._groups[c.group]
            assignments = [
                tuple(row) if min(row, default=0) >= 0 else tuple(face_of(f) for f in row)
                for row in level.rows[c.group][c.row].tolist()
            ]
            columns = zip(
                c.t.tolist(),
                c.theta.tolist(),
                c.d_translation.tolist(),
                c.d_theta.tolist(),
                c.eps_t.tolist(),
                c.row.tolist(),
                assignments,
                strict=True,
            )
            for (x, y), theta, d_t, d_theta, eps_t, row, assignment in columns:
                out.append(
                    Hypothesis(
                        object=group.model.name,
                        stable_pose=group.pose_index,
                        assignment=assignment,
                        pose=Pose(x, y, theta),
                        error_bound=ErrorBound(d_t, d_theta, eps_t),
                        probability=probs[i],
                        equivalence_class=labels[i],
                        interpretation=InterpretationId(c.group, row),
                    )
                )
                i += 1
        out.sort(key=lambda h: (-h.probability, h.equivalence_class))
        return out, frozenset(int(rank[c]) for c in np.unique(classes[wide]))

    @cached_property
    def symmetry_tolerance(self) -> float:
        """``tau``: posed outlines closer than this are one equivalence class (DESIGN
        §2): ``2 eps_d``, fixed by the sensor; with the thesis' fixed error disk, half
        that disk, as the thesis merged what its disk could not tell apart."""
        tau = max(2 * self.bounds.position_error, SYMMETRY_FLOOR * self.length_scale)
        if self.config.bound_mode == "thesis":
            core = [c.eps_t - c.cell for c in self._derived.candidates if len(c.weight)]
            if core:
                tau = max(tau, float(np.median(np.concatenate(core))) / 2)
        return tau

    def _equivalence(
        self, cands: list[PoseSamples], prob: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Class label per hypothesis (:mod:`planner.recognition.equivalence`): posed
        outlines within the symmetry tolerance of each other, most probable first,
        classes the leaders split joined where they coincide
        (:mod:`planner.recognition.class_join`); and per hypothesis whether its
        class was joined. When no two can share a class, each is its own, numbered
        as the leaders come (most probable first), found without the classes."""
        tau = self.symmetry_tolerance
        order = np.argsort(-prob, kind="stable")
        if self._apart:  # the candidates `cands` are the derived state's
            place = np.empty(len(prob), dtype=np.int64)
            place[order] = np.arange(len(prob))
            return place, np.zeros(len(prob), dtype=bool)
        labels = interpretation_labels(cands)
        shapes = self._shapes[[c.group for c in cands]]
        spacing = SAMPLE_SPACING * tau  # of the points measured along each face
        # one class: the outlines coincide at every probing height
        per_height, wide = [], np.zeros(len(prob), dtype=bool)
        for z in probing_heights(self.models):
            rings = [PosedRings.of(self._stable(c, z), c.theta, c.t, spacing) for c in cands]
            label = equivalence_classes(rings, order, labels, tau, shapes)
            label, joined = join_classes(rings, label, order, labels, tau, shapes=shapes)
            per_height.append(label)
            wide |= joined[label]
        if len(per_height) == 1:
            return per_height[0], wide
        classes = row_labels(np.column_stack(per_height))
        return classes, wide

    def _stable(self, cands: PoseSamples, height: float | None) -> StablePose:
        return self._groups[cands.group].stable.layer(height)

    @property
    def status(self) -> Status:
        """``localized`` when one equivalence class is left AND its bound is within
        the session's accuracy, or the classes left are one answer within it
        (:mod:`planner.recognition.localization`); ``ambiguous`` otherwise."""
        if not self.contacts:
            return "awaiting_contact"
        if not self.hypotheses:
            return "inconsistent"
        return "localized" if not self.localization.missing else "ambiguous"

    @cached_property
    def localization(self) -> Localization:
        """How far the session is from `localized`: classes left, the bound of the
        answer, and what is missing (:mod:`planner.recognition.localization`)."""
        hyps = self.hypotheses
        classes = len({h.equivalence_class for h in hyps})
        if not hyps:
            return Localization(0, None, self.accuracy, ("one_class",))
        best = hyps[0].equivalence_class
        members = [h for h in hyps if h.equivalence_class == best]
        # the members lie within tau/2 of the leader's outline (tau in a joined class):
        # the class bound is the widest member's, its outline disk widened by as much;
        # a class of one is its leader, and its bound the leader's own
        half = self.symmetry_tolerance / (1 if best in self.joined_classes else 2)
        half = 0.0 if len(members) == 1 else half
        # a round outline's rotation is free: every rotation is one class
        free = all(self._round_poses[h.object][h.stable_pose] for h in members)
        bound = class_bound(members, half, free)
        if classes > 1 and self.config.bound_mode != "thesis":  # the thesis: one class
            union = answer_bound(
                hyps, bound, self.accuracy, self._layers, self.symmetry_tolerance, free
            )
            if union is not None:  # the classes left are one answer
                return Localization(classes, union, self.accuracy, (), free, classes)
        missing = (() if classes == 1 else ("one_class",)) + (
            () if self.accuracy.admits(bound, rotation_free=free) else ("accuracy",)
        )
        return Localization(classes, bound, self.accuracy, missing, free)

    def _layers(self, name: str, stable_pose: int) -> list[StablePose]:
        """The outline of an object's stable pose at every probing height."""
        stable = self.models_by_name[name].stable_poses[stable_pose]
        return [stable.layer(z) for z in probing_heights(self.models)]

    @cached_property
    def _round_poses(self) -> dict[str, list[bool]]:
        """Per object, whether each stable pose is round within the symmetry tolerance."""
        tau = self.symmetry_tolerance
        return {m.name: [round_within(p, tau) for p in m.stable_poses] for m in self.models}

    def posed_outline(self, hypothesis: Hypothesis) -> np.ndarray:
        """World coordinates of a hypothesis' outline."""
        stable = self.models_by_name[hypothesis.object].stable_poses[hypothesis.stable_pose]
        return hypothesis.pose.apply(stable.outline)
