"""The planning strategies: which path to take, on the class survivor table alone (DESIGN §4.12).

Strategies: ``random`` (thesis Exp. I), ``thesis`` (opening probes, then the
grid windows of :mod:`planner.image.windows` in CHOOSE order), ``pdm`` (max P(DM)),
``pruning`` (max expected pruning), ``lookahead`` (min expected remaining
touches, `depth` deep, a set still open at the horizon valued by its entropy against
the best gain per touch), ``optimal`` (exact DP over survivor sets for at most
`optimal_max_classes` classes, else lookahead, saying so), and the published peers on
the same table: ``ec2`` (max expected edge weight cut), ``infogain`` (max expected
entropy reduction of the classes) and ``pomcp`` (Monte-Carlo tree search,
`simulations` per plan). None of them returns an uninformative path while an
informative candidate exists.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.planning.analysis import as_generator
from planner.planning.bitsets import SurvivorTable
from planner.planning.budget import Budget
from planner.planning.config import StrategyConfig
from planner.planning.peers import edge_cut, information_gain
from planner.planning.pomcp import search as pomcp_search
from planner.planning.scoring import (
    UNINFORMATIVE,
    InformationScores,
    combined_objective,
    information_scores,
)
from planner.planning.search import expected_remaining

__all__ = ["Ranking", "rank_candidates"]


@dataclass(frozen=True, eq=False)
class Ranking:
    """A strategy's answer: informative candidate indices, best first (`order`);
    `expected_remaining` (C,) with `exact` (C,) bool (a lower bound where not
    exact; inf where never scored); `truncated` when the budget stopped the
    search; `note` when the strategy deviated or found nothing."""

    order: np.ndarray
    expected_remaining: np.ndarray
    exact: np.ndarray
    truncated: bool = False
    note: str | None = None


def rank_candidates(
    table: SurvivorTable,
    config: StrategyConfig | None = None,
    *,
    info: InformationScores | None = None,
    motion: np.ndarray | None = None,
    source: np.ndarray | None = None,
    tier: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    budget: Budget | None = None,
) -> Ranking:
    """Apply the configured strategy to an outcome matrix (C paths x K classes).

    `motion` (C,) defaults to zero; `source` (C,) names each candidate's origin
    (``random`` draws and thesis ``probe``/``window`` rows are what those
    strategies pick from) and `tier` (C,) their rank (the windows' level, default
    0); `budget` bounds the search. Expected remaining
    touches are computed for the first `max_paths` of the order when the
    strategy did not compute them itself (``random``, ``thesis``, ``pdm``,
    ``pruning``): searched `depth` touches deep when there are at most
    `optimal_max_classes` classes, else one touch deep, the bound
    ``(1 + w(open)) / (1 - w(stay))`` that lower-bounds the deeper value.
    """
    config = config or StrategyConfig()
    n = table.n_paths
    ctx = _Context(
        config,
        table,
        info if info is not None else information_scores(table),
        np.zeros(n) if motion is None else np.asarray(motion, dtype=float),
        np.full(n, "", dtype="<U12") if source is None else np.asarray(source),
        np.zeros(n, dtype=int) if tier is None else np.asarray(tier, dtype=int),
        as_generator(rng),
        budget or Budget(config.budget_work, config.budget_ms),
    )
    ranking = _STRATEGIES[config.name](ctx)
    if ranking.note is None and not len(ranking.order):
        ranking = Ranking(
            ranking.order,
            ranking.expected_remaining,
            ranking.exact,
            False,
            f"no informative path among {n} candidates",
        )
    top = ranking.order[: config.max_paths]
    if len(top) and not ranking.exact[top].all():
        # strategies that do not search: `depth` deep on small sets, else one touch deep
        depth = config.depth if table.n_classes <= config.optimal_max_classes else 1
        result = expected_remaining(table, depth, paths=top, budget=ctx.budget, whole=True)
        value = np.where(ranking.exact, ranking.expected_remaining, result.value)
        exact = ranking.exact | result.exact
        return Ranking(
            ranking.order, value, exact, ranking.truncated or result.truncated, ranking.note
        )
    return ranking


@dataclass(frozen=True, eq=False)
class _Context:
    """What every strategy reads: the settings, the class survivor table and its
    scores, and per candidate (C,) the motion cost, source and tier; the random
    generator and the budget."""

    config: StrategyConfig
    table: SurvivorTable
    info: InformationScores
    motion: np.ndarray
    source: np.ndarray
    tier: np.ndarray
    rng: np.random.Generator
    budget: Budget


def _informative(ctx: _Context, rows: np.ndarray | None = None) -> np.ndarray:
    rows = np.arange(ctx.table.n_paths) if rows is None else rows
    return rows[ctx.info.family[rows] != UNINFORMATIVE]


def _order(keys: tuple[np.ndarray, ...]) -> np.ndarray:
    """``np.lexsort`` on the keys rounded to 1e-9: values equal but for floating-point
    noise (the same session derived along another path sums in another order) tie,
    and the next key, then the candidate order, decides, as it would for exact ties."""
    return np.lexsort(tuple(np.round(k, 9) if k.dtype.kind == "f" else k for k in keys))


def _unscored(ctx: _Context, order: np.ndarray, note: str | None = None) -> Ranking:
    n = ctx.table.n_paths
    return Ranking(order, np.full(n, np.inf), np.zeros(n, dtype=bool), False, note)


def _pdm(ctx: _Context) -> Ranking:
    ok, info = _informative(ctx), ctx.info
    # cost = (1 - P(DM)) + motion_weight * motion_cost
    cost = combined_objective(1.0 - info.p_distinguishing, ctx.motion, ctx.config.motion_weight)
    keys = (ctx.motion[ok], -info.expected_pruning[ok], -info.p_informative[ok], cost[ok])
    return _unscored(ctx, ok[_order(keys)])


def _pruning(ctx: _Context) -> Ranking:
    ok, info = _informative(ctx), ctx.info
    # cost = -expected pruning + motion_weight * motion_cost
    cost = combined_objective(-info.expected_pruning, ctx.motion, ctx.config.motion_weight)
    return _unscored(ctx, ok[_order((ctx.motion[ok], -info.p_distinguishing[ok], cost[ok]))])


def _lookahead(ctx: _Context, depth: int | None = None, note: str | None = None) -> Ranking:
    ok = _informative(ctx)
    result = expected_remaining(
        ctx.table,
        depth,
        paths=ok,
        top_k=ctx.config.max_paths,
        extra_cost=ctx.config.motion_weight * ctx.motion,
        budget=ctx.budget,
        leaf="entropy",
        whole=True,  # a search the budget stops is ranked by information gain instead
    )
    # cost = E_P + motion_weight * motion_cost; exact values rank before bounds; equal
    # costs go to the larger P(DM) (finish now), then the larger information gain (a
    # hedge on what lies past the horizon; with wide error disks P(DM) is mostly 0)
    cost = combined_objective(result.value, ctx.motion, ctx.config.motion_weight)
    keys = (
        ctx.motion[ok],
        -result.gain[ok],
        -ctx.info.p_distinguishing[ok],
        np.round(cost[ok], 9),
        ~result.exact[ok],
    )
    if result.truncated:
        # a search the budget stopped has valued some paths and only bounded the
        # rest, and would prefer whichever it valued first: the information gain
        # ranks every path alike (measured: README, "Beside the published strategies")
        note = "; ".join(
            filter(None, [note, "search stopped at the budget: ranked by information gain"])
        )
        order = _greedy_order(ctx, ok, information_gain(ctx.table))
        return Ranking(order, result.value, result.exact, result.truncated, note)
    return Ranking(ok[_order(keys)], result.value, result.exact, result.truncated, note)


def _depth_lookahead(ctx: _Context) -> Ranking:
    return _lookahead(ctx, ctx.config.depth)


def _optimal(ctx: _Context) -> Ranking:
    k, limit = ctx.table.n_classes, ctx.config.optimal_max_classes
    if k <= limit:
        return _lookahead(ctx, None)  # no depth limit: the exact DP over survivor sets
    note = f"optimal played lookahead (depth {ctx.config.depth}): {k} classes > {limit}"
    return _lookahead(ctx, ctx.config.depth, note)


def _greedy(ctx: _Context, score: np.ndarray) -> Ranking:
    return _unscored(ctx, _greedy_order(ctx, _informative(ctx), score))


def _greedy_order(ctx: _Context, ok: np.ndarray, score: np.ndarray) -> np.ndarray:
    """The paths `ok` by `score` (largest first), less motion-weighted; ties to the
    larger P(DM), then the shorter motion."""
    cost = combined_objective(-score, ctx.motion, ctx.config.motion_weight)
    return ok[_order((ctx.motion[ok], -ctx.info.p_distinguishing[ok], cost[ok]))]


def _ec2(ctx: _Context) -> Ranking:
    return _greedy(ctx, edge_cut(ctx.table))


def _infogain(ctx: _Context) -> Ranking:
    return _greedy(ctx, information_gain(ctx.table))


def _pomcp(ctx: _Context) -> Ranking:
    result = pomcp_search(ctx.table, ctx.rng, simulations=ctx.config.simulations, budget=ctx.budget)
    ok = _informative(ctx)
    # the tree's choice first, then the paths it tried by visits and value, then the rest
    first = (ok != result.best).astype(int)
    cost = combined_objective(result.value[ok], ctx.motion[ok], ctx.config.motion_weight)
    keys = (ctx.motion[ok], -ctx.info.p_distinguishing[ok], cost, -result.visits[ok], first)
    note = "simulations stopped at the budget" if result.truncated else None
    ranking = _unscored(ctx, ok[_order(keys)], note)
    return Ranking(ranking.order, ranking.expected_remaining, ranking.exact, result.truncated, note)


def _random(ctx: _Context) -> Ranking:
    drawn = _informative(ctx, np.flatnonzero(ctx.source == "random"))
    if len(drawn):
        return _unscored(ctx, drawn)
    ok = _informative(ctx)
    if not len(ok):
        return _unscored(ctx, ok)
    pick = ok[ctx.rng.integers(len(ok))]
    return _unscored(ctx, np.array([pick]), "no informative random draw: a random candidate")


def _thesis(ctx: _Context) -> Ranking:
    for kind in ("probe", "random"):
        rows = _informative(ctx, np.flatnonzero(ctx.source == kind))
        if len(rows):
            return _unscored(ctx, rows)
    # windows come in CHOOSE order (lowest admitted strength, then nearest origin)
    rows = _informative(ctx, np.flatnonzero(ctx.source == "window"))
    if len(rows) and ctx.config.thesis_choice == "random":
        # §4.3.6: "at random from among the most highly diagnostic family of paths"
        family = ctx.tier[rows] == ctx.tier[rows].min()
        rows = np.concatenate([ctx.rng.permutation(rows[family]), rows[~family]])
    if len(rows):
        return _unscored(ctx, rows)
    fallback = _pdm(ctx)
    note = (
        "no informative thesis window: best P(DM) among all candidates"
        if len(fallback.order)
        else None
    )
    return _unscored(ctx, fallback.order, note)


_STRATEGIES: dict[str, Callable[[_Context], Ranking]] = {
    "random": _random,
    "thesis": _thesis,
    "pdm": _pdm,
    "pruning": _pruning,
    "lookahead": _depth_lookahead,
    "optimal": _optimal,
    "ec2": _ec2,
    "infogain": _infogain,
    "pomcp": _pomcp,
}
