from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.localization_out_missing_item import LocalizationOutMissingItem
from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.error_bound_out import ErrorBoundOut





T = TypeVar("T", bound="LocalizationOut")



@_attrs_define
class LocalizationOut:
    """ How far the session is from `localized` (one class, or classes that are one
    answer, AND the bound within the accuracy): classes left, bound, what is missing.

        Attributes:
            bound (ErrorBoundOut | None): the most probable class' bound (its widest member's, widened by the symmetry
                tolerance), or the one covering classes that are one answer; null without a hypothesis
            classes (int):
            missing (list[LocalizationOutMissingItem]): empty when localized; one_class while several classes are left that
                are not one answer within the accuracy, accuracy while the bound exceeds it
            covered (int | Unset): how many classes the bound covers (one part's nearby poses: a curve's) Default: 1.
            rotation_free (bool | Unset): true when the class' outline is round (a disc): every rotation is one class, the
                bound's rotation is pi and the accuracy asks for the translation only Default: False.
     """

    bound: ErrorBoundOut | None
    classes: int
    missing: list[LocalizationOutMissingItem]
    covered: int | Unset = 1
    rotation_free: bool | Unset = False
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.error_bound_out import ErrorBoundOut # noqa: PLC0415
        bound: dict[str, Any] | None
        if isinstance(self.bound, ErrorBoundOut):
            bound = self.bound.to_dict()
        else:
            bound = self.bound

        classes = self.classes

        missing = []
        for missing_item_data in self.missing:
            missing_item = missing_item_data.value
            missing.append(missing_item)



        covered = self.covered

        rotation_free = self.rotation_free


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "bound": bound,
            "classes": classes,
            "missing": missing,
        })
        if covered is not UNSET:
            field_dict["covered"] = covered
        if rotation_free is not UNSET:
            field_dict["rotation_free"] = rotation_free

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.error_bound_out import ErrorBoundOut # noqa: PLC0415
        d = dict(src_dict)
        def _parse_bound(data: object) -> ErrorBoundOut | None:
            if data is None:
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                bound_type_0 = ErrorBoundOut.from_dict(data)



                return bound_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(ErrorBoundOut | None, data)

        bound = _parse_bound(d.pop("bound"))


        classes = d.pop("classes")

        missing = []
        _missing = d.pop("missing")
        for missing_item_data in (_missing):
            missing_item = LocalizationOutMissingItem(missing_item_data)



            missing.append(missing_item)


        covered = d.pop("covered", UNSET)

        rotation_free = d.pop("rotation_free", UNSET)

        localization_out = cls(
            bound=bound,
            classes=classes,
            missing=missing,
            covered=covered,
            rotation_free=rotation_free,
        )


        localization_out.additional_properties = d
        return localization_out

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
