"""Confusability of hypotheses on each sensing path, and the class survivor sets (DESIGN §4.11).

Two hypotheses are confusable on a path when any of their possible outcomes
(:class:`~planner.planning.outcomes.Outcomes`) match within the tolerances of
:mod:`planner.planning.matching`. Class B survives truth class A on a path when
some member of B is confusable with some member of A; the survivor sets over
classes are bitsets (:class:`~planner.planning.bitsets.SurvivorTable`).
"""

from __future__ import annotations

import numpy as np

from planner.planning.bitsets import SurvivorTable, transpose_bits, unpack_bits
from planner.planning.matching import match_rows, miss_bits
from planner.planning.outcomes import OutcomeConfig, Outcomes
from planner.planning.posed_set import PosedSet
from planner.types import SensorBounds

__all__ = ["class_bits", "class_survivors", "confusability", "survivor_table"]


def confusability(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> np.ndarray:
    """(C, H, H) bool: can hypotheses h and g give the same measurement on path c?

    Two outcomes match when both miss, or both hit with points within
    ``2 eps_d + (eps_t(h) + eps_t(g)) / 2`` (plus grazing slack) and normals
    within ``2 phi + dtheta(h) + dtheta(g)`` (plus the vertex cones). Two
    hypotheses are confusable when any of their possible outcomes match;
    members of one equivalence class are always confusable.
    """
    n_hyp = len(posed)
    chunk = (config or OutcomeConfig()).chunk_elements
    rows = match_rows(posed, outcomes, sensor, chunk)
    rows |= transpose_bits(rows, n_hyp) | miss_bits(outcomes, np.arange(n_hyp), n_hyp)
    return unpack_bits(rows, n_hyp) | (posed.cls[:, None] == posed.cls[None, :])


def class_survivors(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> SurvivorTable:
    """The class survivor table straight from the outcomes, as
    ``survivor_table(posed, confusability(...))`` but never forming the (C, H, H)
    matrix: class B survives truth class A on a path when some member of B is
    confusable with some member of A."""
    return SurvivorTable.from_bits(class_bits(posed, outcomes, sensor, config), posed.class_weight)


def class_bits(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> np.ndarray:
    """(C, K, W) class confusability as bitsets (see :func:`class_survivors`)."""
    n_hyp, n_cls = len(posed), posed.n_classes
    # hypotheses in class order: rows and bits of one class side by side
    order = np.argsort(posed.cls, kind="stable")
    rows = match_rows(posed, outcomes, sensor, (config or OutcomeConfig()).chunk_elements, order)
    misses = miss_bits(outcomes, posed.cls, n_cls)
    if n_cls == n_hyp:  # one hypothesis per class: R is the class relation
        return rows | transpose_bits(rows, n_hyp) | misses
    by_class = posed.cls[order]
    first = np.flatnonzero(np.r_[True, by_class[1:] != by_class[:-1]])
    # X[c, A, g] = OR_{h in A} R[c, h, g]; then Y[c, B, A] = OR_{g in B} X[c, A, g]
    y = transpose_bits(np.bitwise_or.reduceat(rows, first, axis=1), n_hyp)
    y = np.bitwise_or.reduceat(y, first, axis=1)
    # confusability is symmetric: conf = Y | Y^T
    return y | transpose_bits(y, n_cls) | misses


def survivor_table(posed: PosedSet, confusable: np.ndarray) -> SurvivorTable:
    """Class-level survivor sets from the (C, H, H) hypothesis confusability.

    Class B survives truth class A on a path when some member of B is
    confusable with some member of A (a class is never split).
    """
    order = np.argsort(posed.cls, kind="stable")
    by_class = posed.cls[order]
    first = np.flatnonzero(np.r_[True, by_class[1:] != by_class[:-1]])
    conf = np.asarray(confusable, dtype=bool)
    if len(first) < len(order) or np.any(order != np.arange(len(order))):
        # conf_cls[c, A, B] = OR over h in A, g in B of conf[c, h, g]
        conf = conf[:, order][:, :, order]
        conf = np.logical_or.reduceat(conf, first, axis=1)
        conf = np.logical_or.reduceat(conf, first, axis=2)
    return SurvivorTable.from_matrix(conf, posed.class_weight)
