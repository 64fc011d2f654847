from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset






T = TypeVar("T", bound="SensorIn")



@_attrs_define
class SensorIn:
    """ Bounded sensor errors: contact position (length) and normal angle (radians).

        Attributes:
            normal_error (float | Unset):  Default: 0.0.
            position_error (float | Unset):  Default: 0.0.
     """

    normal_error: float | Unset = 0.0
    position_error: float | Unset = 0.0





    def to_dict(self) -> dict[str, Any]:
        normal_error = self.normal_error

        position_error = self.position_error


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if normal_error is not UNSET:
            field_dict["normal_error"] = normal_error
        if position_error is not UNSET:
            field_dict["position_error"] = position_error

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        normal_error = d.pop("normal_error", UNSET)

        position_error = d.pop("position_error", UNSET)

        sensor_in = cls(
            normal_error=normal_error,
            position_error=position_error,
        )

        return sensor_in

