from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.report_out_status import ReportOutStatus
from typing import cast

if TYPE_CHECKING:
  from ..models.accuracy_out import AccuracyOut
  from ..models.report_result_out import ReportResultOut
  from ..models.report_touch_out import ReportTouchOut
  from ..models.sensor_out import SensorOut





T = TypeVar("T", bound="ReportOut")



@_attrs_define
class ReportOut:
    """ A session's report: each touch with its residuals, the answer with its bound,
    probability and status (report.csv has the same in rows).

        Attributes:
            accuracy (AccuracyOut): What `localized` requires: the pose bounds at most these.
            id (str):
            objects (list[str]):
            result (None | ReportResultOut): null without a hypothesis
            sensor (SensorOut):
            status (ReportOutStatus):
            touches (list[ReportTouchOut]):
            version (int):
     """

    accuracy: AccuracyOut
    id: str
    objects: list[str]
    result: None | ReportResultOut
    sensor: SensorOut
    status: ReportOutStatus
    touches: list[ReportTouchOut]
    version: int
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.accuracy_out import AccuracyOut # noqa: PLC0415
        from ..models.report_result_out import ReportResultOut # noqa: PLC0415
        from ..models.report_touch_out import ReportTouchOut # noqa: PLC0415
        from ..models.sensor_out import SensorOut # noqa: PLC0415
        accuracy = self.accuracy.to_dict()

        id = self.id

        objects = self.objects



        result: dict[str, Any] | None
        if isinstance(self.result, ReportResultOut):
            result = self.result.to_dict()
        else:
            result = self.result

        sensor = self.sensor.to_dict()

        status = self.status.value

        touches = []
        for touches_item_data in self.touches:
            touches_item = touches_item_data.to_dict()
            touches.append(touches_item)



        version = self.version


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "accuracy": accuracy,
            "id": id,
            "objects": objects,
            "result": result,
            "sensor": sensor,
            "status": status,
            "touches": touches,
            "version": version,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.accuracy_out import AccuracyOut # noqa: PLC0415
        from ..models.report_result_out import ReportResultOut # noqa: PLC0415
        from ..models.report_touch_out import ReportTouchOut # noqa: PLC0415
        from ..models.sensor_out import SensorOut # noqa: PLC0415
        d = dict(src_dict)
        accuracy = AccuracyOut.from_dict(d.pop("accuracy"))




        id = d.pop("id")

        objects = cast(list[str], d.pop("objects"))


        def _parse_result(data: object) -> None | ReportResultOut:
            if data is None:
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                result_type_0 = ReportResultOut.from_dict(data)



                return result_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | ReportResultOut, data)

        result = _parse_result(d.pop("result"))


        sensor = SensorOut.from_dict(d.pop("sensor"))




        status = ReportOutStatus(d.pop("status"))




        touches = []
        _touches = d.pop("touches")
        for touches_item_data in (_touches):
            touches_item = ReportTouchOut.from_dict(touches_item_data)



            touches.append(touches_item)


        version = d.pop("version")

        report_out = cls(
            accuracy=accuracy,
            id=id,
            objects=objects,
            result=result,
            sensor=sensor,
            status=status,
            touches=touches,
            version=version,
        )


        report_out.additional_properties = d
        return report_out

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
