from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset







T = TypeVar("T", bound="AccuracyIn")



@_attrs_define
class AccuracyIn:
    """ What `localized` requires: the pose's translation bound (length) and
    rotation bound (radians) at most these. Default: 5 position errors plus 2% of
    the largest object's diameter, and twice the normal error plus 0.02 rad.

        Attributes:
            rotation (float):
            translation (float):
     """

    rotation: float
    translation: float





    def to_dict(self) -> dict[str, Any]:
        rotation = self.rotation

        translation = self.translation


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "rotation": rotation,
            "translation": translation,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        rotation = d.pop("rotation")

        translation = d.pop("translation")

        accuracy_in = cls(
            rotation=rotation,
            translation=translation,
        )

        return accuracy_in

