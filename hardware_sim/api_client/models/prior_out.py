from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
  from ..models.region_out import RegionOut





T = TypeVar("T", bound="PriorOut")



@_attrs_define
class PriorOut:
    """ The pose prior the session was created with.

        Attributes:
            region (None | RegionOut):
            theta (list[float] | None): [lo, hi] radians
     """

    region: None | RegionOut
    theta: list[float] | None
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.region_out import RegionOut # noqa: PLC0415
        region: dict[str, Any] | None
        if isinstance(self.region, RegionOut):
            region = self.region.to_dict()
        else:
            region = self.region

        theta: list[float] | None
        if isinstance(self.theta, list):
            theta = self.theta


        else:
            theta = self.theta


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "region": region,
            "theta": theta,
        })

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.region_out import RegionOut # noqa: PLC0415
        d = dict(src_dict)
        def _parse_region(data: object) -> None | RegionOut:
            if data is None:
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                region_type_0 = RegionOut.from_dict(data)



                return region_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | RegionOut, data)

        region = _parse_region(d.pop("region"))


        def _parse_theta(data: object) -> list[float] | None:
            if data is None:
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                theta_type_0 = cast(list[float], data)

                return theta_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[float] | None, data)

        theta = _parse_theta(d.pop("theta"))


        prior_out = cls(
            region=region,
            theta=theta,
        )


        prior_out.additional_properties = d
        return prior_out

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
