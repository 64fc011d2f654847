from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
  from ..models.error_bound_out import ErrorBoundOut
  from ..models.pose_out import PoseOut





T = TypeVar("T", bound="HypothesisOut")



@_attrs_define
class HypothesisOut:
    """ 
        Attributes:
            assignment (list[int | None]): face index per contact, in contact order; null = spurious contact. Where a part's
                interpretations multiply on a finely drawn curve, a contact whose rows differed only in neighbouring faces is
                folded: it names the first of them
            equivalence_class (int): 0 = the most probable class
            error_bound (ErrorBoundOut): |dt| of the translation, |dtheta| (radians) and the error disk diameter eps_t.
            object_ (str):
            pose (PoseOut): Model-to-world pose: ``v_world = R(theta) v_model + (x, y)``; theta in radians.
            probability (float):
            stable_pose (int):
     """

    assignment: list[int | None]
    equivalence_class: int
    error_bound: ErrorBoundOut
    object_: str
    pose: PoseOut
    probability: float
    stable_pose: int
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.error_bound_out import ErrorBoundOut # noqa: PLC0415
        from ..models.pose_out import PoseOut # noqa: PLC0415
        assignment = []
        for assignment_item_data in self.assignment:
            assignment_item: int | None
            assignment_item = assignment_item_data
            assignment.append(assignment_item)



        equivalence_class = self.equivalence_class

        error_bound = self.error_bound.to_dict()

        object_ = self.object_

        pose = self.pose.to_dict()

        probability = self.probability

        stable_pose = self.stable_pose


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "assignment": assignment,
            "equivalence_class": equivalence_class,
            "error_bound": error_bound,
            "object": object_,
            "pose": pose,
            "probability": probability,
            "stable_pose": stable_pose,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.error_bound_out import ErrorBoundOut # noqa: PLC0415
        from ..models.pose_out import PoseOut # noqa: PLC0415
        d = dict(src_dict)
        assignment = []
        _assignment = d.pop("assignment")
        for assignment_item_data in (_assignment):
            def _parse_assignment_item(data: object) -> int | None:
                if data is None:
                    return data
                return cast(int | None, data)

            assignment_item = _parse_assignment_item(assignment_item_data)

            assignment.append(assignment_item)


        equivalence_class = d.pop("equivalence_class")

        error_bound = ErrorBoundOut.from_dict(d.pop("error_bound"))




        object_ = d.pop("object")

        pose = PoseOut.from_dict(d.pop("pose"))




        probability = d.pop("probability")

        stable_pose = d.pop("stable_pose")

        hypothesis_out = cls(
            assignment=assignment,
            equivalence_class=equivalence_class,
            error_bound=error_bound,
            object_=object_,
            pose=pose,
            probability=probability,
            stable_pose=stable_pose,
        )


        hypothesis_out.additional_properties = d
        return hypothesis_out

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
