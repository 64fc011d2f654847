"""The greedy criteria of published touch planners, scored on the same survivor table as
``lookahead`` so that only the decision differs (DESIGN §4.12).

A truth in class k on path P leaves the classes S_P(k) (our outcome model, the sensor's
bounded error included), with class weights w summing to 1:

- EC2, equivalence-class edge cutting (Golovin, Krause & Ray, NIPS 2010; Javdani et
  al.'s hyperedge cutting for touch, ICRA 2013): an edge joins every two hypotheses of
  different classes, weighted w(h) w(g); a touch cuts the edges with an end it rules
  out. The greedy rule takes the path with the largest expected weight cut.
- Information gain (Hebert et al., ICRA 2013): the largest expected reduction of the
  entropy of the class distribution.

Both rank every path at once, in one pass over the survivor bitsets.

>>> import numpy as np
>>> from planner.planning.bitsets import SurvivorTable
>>> eye = np.eye(2, dtype=bool)
>>> table = SurvivorTable.from_matrix(np.stack([eye, ~eye | eye]), np.array([0.5, 0.5]))
>>> edge_cut(table).tolist(), information_gain(table).round(4).tolist()
([0.25, 0.0], [0.6931, 0.0])
"""

from __future__ import annotations

import numpy as np

from planner.planning.bitsets import SurvivorTable, weighted_count

__all__ = ["edge_cut", "entropy", "information_gain"]


def _edges_within(w_sum: np.ndarray, w_sq: np.ndarray) -> np.ndarray:
    # weight of the edges inside a set: sum_{j < l in S} w_j w_l = (w(S)^2 - sum_S w_j^2) / 2
    return np.maximum(w_sum * w_sum - w_sq, 0.0) / 2.0


def edge_cut(table: SurvivorTable) -> np.ndarray:
    """(C,) expected weight of the edges each path cuts: every pair of classes is an
    edge of weight w_j w_l; after truth k only the edges inside S_P(k) are left.

    E_cut(P) = E(all) - sum_k w_k E(S_P(k)), E(S) the edge weight inside S.
    """
    w = table.weight
    inside = _edges_within(weighted_count(table.bits, w), weighted_count(table.bits, w * w))
    total = _edges_within(np.asarray(w.sum()), np.asarray((w * w).sum()))
    return np.clip(total - inside @ w, 0.0, None)


def entropy(weight: np.ndarray) -> float:
    """Shannon entropy (nats) of the distribution proportional to `weight`."""
    w = np.asarray(weight, dtype=float)
    p = w[w > 0] / w.sum()
    return float(-(p * np.log(p)).sum())


def information_gain(table: SurvivorTable, weight: np.ndarray | None = None) -> np.ndarray:
    """(C,) expected entropy reduction (nats) of the class distribution by each path.

    IG(P) = H(w) - sum_k w_k H(w | S_P(k)), with
    H(w | S) = log w(S) - sum_{j in S} w_j log w_j / w(S); `weight` replaces the
    table's class weights (zero outside a state).
    """
    w = table.weight if weight is None else np.asarray(weight, dtype=float)
    w = w / w.sum() if w.sum() > 0 else w
    w_log_w = np.where(w > 0, w * np.log(np.where(w > 0, w, 1.0)), 0.0)
    mass = weighted_count(table.bits, w)
    left = np.log(np.maximum(mass, 1e-300)) - weighted_count(table.bits, w_log_w) / np.maximum(
        mass, 1e-300
    )
    return np.clip(entropy(w) - np.maximum(left, 0.0) @ w, 0.0, None)
