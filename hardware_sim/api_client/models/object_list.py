from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
  from ..models.object_out import ObjectOut





T = TypeVar("T", bound="ObjectList")



@_attrs_define
class ObjectList:
    """ A §8 object file: every registered object, by name.

        Attributes:
            objects (list[ObjectOut]):
     """

    objects: list[ObjectOut]
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.object_out import ObjectOut # noqa: PLC0415
        objects = []
        for objects_item_data in self.objects:
            objects_item = objects_item_data.to_dict()
            objects.append(objects_item)




        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "objects": objects,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.object_out import ObjectOut # noqa: PLC0415
        d = dict(src_dict)
        objects = []
        _objects = d.pop("objects")
        for objects_item_data in (_objects):
            objects_item = ObjectOut.from_dict(objects_item_data)



            objects.append(objects_item)


        object_list = cls(
            objects=objects,
        )


        object_list.additional_properties = d
        return object_list

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
