from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast






T = TypeVar("T", bound="ReportBoundOut")



@_attrs_define
class ReportBoundOut:
    """ 
        Attributes:
            eps_t (float | None): error disk diameter
            rotation (float | None): radians
            translation (float | None):
     """

    eps_t: float | None
    rotation: float | None
    translation: float | None
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        eps_t: float | None
        eps_t = self.eps_t

        rotation: float | None
        rotation = self.rotation

        translation: float | None
        translation = self.translation


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "eps_t": eps_t,
            "rotation": rotation,
            "translation": translation,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        def _parse_eps_t(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        eps_t = _parse_eps_t(d.pop("eps_t"))


        def _parse_rotation(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        rotation = _parse_rotation(d.pop("rotation"))


        def _parse_translation(data: object) -> float | None:
            if data is None:
                return data
            return cast(float | None, data)

        translation = _parse_translation(d.pop("translation"))


        report_bound_out = cls(
            eps_t=eps_t,
            rotation=rotation,
            translation=translation,
        )


        report_bound_out.additional_properties = d
        return report_bound_out

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
