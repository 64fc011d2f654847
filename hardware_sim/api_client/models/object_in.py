from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.stable_pose_in import StablePoseIn





T = TypeVar("T", bound="ObjectIn")



@_attrs_define
class ObjectIn:
    """ One object in the §8 format: `outline` (one stable pose) or `stable_poses`.

        Attributes:
            name (str):
            holes (list[list[list[float]]] | None | Unset):
            normal_z (list[float] | None | Unset):
            outline (list[list[float]] | None | Unset):
            prior (float | None | Unset):
            stable_poses (list[StablePoseIn] | None | Unset):
     """

    name: str
    holes: list[list[list[float]]] | None | Unset = UNSET
    normal_z: list[float] | None | Unset = UNSET
    outline: list[list[float]] | None | Unset = UNSET
    prior: float | None | Unset = UNSET
    stable_poses: list[StablePoseIn] | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        from ..models.stable_pose_in import StablePoseIn # noqa: PLC0415
        name = self.name

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

        outline: list[list[float]] | None | Unset
        if isinstance(self.outline, Unset):
            outline = UNSET
        elif isinstance(self.outline, list):
            outline = []
            for outline_type_0_item_data in self.outline:
                outline_type_0_item = outline_type_0_item_data


                outline.append(outline_type_0_item)


        else:
            outline = self.outline

        prior: float | None | Unset
        if isinstance(self.prior, Unset):
            prior = UNSET
        else:
            prior = self.prior

        stable_poses: list[dict[str, Any]] | None | Unset
        if isinstance(self.stable_poses, Unset):
            stable_poses = UNSET
        elif isinstance(self.stable_poses, list):
            stable_poses = []
            for stable_poses_type_0_item_data in self.stable_poses:
                stable_poses_type_0_item = stable_poses_type_0_item_data.to_dict()
                stable_poses.append(stable_poses_type_0_item)


        else:
            stable_poses = self.stable_poses


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "name": name,
        })
        if holes is not UNSET:
            field_dict["holes"] = holes
        if normal_z is not UNSET:
            field_dict["normal_z"] = normal_z
        if outline is not UNSET:
            field_dict["outline"] = outline
        if prior is not UNSET:
            field_dict["prior"] = prior
        if stable_poses is not UNSET:
            field_dict["stable_poses"] = stable_poses

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.stable_pose_in import StablePoseIn # noqa: PLC0415
        d = dict(src_dict)
        name = d.pop("name")

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


        def _parse_outline(data: object) -> list[list[float]] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                outline_type_0 = []
                _outline_type_0 = data
                for outline_type_0_item_data in (_outline_type_0):
                    outline_type_0_item = cast(list[float], outline_type_0_item_data)

                    outline_type_0.append(outline_type_0_item)

                return outline_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[list[float]] | None | Unset, data)

        outline = _parse_outline(d.pop("outline", UNSET))


        def _parse_prior(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        prior = _parse_prior(d.pop("prior", UNSET))


        def _parse_stable_poses(data: object) -> list[StablePoseIn] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                stable_poses_type_0 = []
                _stable_poses_type_0 = data
                for stable_poses_type_0_item_data in (_stable_poses_type_0):
                    stable_poses_type_0_item = StablePoseIn.from_dict(stable_poses_type_0_item_data)



                    stable_poses_type_0.append(stable_poses_type_0_item)

                return stable_poses_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[StablePoseIn] | None | Unset, data)

        stable_poses = _parse_stable_poses(d.pop("stable_poses", UNSET))


        object_in = cls(
            name=name,
            holes=holes,
            normal_z=normal_z,
            outline=outline,
            prior=prior,
            stable_poses=stable_poses,
        )

        return object_in

