"""Online POMDP planning by Monte-Carlo tree search (POMCP, Silver & Veness, NIPS 2010),
with pomdp-py's planner, on the same survivor table as ``lookahead`` (DESIGN §4.12).

The POMDP:

- state: the true class k and the classes S still alive (S is in the state so that the
  reward can stop once S is settled; the robot observes S, so the belief over it is
  exact);
- action: a candidate path c, among those that can split S; once S is settled, only
  "stop", which changes nothing;
- transition: S' = S & S_c(k), k unchanged; observation: S' (the outcome cell, named by
  the classes it leaves);
- reward: -1 per touch while S can be split, 0 once it cannot; no discount, so a
  node's value is minus the expected number of touches.

The belief at the root is the class weights. Rollouts take a path at random among those
that split the set. Everything random draws from the caller's generator, so the choice
is a function of the seed; the budget is a number of simulations, counted as work too.

>>> import numpy as np
>>> from planner.planning.bitsets import SurvivorTable
>>> eye = np.eye(2, dtype=bool)
>>> table = SurvivorTable.from_matrix(np.stack([~eye | eye, eye]), np.array([0.5, 0.5]))
>>> search(table, np.random.default_rng(0), simulations=50).best
1
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pomdp_py

from planner.planning.bitsets import SurvivorTable, to_int
from planner.planning.budget import Budget
from planner.planning.search_nodes import SearchSpace

__all__ = ["PomcpResult", "search"]

#: Simulations run between two looks at the work budget.
_CHUNK = 50
_WORD = (1 << 64) - 1
#: The action offered once the alive set is settled.
STOP = -1


@dataclass(frozen=True, eq=False)
class PomcpResult:
    """The root's statistics per candidate (C,): `value` (estimated expected touches,
    this one included; inf where never tried) and `visits`; `best` the path the tree
    prefers (-1: none can split the set); `simulations` run; `truncated` when the work
    budget stopped them early."""

    value: np.ndarray
    visits: np.ndarray
    best: int
    simulations: int
    truncated: bool


class _State(pomdp_py.State):
    __slots__ = ("alive", "truth")

    def __init__(self, truth: int, alive: int) -> None:
        self.truth, self.alive = truth, alive

    def __hash__(self) -> int:
        return hash((self.truth, self.alive))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _State) and (self.truth, self.alive) == (
            other.truth,
            other.alive,
        )


class _Path(pomdp_py.Action):
    __slots__ = ("index",)

    def __init__(self, index: int) -> None:
        self.index = index

    def __hash__(self) -> int:
        return self.index

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Path) and self.index == other.index


class _Cell(pomdp_py.Observation):
    __slots__ = ("alive",)

    def __init__(self, alive: int) -> None:
        self.alive = alive

    def __hash__(self) -> int:
        return hash(self.alive)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Cell) and self.alive == other.alive


class _Model:
    """The survivor table as Python ints (bit j = class j), with per-set memos of what
    the search asks again and again: is the set settled, which paths split it."""

    def __init__(self, table: SurvivorTable, rng: np.random.Generator) -> None:
        self.space = SearchSpace(table)
        self.table = table
        self.rng = rng
        words = table.bits.shape[-1]
        # survivors[c][k] = S_c(k) as an int
        parts = [table.bits[..., w].astype(object) << (64 * w) for w in range(words)]
        self.survivors = np.bitwise_or.reduce(np.stack(parts), axis=0).tolist()
        self.everything = to_int(np.bitwise_or.reduce(table.bits, axis=(0, 1)))
        self._splitting: dict[int, list[int]] = {}
        self.steps = 0

    def splitting(self, alive: int) -> list[int]:
        """Paths that split `alive` for some truth in it (none when it is settled)."""
        known = self._splitting.get(alive)
        if known is None:
            n = self.table.n_classes
            idx = np.array([j for j in range(n) if alive >> j & 1], dtype=np.int64)
            words = range(self.table.bits.shape[-1])
            state = np.array([(alive >> (64 * w)) & _WORD for w in words], dtype=np.uint64)
            if self.space.settled(state, idx):
                known = []
            else:
                sets = self.table.bits[:, idx] & state
                known = np.flatnonzero(np.any(sets != state, axis=(1, 2))).tolist()
            self._splitting[alive] = known
        return known


class _Transition(pomdp_py.TransitionModel):
    def __init__(self, model: _Model) -> None:
        self.model = model

    def sample(self, state: _State, action: _Path) -> _State:
        self.model.steps += 1
        if action.index == STOP:
            return state
        # S' = S & S_c(k)
        return _State(state.truth, state.alive & self.model.survivors[action.index][state.truth])


class _Observe(pomdp_py.ObservationModel):
    def sample(self, next_state: _State, action: _Path) -> _Cell:
        return _Cell(next_state.alive)


class _Reward(pomdp_py.RewardModel):
    def __init__(self, model: _Model) -> None:
        self.model = model

    def sample(self, state: _State, action: _Path, next_state: _State) -> float:
        # -1 per touch; "stop" is offered only once the set cannot be split
        return 0.0 if action.index == STOP else -1.0


class _Policy(pomdp_py.RolloutPolicy):
    def __init__(self, model: _Model) -> None:
        self.model = model
        self._actions: dict[int, list[_Path]] = {}

    def get_all_actions(self, state: _State | None = None, history: tuple = ()) -> list[_Path]:
        alive = self.model.everything if state is None else state.alive
        known = self._actions.get(alive)
        if known is None:
            known = [_Path(c) for c in self.model.splitting(alive)] or [_Path(STOP)]
            self._actions[alive] = known
        return known

    def rollout(self, state: _State, history: tuple = ()) -> _Path:
        actions = self.get_all_actions(state)
        if len(actions) == 1:
            return actions[0]
        return actions[int(self.model.rng.integers(len(actions)))]


class _Belief(pomdp_py.Particles):
    """The class weights as a belief: each particle one class, drawn by its weight."""

    def __init__(self, states: list[_State], weight: np.ndarray, rng: np.random.Generator):
        super().__init__(states)
        self.states, self.weight, self.rng = states, weight, rng

    def random(self) -> _State:
        return self.states[int(self.rng.choice(len(self.states), p=self.weight))]

    def __deepcopy__(self, memo: dict) -> _Belief:
        return self  # read only: the root's copy may share it


def search(
    table: SurvivorTable,
    rng: np.random.Generator,
    *,
    simulations: int = 1000,
    exploration: float = 1.0,
    max_depth: int | None = None,
    budget: Budget | None = None,
) -> PomcpResult:
    """Run POMCP from the root (all classes alive) for `simulations` simulations
    (fewer if `budget` runs out; it counts each simulated touch),
    tree and rollouts `max_depth` touches deep (default: classes + 2)."""
    n_paths = table.n_paths
    model = _Model(table, rng)
    root = model.everything
    value = np.full(n_paths, np.inf)
    visits = np.zeros(n_paths, dtype=np.int64)
    if not model.splitting(root):
        return PomcpResult(value, visits, -1, 0, False)
    states = [_State(k, root) for k in range(table.n_classes)]
    policy = _Policy(model)
    agent = pomdp_py.Agent(
        _Belief(states, table.weight, rng), policy, _Transition(model), _Observe(), _Reward(model)
    )
    depth = max_depth if max_depth is not None else table.n_classes + 2
    done, truncated = 0, False
    while done < simulations:
        chunk = min(_CHUNK, simulations - done)
        planner = pomdp_py.POMCP(
            max_depth=depth,
            discount_factor=1.0,
            num_sims=chunk,
            exploration_const=exploration,
            rollout_policy=policy,
        )
        planner.plan(agent)  # the tree lives on the agent: each chunk grows it further
        done += chunk
        if budget is not None:
            budget.spend("simulated_touch", model.steps)
            model.steps = 0
            if budget.exhausted():
                truncated = done < simulations
                break
    for action in agent.tree.children:
        if action.index == STOP:
            continue
        node = agent.tree[action]
        visits[action.index] = node.num_visits
        if node.num_visits > 0:
            value[action.index] = -node.value
    tried = np.flatnonzero(visits > 0)
    # the most visited root path, as UCT recommends; ties to the better value
    best = int(tried[np.lexsort((value[tried], -visits[tried]))[0]]) if len(tried) else -1
    return PomcpResult(value, visits, best, done, truncated)
