""" Contains all the data models used in inputs/outputs """

from .accuracy_in import AccuracyIn
from .accuracy_out import AccuracyOut
from .contact_in import ContactIn
from .contact_out import ContactOut
from .error_bound_out import ErrorBoundOut
from .field_error import FieldError
from .get_image_png_view import GetImagePngView
from .get_image_svg_view import GetImageSvgView
from .health import Health
from .hypothesis_out import HypothesisOut
from .import_mesh_file_type import ImportMeshFileType
from .localization_out import LocalizationOut
from .localization_out_missing_item import LocalizationOutMissingItem
from .object_created import ObjectCreated
from .object_in import ObjectIn
from .object_list import ObjectList
from .object_out import ObjectOut
from .observation_in import ObservationIn
from .observation_out import ObservationOut
from .path_in import PathIn
from .path_out import PathOut
from .plan_out import PlanOut
from .plan_out_status import PlanOutStatus
from .plan_out_stopped_by_type_0 import PlanOutStoppedByType0
from .planned_path_out import PlannedPathOut
from .planned_path_out_scored_by import PlannedPathOutScoredBy
from .pose_out import PoseOut
from .prior_in import PriorIn
from .prior_out import PriorOut
from .problem import Problem
from .region_in import RegionIn
from .region_out import RegionOut
from .report_bound_out import ReportBoundOut
from .report_contact_out import ReportContactOut
from .report_out import ReportOut
from .report_out_status import ReportOutStatus
from .report_result_out import ReportResultOut
from .report_result_out_missing_item import ReportResultOutMissingItem
from .report_touch_out import ReportTouchOut
from .report_touch_out_kind import ReportTouchOutKind
from .sensor_in import SensorIn
from .sensor_out import SensorOut
from .session_create import SessionCreate
from .session_out import SessionOut
from .session_out_status import SessionOutStatus
from .slice_in import SliceIn
from .slice_out import SliceOut
from .stable_pose_in import StablePoseIn
from .stable_pose_out import StablePoseOut
from .strategy_in import StrategyIn
from .strategy_in_name import StrategyInName
from .strategy_out import StrategyOut
from .view_link_out import ViewLinkOut
from .workspace_in import WorkspaceIn
from .workspace_out import WorkspaceOut

__all__ = (
    "AccuracyIn",
    "AccuracyOut",
    "ContactIn",
    "ContactOut",
    "ErrorBoundOut",
    "FieldError",
    "GetImagePngView",
    "GetImageSvgView",
    "Health",
    "HypothesisOut",
    "ImportMeshFileType",
    "LocalizationOut",
    "LocalizationOutMissingItem",
    "ObjectCreated",
    "ObjectIn",
    "ObjectList",
    "ObjectOut",
    "ObservationIn",
    "ObservationOut",
    "PathIn",
    "PathOut",
    "PlannedPathOut",
    "PlannedPathOutScoredBy",
    "PlanOut",
    "PlanOutStatus",
    "PlanOutStoppedByType0",
    "PoseOut",
    "PriorIn",
    "PriorOut",
    "Problem",
    "RegionIn",
    "RegionOut",
    "ReportBoundOut",
    "ReportContactOut",
    "ReportOut",
    "ReportOutStatus",
    "ReportResultOut",
    "ReportResultOutMissingItem",
    "ReportTouchOut",
    "ReportTouchOutKind",
    "SensorIn",
    "SensorOut",
    "SessionCreate",
    "SessionOut",
    "SessionOutStatus",
    "SliceIn",
    "SliceOut",
    "StablePoseIn",
    "StablePoseOut",
    "StrategyIn",
    "StrategyInName",
    "StrategyOut",
    "ViewLinkOut",
    "WorkspaceIn",
    "WorkspaceOut",
)
