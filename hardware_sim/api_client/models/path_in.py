from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast






T = TypeVar("T", bound="PathIn")



@_attrs_define
class PathIn:
    """ 
        Attributes:
            direction (list[float]): non-zero; normalized by the service
            length (float):
            origin (list[float]): [x, y]
     """

    direction: list[float]
    length: float
    origin: list[float]





    def to_dict(self) -> dict[str, Any]:
        direction = self.direction



        length = self.length

        origin = self.origin




        field_dict: dict[str, Any] = {}

        field_dict.update({
            "direction": direction,
            "length": length,
            "origin": origin,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        direction = cast(list[float], d.pop("direction"))


        length = d.pop("length")

        origin = cast(list[float], d.pop("origin"))


        path_in = cls(
            direction=direction,
            length=length,
            origin=origin,
        )

        return path_in

