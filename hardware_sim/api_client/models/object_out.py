from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.stable_pose_out import StablePoseOut





T = TypeVar("T", bound="ObjectOut")



@_attrs_define
class ObjectOut:
    """ An object in the §8 format (always the ``stable_poses`` form).

        Attributes:
            name (str):
            stable_poses (list[StablePoseOut]):
            prior (float | None | Unset):
     """

    name: str
    stable_poses: list[StablePoseOut]
    prior: float | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.stable_pose_out import StablePoseOut # noqa: PLC0415
        name = self.name

        stable_poses = []
        for stable_poses_item_data in self.stable_poses:
            stable_poses_item = stable_poses_item_data.to_dict()
            stable_poses.append(stable_poses_item)



        prior: float | None | Unset
        if isinstance(self.prior, Unset):
            prior = UNSET
        else:
            prior = self.prior


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "name": name,
            "stable_poses": stable_poses,
        })
        if prior is not UNSET:
            field_dict["prior"] = prior

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.stable_pose_out import StablePoseOut # noqa: PLC0415
        d = dict(src_dict)
        name = d.pop("name")

        stable_poses = []
        _stable_poses = d.pop("stable_poses")
        for stable_poses_item_data in (_stable_poses):
            stable_poses_item = StablePoseOut.from_dict(stable_poses_item_data)



            stable_poses.append(stable_poses_item)


        def _parse_prior(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        prior = _parse_prior(d.pop("prior", UNSET))


        object_out = cls(
            name=name,
            stable_poses=stable_poses,
            prior=prior,
        )


        object_out.additional_properties = d
        return object_out

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
