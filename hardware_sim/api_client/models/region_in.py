from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast






T = TypeVar("T", bound="RegionIn")



@_attrs_define
class RegionIn:
    """ The object's area centroid lies within `radius` of `center` (world frame).

        Attributes:
            center (list[float]): [x, y]
            radius (float):
     """

    center: list[float]
    radius: float





    def to_dict(self) -> dict[str, Any]:
        center = self.center



        radius = self.radius


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "center": center,
            "radius": radius,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        center = cast(list[float], d.pop("center"))


        radius = d.pop("radius")

        region_in = cls(
            center=center,
            radius=radius,
        )

        return region_in

