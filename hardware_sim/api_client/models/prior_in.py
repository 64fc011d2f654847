from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.region_in import RegionIn





T = TypeVar("T", bound="PriorIn")



@_attrs_define
class PriorIn:
    """ A rough pose known beforehand: a region for the object's centroid and/or a
    rotation range [lo, hi] (radians, lo <= hi <= lo + 2 pi).

        Attributes:
            region (None | RegionIn | Unset):
            theta (list[float] | None | Unset):
     """

    region: None | RegionIn | Unset = UNSET
    theta: list[float] | None | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        from ..models.region_in import RegionIn # noqa: PLC0415
        region: dict[str, Any] | None | Unset
        if isinstance(self.region, Unset):
            region = UNSET
        elif isinstance(self.region, RegionIn):
            region = self.region.to_dict()
        else:
            region = self.region

        theta: list[float] | None | Unset
        if isinstance(self.theta, Unset):
            theta = UNSET
        elif isinstance(self.theta, list):
            theta = self.theta


        else:
            theta = self.theta


        field_dict: dict[str, Any] = {}

        field_dict.update({
        })
        if region is not UNSET:
            field_dict["region"] = region
        if theta is not UNSET:
            field_dict["theta"] = theta

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.region_in import RegionIn # noqa: PLC0415
        d = dict(src_dict)
        def _parse_region(data: object) -> None | RegionIn | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                region_type_0 = RegionIn.from_dict(data)



                return region_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | RegionIn | Unset, data)

        region = _parse_region(d.pop("region", UNSET))


        def _parse_theta(data: object) -> list[float] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                theta_type_0 = cast(list[float], data)

                return theta_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[float] | None | Unset, data)

        theta = _parse_theta(d.pop("theta", UNSET))


        prior_in = cls(
            region=region,
            theta=theta,
        )

        return prior_in

