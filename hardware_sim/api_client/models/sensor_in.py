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
    With a ball tip, `tip_radius` (length): each contact reported is the ball's
    centre and `position_error` bounds that centre (DESIGN §4.14).

        Attributes:
            normal_error (float | Unset):  Default: 0.0.
            position_error (float | Unset):  Default: 0.0.
            tip_radius (float | Unset): ball tip radius (length) Default: 0.0.
     """

    normal_error: float | Unset = 0.0
    position_error: float | Unset = 0.0
    tip_radius: float | Unset = 0.0





    def to_dict(self) -> dict[str, Any]:
        normal_error = self.normal_error

        position_error = self.position_error

        tip_radius = self.tip_radius


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if normal_error is not UNSET:
            field_dict["normal_error"] = normal_error
        if position_error is not UNSET:
            field_dict["position_error"] = position_error
        if tip_radius is not UNSET:
            field_dict["tip_radius"] = tip_radius

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        normal_error = d.pop("normal_error", UNSET)

        position_error = d.pop("position_error", UNSET)

        tip_radius = d.pop("tip_radius", UNSET)

        sensor_in = cls(
            normal_error=normal_error,
            position_error=position_error,
            tip_radius=tip_radius,
        )

        return sensor_in

