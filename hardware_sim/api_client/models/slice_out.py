from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast






T = TypeVar("T", bound="SliceOut")



@_attrs_define
class SliceOut:
    """ 
        Attributes:
            height (float):
            outline (list[list[float]]):
            holes (list[list[list[float]]] | None | Unset):
            normal_z (list[float] | None | Unset):
     """

    height: float
    outline: list[list[float]]
    holes: list[list[list[float]]] | None | Unset = UNSET
    normal_z: list[float] | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        height = self.height

        outline = []
        for outline_item_data in self.outline:
            outline_item = outline_item_data


            outline.append(outline_item)



        holes: list[list[list[float]]] | None | Unset
        if isinstance(self.holes, Unset):
            holes = UNSET
        elif isinstance(self.holes, list):
            holes = []
            for holes_type_0_item_data in self.holes:
                holes_type_0_item = []
                for holes_type_0_item_item_data in holes_type_0_item_data:
                    holes_type_0_item_item = holes_type_0_item_item_data


                    holes_type_0_item.append(holes_type_0_item_item)


                holes.append(holes_type_0_item)


        else:
            holes = self.holes

        normal_z: list[float] | None | Unset
        if isinstance(self.normal_z, Unset):
            normal_z = UNSET
        elif isinstance(self.normal_z, list):
            normal_z = self.normal_z


        else:
            normal_z = self.normal_z


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
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


        def _parse_holes(data: object) -> list[list[list[float]]] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                holes_type_0 = []
                _holes_type_0 = data
                for holes_type_0_item_data in (_holes_type_0):
                    holes_type_0_item = []
                    _holes_type_0_item = holes_type_0_item_data
                    for holes_type_0_item_item_data in (_holes_type_0_item):
                        holes_type_0_item_item = cast(list[float], holes_type_0_item_item_data)

                        holes_type_0_item.append(holes_type_0_item_item)

                    holes_type_0.append(holes_type_0_item)

                return holes_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[list[list[float]]] | None | Unset, data)

        holes = _parse_holes(d.pop("holes", UNSET))


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


        slice_out = cls(
            height=height,
            outline=outline,
            holes=holes,
            normal_z=normal_z,
        )


        slice_out.additional_properties = d
        return slice_out

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
