from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.session_out_status import SessionOutStatus
from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.accuracy_out import AccuracyOut
  from ..models.hypothesis_out import HypothesisOut
  from ..models.localization_out import LocalizationOut
  from ..models.observation_out import ObservationOut
  from ..models.prior_out import PriorOut
  from ..models.sensor_out import SensorOut
  from ..models.strategy_out import StrategyOut
  from ..models.workspace_out import WorkspaceOut





T = TypeVar("T", bound="SessionOut")



@_attrs_define
class SessionOut:
    """ A session's state: its configuration, observations and hypotheses (most probable
    first; `hypothesis_count` is the length before any ``?limit=``).

        Attributes:
            accuracy (AccuracyOut): What `localized` requires: the pose bounds at most these.
            class_count (int): equivalence classes left
            hypotheses (list[HypothesisOut]):
            hypothesis_count (int):
            id (str):
            localization (LocalizationOut): How far the session is from `localized` (one class, or classes that are one
                answer, AND the bound within the accuracy): classes left, bound, what is missing.
            max_outliers (int):
            objects (list[str]):
            observations (list[ObservationOut]):
            sensor (SensorOut):
            sensor_position (list[float]):
            status (SessionOutStatus):
            strategy (StrategyOut):
            version (int):
            workspace (WorkspaceOut):
            prior (None | PriorOut | Unset):
     """

    accuracy: AccuracyOut
    class_count: int
    hypotheses: list[HypothesisOut]
    hypothesis_count: int
    id: str
    localization: LocalizationOut
    max_outliers: int
    objects: list[str]
    observations: list[ObservationOut]
    sensor: SensorOut
    sensor_position: list[float]
    status: SessionOutStatus
    strategy: StrategyOut
    version: int
    workspace: WorkspaceOut
    prior: None | PriorOut | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)





    def to_dict(self) -> dict[str, Any]:
        from ..models.accuracy_out import AccuracyOut # noqa: PLC0415
        from ..models.hypothesis_out import HypothesisOut # noqa: PLC0415
        from ..models.localization_out import LocalizationOut # noqa: PLC0415
        from ..models.observation_out import ObservationOut # noqa: PLC0415
        from ..models.prior_out import PriorOut # noqa: PLC0415
        from ..models.sensor_out import SensorOut # noqa: PLC0415
        from ..models.strategy_out import StrategyOut # noqa: PLC0415
        from ..models.workspace_out import WorkspaceOut # noqa: PLC0415
        accuracy = self.accuracy.to_dict()

        class_count = self.class_count

        hypotheses = []
        for hypotheses_item_data in self.hypotheses:
            hypotheses_item = hypotheses_item_data.to_dict()
            hypotheses.append(hypotheses_item)



        hypothesis_count = self.hypothesis_count

        id = self.id

        localization = self.localization.to_dict()

        max_outliers = self.max_outliers

        objects = self.objects



        observations = []
        for observations_item_data in self.observations:
            observations_item = observations_item_data.to_dict()
            observations.append(observations_item)



        sensor = self.sensor.to_dict()

        sensor_position = self.sensor_position



        status = self.status.value

        strategy = self.strategy.to_dict()

        version = self.version

        workspace = self.workspace.to_dict()

        prior: dict[str, Any] | None | Unset
        if isinstance(self.prior, Unset):
            prior = UNSET
        elif isinstance(self.prior, PriorOut):
            prior = self.prior.to_dict()
        else:
            prior = self.prior


        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update({
            "accuracy": accuracy,
            "class_count": class_count,
            "hypotheses": hypotheses,
            "hypothesis_count": hypothesis_count,
            "id": id,
            "localization": localization,
            "max_outliers": max_outliers,
            "objects": objects,
            "observations": observations,
            "sensor": sensor,
            "sensor_position": sensor_position,
            "status": status,
            "strategy": strategy,
            "version": version,
            "workspace": workspace,
        })
        if prior is not UNSET:
            field_dict["prior"] = prior

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.accuracy_out import AccuracyOut # noqa: PLC0415
        from ..models.hypothesis_out import HypothesisOut # noqa: PLC0415
        from ..models.localization_out import LocalizationOut # noqa: PLC0415
        from ..models.observation_out import ObservationOut # noqa: PLC0415
        from ..models.prior_out import PriorOut # noqa: PLC0415
        from ..models.sensor_out import SensorOut # noqa: PLC0415
        from ..models.strategy_out import StrategyOut # noqa: PLC0415
        from ..models.workspace_out import WorkspaceOut # noqa: PLC0415
        d = dict(src_dict)
        accuracy = AccuracyOut.from_dict(d.pop("accuracy"))




        class_count = d.pop("class_count")

        hypotheses = []
        _hypotheses = d.pop("hypotheses")
        for hypotheses_item_data in (_hypotheses):
            hypotheses_item = HypothesisOut.from_dict(hypotheses_item_data)



            hypotheses.append(hypotheses_item)


        hypothesis_count = d.pop("hypothesis_count")

        id = d.pop("id")

        localization = LocalizationOut.from_dict(d.pop("localization"))




        max_outliers = d.pop("max_outliers")

        objects = cast(list[str], d.pop("objects"))


        observations = []
        _observations = d.pop("observations")
        for observations_item_data in (_observations):
            observations_item = ObservationOut.from_dict(observations_item_data)



            observations.append(observations_item)


        sensor = SensorOut.from_dict(d.pop("sensor"))




        sensor_position = cast(list[float], d.pop("sensor_position"))


        status = SessionOutStatus(d.pop("status"))




        strategy = StrategyOut.from_dict(d.pop("strategy"))




        version = d.pop("version")

        workspace = WorkspaceOut.from_dict(d.pop("workspace"))




        def _parse_prior(data: object) -> None | PriorOut | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                prior_type_0 = PriorOut.from_dict(data)



                return prior_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | PriorOut | Unset, data)

        prior = _parse_prior(d.pop("prior", UNSET))


        session_out = cls(
            accuracy=accuracy,
            class_count=class_count,
            hypotheses=hypotheses,
            hypothesis_count=hypothesis_count,
            id=id,
            localization=localization,
            max_outliers=max_outliers,
            objects=objects,
            observations=observations,
            sensor=sensor,
            sensor_position=sensor_position,
            status=status,
            strategy=strategy,
            version=version,
            workspace=workspace,
            prior=prior,
        )


        session_out.additional_properties = d
        return session_out

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
