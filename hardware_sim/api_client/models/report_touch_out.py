from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.report_touch_out_kind import ReportTouchOutKind
from typing import cast

if TYPE_CHECKING:
  from ..models.path_out import PathOut
  from ..models.report_contact_out import ReportContactOut





T = TypeVar("T", bound="ReportTouchOut")



@_attrs_define
class ReportTouchOut:
    """ One touch with its residuals against the most probable hypothesis.

        Attributes:
            clearance (float | None): a miss: how far the path passed from the answer's posed outline
            contact (None | ReportContactOut):
            distance (float | None): length from the contact point to that posed face
            face (int | None): the answer's face the contact lies on
            index (int):
            kind (ReportTouchOutKind): a contact on a face of the answer, a contact the answer calls spurious, or a path
                that touched nothing
            normal_angle (float | None): radians from the posed face's outward normal to the measured one, counter-clockwise
                positive
            path (PathOut):
     """

    clearance: float | None
    contact: None | ReportContactOut
    distance: float | None
    face: int | None
    index: int
    kind: ReportTouchOutKind
    normal_angle: float | None
    path: PathOut
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.path_out import PathOut # noqa: PLC0415
        from ..models.report_contact_out import ReportContactOut # noqa: PLC0415
        clearance: float | None
        clearance = self.clearance

        contact: dict[str, Any] | None
        if isinstance(self.contact, ReportContactOut):
            contact = self.contact.to_dict()
        else:
            contact = self.contact

        distance: float | None
        distance = self.distance

        face: int | None
        face = self.face

        index = self.index

        kind = self.kind.value

        normal_angle: float | None
        normal_angle = self.normal_angle

        path = self.path.to_dict()


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "clearance": clearance,
            "contact": contact,
            "distance": distance,
            "face": face,
            "index": index,
            "kind": kind,
            "normal_angle": normal_angle,
            "path": path,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.path_out import PathOut # noqa: PLC0415
        from ..models.report_contact_out import ReportContactOut # noqa: PLC0415
        d = dict(src_dict)
        def _parse_clearance(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        clearance = _parse_clearance(d.pop("clearance"))


        def _parse_contact(data: object) -> None | ReportContactOut:
            if data is None:
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                contact_type_0 = ReportContactOut.from_dict(data)



                return contact_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | ReportContactOut, data)

        contact = _parse_contact(d.pop("contact"))


        def _parse_distance(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        distance = _parse_distance(d.pop("distance"))


        def _parse_face(data: object) -> int | None:
            if data is None:
                return data
            return cast(int | None, data)

        face = _parse_face(d.pop("face"))


        index = d.pop("index")

        kind = ReportTouchOutKind(d.pop("kind"))




        def _parse_normal_angle(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        normal_angle = _parse_normal_angle(d.pop("normal_angle"))


        path = PathOut.from_dict(d.pop("path"))




        report_touch_out = cls(
            clearance=clearance,
            contact=contact,
            distance=distance,
            face=face,
            index=index,
            kind=kind,
            normal_angle=normal_angle,
            path=path,
        )


        report_touch_out.additional_properties = d
        return report_touch_out

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
