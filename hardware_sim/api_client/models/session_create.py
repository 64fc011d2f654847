from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, BinaryIO, TextIO, TYPE_CHECKING, Generator

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..types import UNSET, Unset
from typing import cast

if TYPE_CHECKING:
  from ..models.accuracy_in import AccuracyIn
  from ..models.object_in import ObjectIn
  from ..models.prior_in import PriorIn
  from ..models.sensor_in import SensorIn
  from ..models.strategy_in import StrategyIn
  from ..models.workspace_in import WorkspaceIn





T = TypeVar("T", bound="SessionCreate")



@_attrs_define
class SessionCreate:
    """ A new session: its object set (registered names or inline §8 objects), sensor
    bounds, safe circle, the sensor's place on it, strategy and allowed outliers.

        Attributes:
            objects (list[ObjectIn | str]):
            accuracy (AccuracyIn | None | Unset): what `localized` requires; default fitted to the sensor
            max_outliers (int | Unset):  Default: 0.
            prior (None | PriorIn | Unset): what is known of the pose before touching (a fixture, a camera, the previous
                part): no hypothesis outside it is considered, and the first probe aims at its region
            sensor (SensorIn | Unset): Bounded sensor errors: contact position (length) and normal angle (radians).
                With a ball tip, `tip_radius` (length): each contact reported is the ball's
                centre and `position_error` bounds that centre (DESIGN §4.14).
            sensor_position (list[float] | None | Unset): default: the point of the safe circle on its +x axis
            strategy (StrategyIn | Unset):
            workspace (WorkspaceIn | Unset): The safe circle: known to contain the object; paths start on it.
     """

    objects: list[ObjectIn | str]
    accuracy: AccuracyIn | None | Unset = UNSET
    max_outliers: int | Unset = 0
    prior: None | PriorIn | Unset = UNSET
    sensor: SensorIn | Unset = UNSET
    sensor_position: list[float] | None | Unset = UNSET
    strategy: StrategyIn | Unset = UNSET
    workspace: WorkspaceIn | Unset = UNSET





    def to_dict(self) -> dict[str, Any]:
        from ..models.accuracy_in import AccuracyIn # noqa: PLC0415
        from ..models.object_in import ObjectIn # noqa: PLC0415
        from ..models.prior_in import PriorIn # noqa: PLC0415
        from ..models.sensor_in import SensorIn # noqa: PLC0415
        from ..models.strategy_in import StrategyIn # noqa: PLC0415
        from ..models.workspace_in import WorkspaceIn # noqa: PLC0415
        objects = []
        for objects_item_data in self.objects:
            objects_item: dict[str, Any] | str
            if isinstance(objects_item_data, ObjectIn):
                objects_item = objects_item_data.to_dict()
            else:
                objects_item = objects_item_data
            objects.append(objects_item)



        accuracy: dict[str, Any] | None | Unset
        if isinstance(self.accuracy, Unset):
            accuracy = UNSET
        elif isinstance(self.accuracy, AccuracyIn):
            accuracy = self.accuracy.to_dict()
        else:
            accuracy = self.accuracy

        max_outliers = self.max_outliers

        prior: dict[str, Any] | None | Unset
        if isinstance(self.prior, Unset):
            prior = UNSET
        elif isinstance(self.prior, PriorIn):
            prior = self.prior.to_dict()
        else:
            prior = self.prior

        sensor: dict[str, Any] | Unset = UNSET
        if not isinstance(self.sensor, Unset):
            sensor = self.sensor.to_dict()

        sensor_position: list[float] | None | Unset
        if isinstance(self.sensor_position, Unset):
            sensor_position = UNSET
        elif isinstance(self.sensor_position, list):
            sensor_position = self.sensor_position


        else:
            sensor_position = self.sensor_position

        strategy: dict[str, Any] | Unset = UNSET
        if not isinstance(self.strategy, Unset):
            strategy = self.strategy.to_dict()

        workspace: dict[str, Any] | Unset = UNSET
        if not isinstance(self.workspace, Unset):
            workspace = self.workspace.to_dict()


        field_dict: dict[str, Any] = {}

        field_dict.update({
            "objects": objects,
        })
        if accuracy is not UNSET:
            field_dict["accuracy"] = accuracy
        if max_outliers is not UNSET:
            field_dict["max_outliers"] = max_outliers
        if prior is not UNSET:
            field_dict["prior"] = prior
        if sensor is not UNSET:
            field_dict["sensor"] = sensor
        if sensor_position is not UNSET:
            field_dict["sensor_position"] = sensor_position
        if strategy is not UNSET:
            field_dict["strategy"] = strategy
        if workspace is not UNSET:
            field_dict["workspace"] = workspace

        return field_dict



    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.accuracy_in import AccuracyIn # noqa: PLC0415
        from ..models.object_in import ObjectIn # noqa: PLC0415
        from ..models.prior_in import PriorIn # noqa: PLC0415
        from ..models.sensor_in import SensorIn # noqa: PLC0415
        from ..models.strategy_in import StrategyIn # noqa: PLC0415
        from ..models.workspace_in import WorkspaceIn # noqa: PLC0415
        d = dict(src_dict)
        objects = []
        _objects = d.pop("objects")
        for objects_item_data in (_objects):
            def _parse_objects_item(data: object) -> ObjectIn | str:
                try:
                    if not isinstance(data, dict):
                        raise TypeError()
                    objects_item_type_1 = ObjectIn.from_dict(data)



                    return objects_item_type_1
                except (TypeError, ValueError, AttributeError, KeyError):
                    pass
                return cast(ObjectIn | str, data)

            objects_item = _parse_objects_item(objects_item_data)

            objects.append(objects_item)


        def _parse_accuracy(data: object) -> AccuracyIn | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                accuracy_type_0 = AccuracyIn.from_dict(data)



                return accuracy_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(AccuracyIn | None | Unset, data)

        accuracy = _parse_accuracy(d.pop("accuracy", UNSET))


        max_outliers = d.pop("max_outliers", UNSET)

        def _parse_prior(data: object) -> None | PriorIn | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                prior_type_0 = PriorIn.from_dict(data)



                return prior_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | PriorIn | Unset, data)

        prior = _parse_prior(d.pop("prior", UNSET))


        _sensor = d.pop("sensor", UNSET)
        sensor: SensorIn | Unset
        if isinstance(_sensor,  Unset):
            sensor = UNSET
        else:
            sensor = SensorIn.from_dict(_sensor)




        def _parse_sensor_position(data: object) -> list[float] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                sensor_position_type_0 = cast(list[float], data)

                return sensor_position_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[float] | None | Unset, data)

        sensor_position = _parse_sensor_position(d.pop("sensor_position", UNSET))


        _strategy = d.pop("strategy", UNSET)
        strategy: StrategyIn | Unset
        if isinstance(_strategy,  Unset):
            strategy = UNSET
        else:
            strategy = StrategyIn.from_dict(_strategy)




        _workspace = d.pop("workspace", UNSET)
        workspace: WorkspaceIn | Unset
        if isinstance(_workspace,  Unset):
            workspace = UNSET
        else:
            workspace = WorkspaceIn.from_dict(_workspace)




        session_create = cls(
            objects=objects,
            accuracy=accuracy,
            max_outliers=max_outliers,
            prior=prior,
            sensor=sensor,
            sensor_position=sensor_position,
            strategy=strategy,
            workspace=workspace,
        )

        return session_create

