from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.slice_out import SliceOut





T = TypeVar("T", bound="StablePoseOut")



@_attrs_define
class StablePoseOut:
    """ One stable pose: its `outline` (with holes), or its `slices` at several
    probing heights, the first at the default height.

        Attributes:
            probability (float):
            holes (list[list[list[float]]] | None | Unset):
            normal_z (list[float] | None | Unset):
            outline (list[list[float]] | None | Unset):
            slices (list[SliceOut] | None | Unset):
     """

    probability: float
    holes: list[list[list[float]]] | None | Unset = UNSET
    normal_z: list[float] | None | Unset = UNSET
    outline: list[list[float]] | None | Unset = UNSET
    slices: list[SliceOut] | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.slice_out import SliceOut # noqa: PLC0415
        probability = self.probability

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
        field_dict.update(self.additional_properties)
        field_dict.update({
            "probability": probability,
        })
        if holes is not UNSET:
            field_dict["holes"] = holes
        if normal_z is not UNSET:
            field_dict["normal_z"] = normal_z
        if outline is not UNSET:
            field_dict["outline"] = outline
        if slices is not UNSET:
            field_dict["slices"] = slices

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.slice_out import SliceOut # noqa: PLC0415
        d = dict(src_dict)
        probability = d.pop("probability")

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


        def _parse_slices(data: object) -> list[SliceOut] | None | Unset:
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
                    slices_type_0_item = SliceOut.from_dict(slices_type_0_item_data)



                    slices_type_0.append(slices_type_0_item)

                return slices_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[SliceOut] | None | Unset, data)

        slices = _parse_slices(d.pop("slices", UNSET))


        stable_pose_out = cls(
            probability=probability,
            holes=holes,
            normal_z=normal_z,
            outline=outline,
            slices=slices,
        )


        stable_pose_out.additional_properties = d
        return stable_pose_out

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
