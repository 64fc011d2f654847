from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.strategy_in_name import StrategyInName
from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="StrategyIn")



@_attrs_define
class StrategyIn:
    """ 
        Attributes:
            budget_ms (float | Unset): a wall-clock cap on the plan, a safety net: when it bites the plan says stopped_by
                'time' and may differ from run to run Default: 1500.0.
            budget_work (float | Unset): the work a plan may do, in units of about a microsecond on the reference machine
                (outcome cells, search nodes, recognition updates): the plan is the same on any machine under any load Default:
                400000.0.
            depth (int | Unset):  Default: 2.
            forecast (int | Unset): how many of the ranked paths get p_forecast (the recognition's own forecast, one
                observation update per class each); 0: none, faster plans Default: 1.
            grid_size (int | Unset):  Default: 70.
            max_paths (int | Unset):  Default: 5.
            motion_weight (float | Unset):  Default: 0.0.
            name (StrategyInName | Unset):  Default: StrategyInName.LOOKAHEAD.
            seed (int | None | Unset): seeds the planner's random choices: the plan at session version v draws from numpy's
                default_rng([seed, v]); null: a seed drawn from the session id
            simulations (int | Unset): the pomcp strategy's Monte-Carlo simulations per plan (the work budget may stop it
                sooner); other strategies ignore it Default: 1000.
     """

    budget_ms: float | Unset = 1500.0
    budget_work: float | Unset = 400000.0
    depth: int | Unset = 2
    forecast: int | Unset = 1
    grid_size: int | Unset = 70
    max_paths: int | Unset = 5
    motion_weight: float | Unset = 0.0
    name: StrategyInName | Unset = StrategyInName.LOOKAHEAD
    seed: int | None | Unset = UNSET
    simulations: int | Unset = 1000





    def to_dict(self) -> dict[str, Any]:
        budget_ms = self.budget_ms

        budget_work = self.budget_work

        depth = self.depth

        forecast = self.forecast

        grid_size = self.grid_size

        max_paths = self.max_paths

        motion_weight = self.motion_weight

        name: str | Unset = UNSET
        if not isinstance(self.name, Unset):
            name = self.name.value


        seed: int | None | Unset
        if isinstance(self.seed, Unset):
            seed = UNSET
        else:
            seed = self.seed

        simulations = self.simulations


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if budget_ms is not UNSET:
            field_dict["budget_ms"] = budget_ms
        if budget_work is not UNSET:
            field_dict["budget_work"] = budget_work
        if depth is not UNSET:
            field_dict["depth"] = depth
        if forecast is not UNSET:
            field_dict["forecast"] = forecast
        if grid_size is not UNSET:
            field_dict["grid_size"] = grid_size
        if max_paths is not UNSET:
            field_dict["max_paths"] = max_paths
        if motion_weight is not UNSET:
            field_dict["motion_weight"] = motion_weight
        if name is not UNSET:
            field_dict["name"] = name
        if seed is not UNSET:
            field_dict["seed"] = seed
        if simulations is not UNSET:
            field_dict["simulations"] = simulations

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        budget_ms = d.pop("budget_ms", UNSET)

        budget_work = d.pop("budget_work", UNSET)

        depth = d.pop("depth", UNSET)

        forecast = d.pop("forecast", UNSET)

        grid_size = d.pop("grid_size", UNSET)

        max_paths = d.pop("max_paths", UNSET)

        motion_weight = d.pop("motion_weight", UNSET)

        _name = d.pop("name", UNSET)
        name: StrategyInName | Unset
        if isinstance(_name,  Unset):
            name = UNSET
        else:
            name = StrategyInName(_name)




        def _parse_seed(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        seed = _parse_seed(d.pop("seed", UNSET))


        simulations = d.pop("simulations", UNSET)

        strategy_in = cls(
            budget_ms=budget_ms,
            budget_work=budget_work,
            depth=depth,
            forecast=forecast,
            grid_size=grid_size,
            max_paths=max_paths,
            motion_weight=motion_weight,
            name=name,
            seed=seed,
            simulations=simulations,
        )

        return strategy_in

