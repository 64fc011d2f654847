from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.planned_path_out_scored_by import PlannedPathOutScoredBy
from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="PlannedPathOut")



@_attrs_define
class PlannedPathOut:
    """ 
        Attributes:
            aim (list[float]):
            direction (list[float]):
            expected_pruning (float):
            expected_remaining (float | None): expected touches still needed when taking this path (itself included), as the
                plan's search values it: not calibrated, values above two or three overstate the touches taken (README,
                Calibration)
            family (str): distinguishing, informative, partial, uninformative, or refining (offered only when no path is
                informative: it shrinks the error disks)
            length (float):
            motion_cost (float | None):
            origin (list[float]):
            p_distinguishing (float):
            p_informative (float):
            expected_eps_t (float | None | Unset): refining paths: the probability-weighted error-disk diameter expected
                after the touch (length)
            height (float | None | Unset): the probing height to run the path at (null: the default height); the
                observation's path carries it back
            p_forecast (float | None | Unset): P(DM) as the recognition itself would judge the touch (each class' predicted
                outcome observed); set on the first `strategy.forecast` paths, None elsewhere. p_distinguishing is the outcome
                model's worst-case value: sure where it says 1, lower than what happens elsewhere
            scored_by (PlannedPathOutScoredBy | Unset): which model ranked the path: the worst-case outcome model (its
                p_distinguishing = 1 is a certificate), or, when that model calls nothing informative, the recognition's own
                predictions (p_forecast) Default: PlannedPathOutScoredBy.OUTCOME_MODEL.
            source (None | str | Unset):
     """

    aim: list[float]
    direction: list[float]
    expected_pruning: float
    expected_remaining: float | None
    family: str
    length: float
    motion_cost: float | None
    origin: list[float]
    p_distinguishing: float
    p_informative: float
    expected_eps_t: float | None | Unset = UNSET
    height: float | None | Unset = UNSET
    p_forecast: float | None | Unset = UNSET
    scored_by: PlannedPathOutScoredBy | Unset = PlannedPathOutScoredBy.OUTCOME_MODEL
    source: None | str | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        aim = self.aim



        direction = self.direction



        expected_pruning = self.expected_pruning

        expected_remaining: float | None
        expected_remaining = self.expected_remaining

        family = self.family

        length = self.length

        motion_cost: float | None
        motion_cost = self.motion_cost

        origin = self.origin



        p_distinguishing = self.p_distinguishing

        p_informative = self.p_informative

        expected_eps_t: float | None | Unset
        if isinstance(self.expected_eps_t, Unset):
            expected_eps_t = UNSET
        else:
            expected_eps_t = self.expected_eps_t

        height: float | None | Unset
        if isinstance(self.height, Unset):
            height = UNSET
        else:
            height = self.height

        p_forecast: float | None | Unset
        if isinstance(self.p_forecast, Unset):
            p_forecast = UNSET
        else:
            p_forecast = self.p_forecast

        scored_by: str | Unset = UNSET
        if not isinstance(self.scored_by, Unset):
            scored_by = self.scored_by.value


        source: None | str | Unset
        if isinstance(self.source, Unset):
            source = UNSET
        else:
            source = self.source


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "aim": aim,
            "direction": direction,
            "expected_pruning": expected_pruning,
            "expected_remaining": expected_remaining,
            "family": family,
            "length": length,
            "motion_cost": motion_cost,
            "origin": origin,
            "p_distinguishing": p_distinguishing,
            "p_informative": p_informative,
        })
        if expected_eps_t is not UNSET:
            field_dict["expected_eps_t"] = expected_eps_t
        if height is not UNSET:
            field_dict["height"] = height
        if p_forecast is not UNSET:
            field_dict["p_forecast"] = p_forecast
        if scored_by is not UNSET:
            field_dict["scored_by"] = scored_by
        if source is not UNSET:
            field_dict["source"] = source

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        aim = cast(list[float], d.pop("aim"))


        direction = cast(list[float], d.pop("direction"))


        expected_pruning = d.pop("expected_pruning")

        def _parse_expected_remaining(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        expected_remaining = _parse_expected_remaining(d.pop("expected_remaining"))


        family = d.pop("family")

        length = d.pop("length")

        def _parse_motion_cost(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        motion_cost = _parse_motion_cost(d.pop("motion_cost"))


        origin = cast(list[float], d.pop("origin"))


        p_distinguishing = d.pop("p_distinguishing")

        p_informative = d.pop("p_informative")

        def _parse_expected_eps_t(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        expected_eps_t = _parse_expected_eps_t(d.pop("expected_eps_t", UNSET))


        def _parse_height(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        height = _parse_height(d.pop("height", UNSET))


        def _parse_p_forecast(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        p_forecast = _parse_p_forecast(d.pop("p_forecast", UNSET))


        _scored_by = d.pop("scored_by", UNSET)
        scored_by: PlannedPathOutScoredBy | Unset
        if isinstance(_scored_by,  Unset):
            scored_by = UNSET
        else:
            scored_by = PlannedPathOutScoredBy(_scored_by)




        def _parse_source(data: object) -> None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(None | str | Unset, data)

        source = _parse_source(d.pop("source", UNSET))


        planned_path_out = cls(
            aim=aim,
            direction=direction,
            expected_pruning=expected_pruning,
            expected_remaining=expected_remaining,
            family=family,
            length=length,
            motion_cost=motion_cost,
            origin=origin,
            p_distinguishing=p_distinguishing,
            p_informative=p_informative,
            expected_eps_t=expected_eps_t,
            height=height,
            p_forecast=p_forecast,
            scored_by=scored_by,
            source=source,
        )


        planned_path_out.additional_properties = d
        return planned_path_out

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
