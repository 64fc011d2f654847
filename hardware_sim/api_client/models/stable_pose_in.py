from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.slice_in import SliceIn





T = TypeVar("T", bound="StablePoseIn")



@_attrs_define
class StablePoseIn:
    """ One stable pose: an `outline` (with holes), or `slices` at several probing
    heights (DESIGN §4.13), the first at the default height; at most
    `max_pose_faces` faces in all.

        Attributes:
            holes (list[list[list[float]]] | Unset):
            normal_z (list[float] | None | Unset):
            outline (list[list[float]] | None | Unset):
            probability (float | Unset):  Default: 1.0.
            slices (list[SliceIn] | None | Unset):
     """

    holes: list[list[list[float]]] | Unset = UNSET
    normal_z: list[float] | None | Unset = UNSET
    outline: list[list[float]] | None | Unset = UNSET
    probability: float | Unset = 1.0
    slices: list[SliceIn] | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        from ..models.slice_in import SliceIn # noqa: PLC0415
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

        probability = self.probability

        slices: list[dict[str, Any]] | None | Unset
        if isinstance(self.slices, Unset):
            slices = UNSET
        elif isinstance(self.slices, list):
            slices = []
            for slices_type_0_item_data in self.slices:
                slices_type_0_item = slices_type_0_item_data.to_dict()
                slices.append(slices_type_0_item)


        else:
            slices = self.slices


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if holes is not UNSET:
            field_dict["holes"] = holes
        if normal_z is not UNSET:
            field_dict["normal_z"] = normal_z
        if outline is not UNSET:
            field_dict["outline"] = outline
        if probability is not UNSET:
            field_dict["probability"] = probability
        if slices is not UNSET:
            field_dict["slices"] = slices

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.slice_in import SliceIn # noqa: PLC0415
        d = dict(src_dict)
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


        probability = d.pop("probability", UNSET)

        def _parse_slices(data: object) -> list[SliceIn] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                slices_type_0 = []
                _slices_type_0 = data
                for slices_type_0_item_data in (_slices_type_0):
                    slices_type_0_item = SliceIn.from_dict(slices_type_0_item_data)



                    slices_type_0.append(slices_type_0_item)

                return slices_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[SliceIn] | None | Unset, data)

        slices = _parse_slices(d.pop("slices", UNSET))


        stable_pose_in = cls(
            holes=holes,
            normal_z=normal_z,
            outline=outline,
            probability=probability,
            slices=slices,
        )

        return stable_pose_in

