from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.plan_out_status import PlanOutStatus
from ..models.plan_out_stopped_by_type_0 import PlanOutStoppedByType0
from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.planned_path_out import PlannedPathOut





T = TypeVar("T", bound="PlanOut")



@_attrs_define
class PlanOut:
    """ 
        Attributes:
            elapsed_ms (float):
            paths (list[PlannedPathOut]):
            status (PlanOutStatus):
            strategy (str):
            truncated (bool):
            version (int): session version the plan was made for
            candidates (int | Unset):  Default: 0.
            classes (int | Unset):  Default: 0.
            note (None | str | Unset):
            stopped_by (None | PlanOutStoppedByType0 | Unset): what ended the plan early: its work budget (deterministic) or
                the wall-clock cap budget_ms; null: it finished
            work (float | Unset): units of work the plan spent Default: 0.0.
     """

    elapsed_ms: float
    paths: list[PlannedPathOut]
    status: PlanOutStatus
    strategy: str
    truncated: bool
    version: int
    candidates: int | Unset = 0
    classes: int | Unset = 0
    note: None | str | Unset = UNSET
    stopped_by: None | PlanOutStoppedByType0 | Unset = UNSET
    work: float | Unset = 0.0
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.planned_path_out import PlannedPathOut # noqa: PLC0415
        elapsed_ms = self.elapsed_ms

        paths = []
        for paths_item_data in self.paths:
            paths_item = paths_item_data.to_dict()
            paths.append(paths_item)



        status = self.status.value

        strategy = self.strategy

        truncated = self.truncated

        version = self.version

        candidates = self.candidates

        classes = self.classes

        note: None | str | Unset
        if isinstance(self.note, Unset):
            note = UNSET
        else:
            note = self.note

        stopped_by: None | str | Unset
        if isinstance(self.stopped_by, Unset):
            stopped_by = UNSET
        elif isinstance(self.stopped_by, PlanOutStoppedByType0):
            stopped_by = self.stopped_by.value
        else:
            stopped_by = self.stopped_by

        work = self.work


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "elapsed_ms": elapsed_ms,
            "paths": paths,
            "status": status,
            "strategy": strategy,
            "truncated": truncated,
            "version": version,
        })
        if candidates is not UNSET:
            field_dict["candidates"] = candidates
        if classes is not UNSET:
            field_dict["classes"] = classes
        if note is not UNSET:
            field_dict["note"] = note
        if stopped_by is not UNSET:
            field_dict["stopped_by"] = stopped_by
        if work is not UNSET:
            field_dict["work"] = work

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.planned_path_out import PlannedPathOut # noqa: PLC0415
        d = dict(src_dict)
        elapsed_ms = d.pop("elapsed_ms")

        paths = []
        _paths = d.pop("paths")
        for paths_item_data in (_paths):
            paths_item = PlannedPathOut.from_dict(paths_item_data)



            paths.append(paths_item)


        status = PlanOutStatus(d.pop("status"))




        strategy = d.pop("strategy")

        truncated = d.pop("truncated")

        version = d.pop("version")

        candidates = d.pop("candidates", UNSET)

        classes = d.pop("classes", UNSET)

        def _parse_note(data: object) -> None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(None | str | Unset, data)

        note = _parse_note(d.pop("note", UNSET))


        def _parse_stopped_by(data: object) -> None | PlanOutStoppedByType0 | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                stopped_by_type_0 = PlanOutStoppedByType0(data)



                return stopped_by_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | PlanOutStoppedByType0 | Unset, data)

        stopped_by = _parse_stopped_by(d.pop("stopped_by", UNSET))


        work = d.pop("work", UNSET)

        plan_out = cls(
            elapsed_ms=elapsed_ms,
            paths=paths,
            status=status,
            strategy=strategy,
            truncated=truncated,
            version=version,
            candidates=candidates,
            classes=classes,
            note=note,
            stopped_by=stopped_by,
            work=work,
        )


        plan_out.additional_properties = d
        return plan_out

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
