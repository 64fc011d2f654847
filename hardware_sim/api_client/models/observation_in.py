from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.contact_in import ContactIn
  from ..models.path_in import PathIn





T = TypeVar("T", bound="ObservationIn")



@_attrs_define
class ObservationIn:
    """ One executed sensing path and what it touched (`contact` null: nothing).

        Attributes:
            path (PathIn):
            contact (ContactIn | None | Unset):
     """

    path: PathIn
    contact: ContactIn | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        from ..models.contact_in import ContactIn # noqa: PLC0415
        from ..models.path_in import PathIn # noqa: PLC0415
        path = self.path.to_dict()

        contact: dict[str, Any] | None | Unset
        if isinstance(self.contact, Unset):
            contact = UNSET
        elif isinstance(self.contact, ContactIn):
            contact = self.contact.to_dict()
        else:
            contact = self.contact


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "path": path,
        })
        if contact is not UNSET:
            field_dict["contact"] = contact

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.contact_in import ContactIn # noqa: PLC0415
        from ..models.path_in import PathIn # noqa: PLC0415
        d = dict(src_dict)
        path = PathIn.from_dict(d.pop("path"))




        def _parse_contact(data: object) -> ContactIn | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                contact_type_0 = ContactIn.from_dict(data)



                return contact_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(ContactIn | None | Unset, data)

        contact = _parse_contact(d.pop("contact", UNSET))


        observation_in = cls(
            path=path,
            contact=contact,
        )

        return observation_in

