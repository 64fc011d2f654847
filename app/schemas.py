"""Request and response bodies of the HTTP API (DESIGN §6; objects in the §8 format).

Output schemas are plain module-level models. Input schemas carry the
service's limits (vertices per outline, objects per session, plan budget, ...)
as ``Field`` constraints so that they appear in the OpenAPI schema; since the
limits are settings, the input models are built per app by
:func:`input_models`. Vectors are JSON arrays ``[x, y]``, angles radians,
lengths in the unit of the object files.

>>> from app.settings import Settings
>>> m = input_models(Settings(db_path="x.db"))
>>> obs = m.ObservationIn.model_validate(
...     {"path": {"origin": [0, -10], "direction": [0, 1], "length": 20}, "contact": None})
>>> obs.path.length
20.0
"""

import math
from dataclasses import dataclass
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from app.schema_examples import OBJECT_EXAMPLES, OBSERVATION_EXAMPLES, SESSION_EXAMPLES
from app.schema_rules import NOT_ZERO, ONE_POSE_FORM, ONE_SHAPE, only_one_shape
from app.settings import Settings
from planner.planning.config import STRATEGIES

__all__ = [
    "MESH_MEDIA_TYPES",
    "ContactOut",
    "ErrorBoundOut",
    "Health",
    "HypothesisOut",
    "InputModels",
    "ObservationOut",
    "PathOut",
    "PoseOut",
    "SensorOut",
    "SessionOut",
    "Status",
    "StrategyOut",
    "WorkspaceOut",
    "input_models",
]

Status = Literal["awaiting_contact", "ambiguous", "localized", "inconsistent"]
StrategyName = Literal[STRATEGIES]  # type: ignore[valid-type]
#: The planner refuses normal error bounds of pi/4 or more (radians).
MAX_NORMAL_ERROR = math.pi / 4
#: Content-Types a mesh upload may carry besides model/* (none a browser sends unasked).
MESH_MEDIA_TYPES = ("application/octet-stream", "application/sla", "application/vnd.ms-pki.stl")
#: Object names: what the object files allow, less '/' and control characters (URL paths).
NAME_PATTERN = r"^[^/\x00-\x1f\x7f]*[^/\s\x00-\x1f\x7f][^/\x00-\x1f\x7f]*$"

Vec2Out = Annotated[list[float], Field(min_length=2, max_length=2)]


# -- responses --------------------------------------------------------------------------------
class PoseOut(BaseModel):
    """Model-to-world pose: ``v_world = R(theta) v_model + (x, y)``; theta in radians."""

    x: float
    y: float
    theta: float


class ErrorBoundOut(BaseModel):
    """|dt| of the translation, |dtheta| (radians) and the error disk diameter eps_t."""

    translation: float
    rotation: float
    eps_t: float


class HypothesisOut(BaseModel):
    object: str
    stable_pose: int = Field(ge=0)
    pose: PoseOut
    error_bound: ErrorBoundOut
    probability: float = Field(ge=0, le=1)
    assignment: list[int | None] = Field(
        description="face index per contact, in contact order; null = spurious contact. "
        "Where a part's interpretations multiply on a finely drawn curve, a contact whose "
        "rows differed only in neighbouring faces is folded: it names the first of them"
    )
    equivalence_class: int = Field(ge=0, description="0 = the most probable class")


class PathOut(BaseModel):
    origin: Vec2Out
    direction: Vec2Out = Field(description="unit vector")
    length: float
    height: float | None = Field(
        None, description="probing height above the table; null: the default height"
    )


class ContactOut(BaseModel):
    point: Vec2Out
    normal: Vec2Out = Field(description="measured outward unit normal")
    normal_z: float | None = None


class ObservationOut(BaseModel):
    index: int = Field(ge=0)
    path: PathOut
    contact: ContactOut | None


class SensorOut(BaseModel):
    position_error: float
    normal_error: float = Field(description="radians")
    tip_radius: float = Field(0.0, description="ball tip radius; contacts are its centre")


class WorkspaceOut(BaseModel):
    center: Vec2Out
    radius: float


class StrategyOut(BaseModel):
    name: str
    depth: int
    budget_ms: float
    budget_work: float
    max_paths: int
    motion_weight: float
    grid_size: int
    forecast: int = 1
    simulations: int = 1000
    seed: int | None = None


class AccuracyOut(BaseModel):
    """What `localized` requires: the pose bounds at most these."""

    translation: float = Field(description="length")
    rotation: float = Field(description="radians")


class LocalizationOut(BaseModel):
    """How far the session is from `localized` (one class, or classes that are one
    answer, AND the bound within the accuracy): classes left, bound, what is missing."""

    classes: int = Field(ge=0)
    bound: ErrorBoundOut | None = Field(
        description="the most probable class' bound (its widest member's, widened by the "
        "symmetry tolerance), or the one covering classes that are one answer; null "
        "without a hypothesis"
    )
    missing: list[Literal["one_class", "accuracy"]] = Field(
        description="empty when localized; one_class while several classes are left that "
        "are not one answer within the accuracy, accuracy while the bound exceeds it"
    )
    rotation_free: bool = Field(
        default=False,
        description="true when the class' outline is round (a disc): every rotation is one "
        "class, the bound's rotation is pi and the accuracy asks for the translation only",
    )
    covered: int = Field(
        default=1,
        ge=0,
        description="how many classes the bound covers (one part's nearby poses: a curve's)",
    )


class RegionOut(BaseModel):
    center: Vec2Out
    radius: float


class PriorOut(BaseModel):
    """The pose prior the session was created with."""

    region: RegionOut | None
    theta: list[float] | None = Field(description="[lo, hi] radians")


class SessionOut(BaseModel):
    """A session's state: its configuration, observations and hypotheses (most probable
    first; `hypothesis_count` is the length before any ``?limit=``)."""

    id: str
    version: int = Field(ge=1)
    status: Status
    objects: list[str]
    sensor: SensorOut
    workspace: WorkspaceOut
    sensor_position: Vec2Out
    strategy: StrategyOut
    max_outliers: int
    observations: list[ObservationOut]
    hypotheses: list[HypothesisOut]
    hypothesis_count: int = Field(ge=0)
    class_count: int = Field(ge=0, description="equivalence classes left")
    accuracy: AccuracyOut
    localization: LocalizationOut
    prior: PriorOut | None = None


class Health(BaseModel):
    status: str


# -- requests ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class InputModels:
    """The request models of one app (their limits come from its settings)."""

    ObjectIn: type[BaseModel]
    SessionCreate: type[BaseModel]
    ObservationIn: type[BaseModel]


def _object_or_name(value: Any) -> str:
    return "object-name" if isinstance(value, str) else "inline-object"


@dataclass(frozen=True)
class _Shapes:
    """The constrained field types of one app's request models."""

    Vec2: Any
    Direction: Any
    Ring: Any
    Holes: Any
    NormalZ: Any
    Name: Any
    Length: Any
    Coord: Any


def _shapes(settings: Settings) -> _Shapes:
    big = settings.max_coordinate
    Coord = Annotated[float, Field(ge=-big, le=big, allow_inf_nan=False)]
    Vec2 = Annotated[list[Coord], Field(min_length=2, max_length=2, description="[x, y]")]
    Ring = Annotated[
        list[Vec2],
        Field(min_length=3, max_length=settings.max_outline_vertices, description="vertices"),
    ]
    return _Shapes(
        Vec2=Vec2,
        Direction=Annotated[
            list[Coord],
            Field(
                min_length=2,
                max_length=2,
                description="[x, y], not both zero; normalized by the service",
                json_schema_extra=NOT_ZERO,
            ),
        ],
        Ring=Ring,
        Holes=Annotated[list[Ring], Field(max_length=settings.max_holes)],
        NormalZ=Annotated[
            list[Annotated[float, Field(ge=-1, le=1)]],
            Field(max_length=settings.max_outline_vertices * (1 + settings.max_holes)),
        ],
        Name=Annotated[str, Field(min_length=1, max_length=200, pattern=NAME_PATTERN)],
        Length=Annotated[float, Field(gt=0, le=4 * big, allow_inf_nan=False)],
        Coord=Coord,
    )


def _object_in(settings: Settings, t: _Shapes) -> type[BaseModel]:
    class SliceIn(BaseModel):
        """The stable pose's outline at one probing height above the table."""

        model_config = ConfigDict(extra="forbid", title="SliceIn")
        height: t.Coord
        outline: t.Ring
        holes: t.Holes = Field(default_factory=list)
        normal_z: t.NormalZ | None = None

    class StablePoseIn(BaseModel):
        """One stable pose: an `outline` (with holes), or `slices` at several probing
        heights (DESIGN §4.13), the first at the default height; at most
        `max_pose_faces` faces in all."""

        model_config = ConfigDict(
            extra="forbid", title="StablePoseIn", json_schema_extra=ONE_POSE_FORM
        )
        outline: t.Ring | None = None
        holes: t.Holes = Field(default_factory=list)
        probability: Annotated[float, Field(gt=0, le=1)] = 1.0
        normal_z: t.NormalZ | None = None
        slices: (
            Annotated[list[SliceIn], Field(min_length=1, max_length=settings.max_slices)] | None
        ) = None

        @model_validator(mode="after")
        def _one_form(self) -> Any:
            if (self.outline is None) == (self.slices is None):
                raise ValueError("give exactly one of 'outline' or 'slices'")
            if self.slices is not None and (self.holes or self.normal_z is not None):
                raise ValueError("with 'slices', 'holes' and 'normal_z' go in each slice")
            layers = self.slices or [self]
            faces = sum(len(s.outline or ()) + sum(map(len, s.holes)) for s in layers)
            if faces > settings.max_pose_faces:
                raise ValueError(
                    f"{faces} faces in all exceed max_pose_faces ({settings.max_pose_faces})"
                )
            return self

    class ObjectIn(BaseModel):
        """One object in the §8 format: `outline` (one stable pose) or `stable_poses`."""

        model_config = ConfigDict(
            extra="forbid", title="ObjectIn", json_schema_extra={**ONE_SHAPE, **OBJECT_EXAMPLES}
        )
        name: t.Name
        outline: t.Ring | None = None
        holes: t.Holes | None = None
        normal_z: t.NormalZ | None = None
        stable_poses: (
            Annotated[list[StablePoseIn], Field(min_length=1, max_length=settings.max_stable_poses)]
            | None
        ) = None
        prior: Annotated[float, Field(gt=0, le=1e12, allow_inf_nan=False)] | None = None

        _shape = model_validator(mode="before")(only_one_shape)

        def as_dict(self) -> dict[str, Any]:
            return self.model_dump(exclude_none=True)

    return ObjectIn


def _strategy_in(settings: Settings) -> type[BaseModel]:
    class StrategyIn(BaseModel):
        model_config = ConfigDict(extra="forbid", title="StrategyIn")
        name: StrategyName = settings.default_strategy  # type: ignore[assignment]
        depth: Annotated[int, Field(ge=1, le=settings.max_lookahead_depth)] = min(
            2, settings.max_lookahead_depth
        )
        budget_ms: Annotated[float, Field(gt=0, le=settings.max_plan_budget_ms)] = Field(
            settings.default_budget_ms,
            description="a wall-clock cap on the plan, a safety net: when it bites the plan "
            "says stopped_by 'time' and may differ from run to run",
        )
        budget_work: Annotated[float, Field(gt=0, le=settings.max_plan_budget_work)] = Field(
            settings.default_budget_work,
            description="the work a plan may do, in units of about a microsecond on the "
            "reference machine (outcome cells, search nodes, recognition updates): the plan "
            "is the same on any machine under any load",
        )
        max_paths: Annotated[int, Field(ge=1, le=settings.max_plan_paths)] = min(
            5, settings.max_plan_paths
        )
        motion_weight: Annotated[float, Field(ge=0, le=1e6)] = 0.0
        grid_size: Annotated[int, Field(ge=10, le=200)] = 70
        forecast: Annotated[int, Field(ge=0, le=settings.max_plan_paths)] = Field(
            1,
            description="how many of the ranked paths get p_forecast (the recognition's "
            "own forecast, one observation update per class each); 0: none, faster plans",
        )
        simulations: Annotated[int, Field(ge=1, le=settings.max_simulations)] = Field(
            min(1000, settings.max_simulations),
            description="the pomcp strategy's Monte-Carlo simulations per plan (the work "
            "budget may stop it sooner); other strategies ignore it",
        )
        seed: Annotated[int, Field(ge=0, le=2**63 - 1)] | None = Field(
            None,
            description=(
                "seeds the planner's random choices: the plan at session version v draws "
                "from numpy's default_rng([seed, v]); null: a seed drawn from the session id"
            ),
        )

    return StrategyIn


def _session_create(
    settings: Settings, t: _Shapes, ObjectIn: type[BaseModel], StrategyIn: type[BaseModel]
) -> type[BaseModel]:
    big = settings.max_coordinate

    class SensorIn(BaseModel):
        """Bounded sensor errors: contact position (length) and normal angle (radians).
        With a ball tip, `tip_radius` (length): each contact reported is the ball's
        centre and `position_error` bounds that centre (DESIGN §4.14)."""

        model_config = ConfigDict(extra="forbid", title="SensorIn")
        position_error: Annotated[float, Field(ge=0, le=big)] = 0.0
        normal_error: Annotated[float, Field(ge=0, lt=MAX_NORMAL_ERROR)] = 0.0
        tip_radius: Annotated[
            float, Field(ge=0, le=big, description="ball tip radius (length)")
        ] = 0.0

    class WorkspaceIn(BaseModel):
        """The safe circle: known to contain the object; paths start on it."""

        model_config = ConfigDict(extra="forbid", title="WorkspaceIn")
        center: t.Vec2 = Field(default_factory=lambda: [0.0, 0.0])
        radius: Annotated[float, Field(gt=0, le=big)] = 200.0

    class AccuracyIn(BaseModel):
        """What `localized` requires: the pose's translation bound (length) and
        rotation bound (radians) at most these. Default: 5 position errors plus 2% of
        the largest object's diameter, and twice the normal error plus 0.02 rad."""

        model_config = ConfigDict(extra="forbid", title="AccuracyIn")
        translation: Annotated[float, Field(gt=0, le=big)]
        rotation: Annotated[float, Field(gt=0, le=math.pi)]

    class RegionIn(BaseModel):
        """The object's area centroid lies within `radius` of `center` (world frame)."""

        model_config = ConfigDict(extra="forbid", title="RegionIn")
        center: t.Vec2
        radius: Annotated[float, Field(gt=0, le=big)]

    class PriorIn(BaseModel):
        """A rough pose known beforehand: a region for the object's centroid and/or a
        rotation range [lo, hi] (radians, lo <= hi <= lo + 2 pi)."""

        model_config = ConfigDict(extra="forbid", title="PriorIn")
        region: RegionIn | None = None
        theta: (
            Annotated[
                list[Annotated[float, Field(ge=-100.0, le=100.0, allow_inf_nan=False)]],
                Field(min_length=2, max_length=2),
            ]
            | None
        ) = None

    ObjectRef = Annotated[
        Annotated[t.Name, Tag("object-name")] | Annotated[ObjectIn, Tag("inline-object")],
        Discriminator(_object_or_name),
    ]

    class SessionCreate(BaseModel):
        """A new session: its object set (registered names or inline §8 objects), sensor
        bounds, safe circle, the sensor's place on it, strategy and allowed outliers."""

        model_config = ConfigDict(
            extra="forbid", title="SessionCreate", json_schema_extra=SESSION_EXAMPLES
        )
        objects: Annotated[
            list[ObjectRef], Field(min_length=1, max_length=settings.max_objects_per_session)
        ]
        sensor: SensorIn = Field(default_factory=SensorIn)
        workspace: WorkspaceIn = Field(default_factory=WorkspaceIn)
        sensor_position: t.Vec2 | None = Field(
            None, description="default: the point of the safe circle on its +x axis"
        )
        strategy: StrategyIn = Field(default_factory=StrategyIn)
        max_outliers: Annotated[int, Field(ge=0, le=settings.max_outliers)] = 0
        accuracy: AccuracyIn | None = Field(
            None, description="what `localized` requires; default fitted to the sensor"
        )
        prior: PriorIn | None = Field(
            None,
            description="what is known of the pose before touching (a fixture, a camera, "
            "the previous part): no hypothesis outside it is considered, and the first "
            "probe aims at its region",
        )

    return SessionCreate


def _observation_in(t: _Shapes) -> type[BaseModel]:
    class PathIn(BaseModel):
        model_config = ConfigDict(extra="forbid", title="PathIn")
        origin: t.Vec2
        direction: t.Direction
        length: t.Length
        height: t.Coord | None = Field(
            None,
            description="probing height above the table, one the objects have slices at "
            "(the plan's path says which); null: the default height",
        )

    class ContactIn(BaseModel):
        model_config = ConfigDict(extra="forbid", title="ContactIn")
        point: t.Vec2
        normal: t.Direction = Field(description="the measured outward normal, not both zero")
        normal_z: Annotated[float, Field(ge=-1, le=1)] | None = None

    class ObservationIn(BaseModel):
        """One executed sensing path and what it touched (`contact` null: nothing)."""

        model_config = ConfigDict(
            extra="forbid", title="ObservationIn", json_schema_extra=OBSERVATION_EXAMPLES
        )
        path: PathIn
        contact: ContactIn | None = None

    return ObservationIn


def input_models(settings: Settings) -> InputModels:
    """Build the request models with the limits of `settings`."""
    t = _shapes(settings)
    ObjectIn = _object_in(settings, t)
    SessionCreate = _session_create(settings, t, ObjectIn, _strategy_in(settings))
    return InputModels(
        ObjectIn=ObjectIn, SessionCreate=SessionCreate, ObservationIn=_observation_in(t)
    )
