from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.report_result_out_missing_item import ReportResultOutMissingItem
from typing import cast

if TYPE_CHECKING:
  from ..models.pose_out import PoseOut
  from ..models.report_bound_out import ReportBoundOut





T = TypeVar("T", bound="ReportResultOut")



@_attrs_define
class ReportResultOut:
    """ The answer: the most probable hypothesis, its class' probability and bound.

        Attributes:
            bound (ReportBoundOut):
            class_probability (float):
            classes (int): equivalence classes left
            missing (list[ReportResultOutMissingItem]):
            object_ (str):
            pose (PoseOut): Model-to-world pose: ``v_world = R(theta) v_model + (x, y)``; theta in radians.
            probability (float):
            stable_pose (int):
     """

    bound: ReportBoundOut
    class_probability: float
    classes: int
    missing: list[ReportResultOutMissingItem]
    object_: str
    pose: PoseOut
    probability: float
    stable_pose: int
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.pose_out import PoseOut # noqa: PLC0415
        from ..models.report_bound_out import ReportBoundOut # noqa: PLC0415
        bound = self.bound.to_dict()

        class_probability = self.class_probability

        classes = self.classes

        missing = []
        for missing_item_data in self.missing:
            missing_item = missing_item_data.value
            missing.append(missing_item)



        object_ = self.object_

        pose = self.pose.to_dict()

        probability = self.probability

        stable_pose = self.stable_pose


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "bound": bound,
            "class_probability": class_probability,
            "classes": classes,
            "missing": missing,
            "object": object_,
            "pose": pose,
            "probability": probability,
            "stable_pose": stable_pose,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.pose_out import PoseOut # noqa: PLC0415
        from ..models.report_bound_out import ReportBoundOut # noqa: PLC0415
        d = dict(src_dict)
        bound = ReportBoundOut.from_dict(d.pop("bound"))




        class_probability = d.pop("class_probability")

        classes = d.pop("classes")

        missing = []
        _missing = d.pop("missing")
        for missing_item_data in (_missing):
            missing_item = ReportResultOutMissingItem(missing_item_data)



            missing.append(missing_item)


        object_ = d.pop("object")

        pose = PoseOut.from_dict(d.pop("pose"))




        probability = d.pop("probability")

        stable_pose = d.pop("stable_pose")

        report_result_out = cls(
            bound=bound,
            class_probability=class_probability,
            classes=classes,
            missing=missing,
            object_=object_,
            pose=pose,
            probability=probability,
            stable_pose=stable_pose,
        )


        report_result_out.additional_properties = d
        return report_result_out

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
