from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset






T = TypeVar("T", bound="SensorOut")



@_attrs_define
class SensorOut:
    """ 
        Attributes:
            normal_error (float): radians
            position_error (float):
            tip_radius (float | Unset): ball tip radius; contacts are its centre Default: 0.0.
     """

    normal_error: float
    position_error: float
    tip_radius: float | Unset = 0.0
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        normal_error = self.normal_error

        position_error = self.position_error

        tip_radius = self.tip_radius


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "normal_error": normal_error,
            "position_error": position_error,
        })
        if tip_radius is not UNSET:
            field_dict["tip_radius"] = tip_radius

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        normal_error = d.pop("normal_error")

        position_error = d.pop("position_error")

        tip_radius = d.pop("tip_radius", UNSET)

        sensor_out = cls(
            normal_error=normal_error,
            position_error=position_error,
            tip_radius=tip_radius,
        )


        sensor_out.additional_properties = d
        return sensor_out

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
