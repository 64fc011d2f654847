from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="PathIn")



@_attrs_define
class PathIn:
    """ 
        Attributes:
            direction (list[float]): [x, y], not both zero; normalized by the service
            length (float):
            origin (list[float]): [x, y]
            height (float | None | Unset): probing height above the table, one the objects have slices at (the plan's path
                says which); null: the default height
     """

    direction: list[float]
    length: float
    origin: list[float]
    height: float | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        direction = self.direction



        length = self.length

        origin = self.origin



        height: float | None | Unset
        if isinstance(self.height, Unset):
            height = UNSET
        else:
            height = self.height


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "direction": direction,
            "length": length,
            "origin": origin,
        })
        if height is not UNSET:
            field_dict["height"] = height

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        direction = cast(list[float], d.pop("direction"))


        length = d.pop("length")

        origin = cast(list[float], d.pop("origin"))


        def _parse_height(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        height = _parse_height(d.pop("height", UNSET))


        path_in = cls(
            direction=direction,
            length=length,
            origin=origin,
            height=height,
        )

        return path_in

