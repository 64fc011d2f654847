from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="WorkspaceIn")



@_attrs_define
class WorkspaceIn:
    """ The safe circle: known to contain the object; paths start on it.

        Attributes:
            center (list[float] | Unset): [x, y]
            radius (float | Unset):  Default: 200.0.
     """

    center: list[float] | Unset = UNSET
    radius: float | Unset = 200.0





    def to_dict(self) -> dict[str, Any]:
        center: list[float] | Unset = UNSET
        if not isinstance(self.center, Unset):
            center = self.center



        radius = self.radius


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if center is not UNSET:
            field_dict["center"] = center
        if radius is not UNSET:
            field_dict["radius"] = radius

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        center = cast(list[float], d.pop("center", UNSET))


        radius = d.pop("radius", UNSET)

        workspace_in = cls(
            center=center,
            radius=radius,
        )

        return workspace_in

