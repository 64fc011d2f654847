from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="StrategyOut")



@_attrs_define
class StrategyOut:
    """ 
        Attributes:
            budget_ms (float):
            budget_work (float):
            depth (int):
            grid_size (int):
            max_paths (int):
            motion_weight (float):
            name (str):
            forecast (int | Unset):  Default: 1.
            seed (int | None | Unset):
            simulations (int | Unset):  Default: 1000.
     """

    budget_ms: float
    budget_work: float
    depth: int
    grid_size: int
    max_paths: int
    motion_weight: float
    name: str
    forecast: int | Unset = 1
    seed: int | None | Unset = UNSET
    simulations: int | Unset = 1000
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        budget_ms = self.budget_ms

        budget_work = self.budget_work

        depth = self.depth

        grid_size = self.grid_size

        max_paths = self.max_paths

        motion_weight = self.motion_weight

        name = self.name

        forecast = self.forecast

        seed: int | None | Unset
        if isinstance(self.seed, Unset):
            seed = UNSET
        else:
            seed = self.seed

        simulations = self.simulations


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "budget_ms": budget_ms,
            "budget_work": budget_work,
            "depth": depth,
            "grid_size": grid_size,
            "max_paths": max_paths,
            "motion_weight": motion_weight,
            "name": name,
        })
        if forecast is not UNSET:
            field_dict["forecast"] = forecast
        if seed is not UNSET:
            field_dict["seed"] = seed
        if simulations is not UNSET:
            field_dict["simulations"] = simulations

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        budget_ms = d.pop("budget_ms")

        budget_work = d.pop("budget_work")

        depth = d.pop("depth")

        grid_size = d.pop("grid_size")

        max_paths = d.pop("max_paths")

        motion_weight = d.pop("motion_weight")

        name = d.pop("name")

        forecast = d.pop("forecast", UNSET)

        def _parse_seed(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        seed = _parse_seed(d.pop("seed", UNSET))


        simulations = d.pop("simulations", UNSET)

        strategy_out = cls(
            budget_ms=budget_ms,
            budget_work=budget_work,
            depth=depth,
            grid_size=grid_size,
            max_paths=max_paths,
            motion_weight=motion_weight,
            name=name,
            forecast=forecast,
            seed=seed,
            simulations=simulations,
        )


        strategy_out.additional_properties = d
        return strategy_out

    @property
    def additional_keys(self) -> list[str]:
        return list(self.additional_properties.keys())

    def __getitem__(self, key: str) -> Any:
        return self.additional_properties[key]

    def __setitem__(self, key: str, value: Any) -> None:
        self.additional_properties[key] = value

    def __delitem__(self, key: str) -> None:
        del self.additional_properties[key]

    def __contains__(self, key: str) -> bool:
        return key in self.additional_properties
