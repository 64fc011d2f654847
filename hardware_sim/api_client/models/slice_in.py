from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="SliceIn")



@_attrs_define
class SliceIn:
    """ The stable pose's outline at one probing height above the table.

        Attributes:
            height (float):
            outline (list[list[float]]): vertices
            holes (list[list[list[float]]] | Unset):
            normal_z (list[float] | None | Unset):
     """

    height: float
    outline: list[list[float]]
    holes: list[list[list[float]]] | Unset = UNSET
    normal_z: list[float] | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        height = self.height

        outline = []
        for outline_item_data in self.outline:
            outline_item = outline_item_data


            outline.append(outline_item)



        holes: list[list[list[float]]] | Unset = UNSET
        if not isinstance(self.holes, Unset):
            holes = []
            for holes_item_data in self.holes:
                holes_item = []
                for holes_item_item_data in holes_item_data:
                    holes_item_item = holes_item_item_data


                    holes_item.append(holes_item_item)


                holes.append(holes_item)



        normal_z: list[float] | None | Unset
        if isinstance(self.normal_z, Unset):
            normal_z = UNSET
        elif isinstance(self.normal_z, list):
            normal_z = self.normal_z


        else:
            normal_z = self.normal_z


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "height": height,
            "outline": outline,
        })
        if holes is not UNSET:
            field_dict["holes"] = holes
        if normal_z is not UNSET:
            field_dict["normal_z"] = normal_z

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        height = d.pop("height")

        outline = []
        _outline = d.pop("outline")
        for outline_item_data in (_outline):
            outline_item = cast(list[float], outline_item_data)

            outline.append(outline_item)


        _holes = d.pop("holes", UNSET)
        holes: list[list[list[float]]] | Unset = UNSET
        if _holes is not UNSET:
            holes = []
            for holes_item_data in _holes:
                holes_item = []
                _holes_item = holes_item_data
                for holes_item_item_data in (_holes_item):
                    holes_item_item = cast(list[float], holes_item_item_data)

                    holes_item.append(holes_item_item)

                holes.append(holes_item)


        def _parse_normal_z(data: object) -> list[float] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                normal_z_type_0 = cast(list[float], data)

                return normal_z_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[float] | None | Unset, data)

        normal_z = _parse_normal_z(d.pop("normal_z", UNSET))


        slice_in = cls(
            height=height,
            outline=outline,
            holes=holes,
            normal_z=normal_z,
        )

        return slice_in

