from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="ContactIn")



@_attrs_define
class ContactIn:
    """ 
        Attributes:
            normal (list[float]): the measured outward normal, not both zero
            point (list[float]): [x, y]
            normal_z (float | None | Unset):
     """

    normal: list[float]
    point: list[float]
    normal_z: float | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        normal = self.normal



        point = self.point



        normal_z: float | None | Unset
        if isinstance(self.normal_z, Unset):
            normal_z = UNSET
        else:
            normal_z = self.normal_z


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "normal": normal,
            "point": point,
        })
        if normal_z is not UNSET:
            field_dict["normal_z"] = normal_z

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        normal = cast(list[float], d.pop("normal"))


        point = cast(list[float], d.pop("point"))


        def _parse_normal_z(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        normal_z = _parse_normal_z(d.pop("normal_z", UNSET))


        contact_in = cls(
            normal=normal,
            point=point,
            normal_z=normal_z,
        )

        return contact_in

