"""The answers about what to do next and what was done: the plan (GET .../plan) and
the session's report (GET .../report.json); plain module-level models, as in
:mod:`app.schemas`, whose shared parts they use."""

from typing import Literal

from pydantic import BaseModel, Field

from app.schemas import (
    AccuracyOut,
    PathOut,
    PoseOut,
    SensorOut,
    Status,
    Vec2Out,
)

__all__ = [
    "ObjectCreated",
    "ObjectList",
    "ObjectOut",
    "PlanOut",
    "PlannedPathOut",
    "ReportBoundOut",
    "ReportContactOut",
    "ReportOut",
    "ReportResultOut",
    "ReportTouchOut",
    "SliceOut",
    "StablePoseOut",
    "ViewLinkOut",
]


class ReportContactOut(BaseModel):
    point: Vec2Out
    normal: Vec2Out = Field(description="measured outward unit normal")


class ReportTouchOut(BaseModel):
    """One touch with its residuals against the most probable hypothesis."""

    index: int = Field(ge=0)
    kind: Literal["contact", "spurious", "miss"] = Field(
        description="a contact on a face of the answer, a contact the answer calls "
        "spurious, or a path that touched nothing"
    )
    path: PathOut
    contact: ReportContactOut | None
    face: int | None = Field(description="the answer's face the contact lies on")
    distance: float | None = Field(description="length from the contact point to that posed face")
    normal_angle: float | None = Field(
        description="radians from the posed face's outward normal to the measured one, "
        "counter-clockwise positive"
    )
    clearance: float | None = Field(
        description="a miss: how far the path passed from the answer's posed outline"
    )


class ReportBoundOut(BaseModel):
    translation: float | None
    rotation: float | None = Field(description="radians")
    eps_t: float | None = Field(description="error disk diameter")


class ReportResultOut(BaseModel):
    """The answer: the most probable hypothesis, its class' probability and bound."""

    object: str
    stable_pose: int = Field(ge=0)
    pose: PoseOut
    bound: ReportBoundOut = Field(description="the bound `localized` is judged on")
    probability: float = Field(ge=0, le=1)
    class_probability: float = Field(ge=0, le=1)
    classes: int = Field(ge=0, description="equivalence classes left")
    missing: list[Literal["one_class", "accuracy"]]


class ReportOut(BaseModel):
    """A session's report: each touch with its residuals, the answer with its bound,
    probability and status (report.csv has the same in rows)."""

    id: str
    version: int = Field(ge=1)
    status: Status
    objects: list[str]
    sensor: SensorOut
    accuracy: AccuracyOut
    touches: list[ReportTouchOut]
    result: ReportResultOut | None = Field(description="null without a hypothesis")


class PlannedPathOut(BaseModel):
    origin: Vec2Out
    direction: Vec2Out
    length: float
    aim: Vec2Out
    family: str = Field(
        description="distinguishing, informative, partial, uninformative, or refining "
        "(offered only when no path is informative: it shrinks the error disks)"
    )
    p_distinguishing: float
    p_informative: float
    expected_pruning: float
    expected_remaining: float | None = Field(
        description="expected touches still needed when taking this path (itself included), "
        "as the plan's search values it: not calibrated, values above two or three "
        "overstate the touches taken (README, Calibration)"
    )
    motion_cost: float | None
    source: str | None = None
    expected_eps_t: float | None = Field(
        default=None,
        description="refining paths: the probability-weighted error-disk diameter "
        "expected after the touch (length)",
    )
    p_forecast: float | None = Field(
        default=None,
        description="P(DM) as the recognition itself would judge the touch (each "
        "class' predicted outcome observed); set on the first `strategy.forecast` "
        "paths, None elsewhere. p_distinguishing is the outcome model's worst-case "
        "value: sure where it says 1, lower than what happens elsewhere",
    )
    scored_by: Literal["outcome_model", "recognition"] = Field(
        default="outcome_model",
        description="which model ranked the path: the worst-case outcome model (its "
        "p_distinguishing = 1 is a certificate), or, when that model calls nothing "
        "informative, the recognition's own predictions (p_forecast)",
    )
    height: float | None = Field(
        default=None,
        description="the probing height to run the path at (null: the default height); "
        "the observation's path carries it back",
    )


class PlanOut(BaseModel):
    status: Status
    truncated: bool
    elapsed_ms: float
    paths: list[PlannedPathOut]
    strategy: str
    note: str | None = None
    candidates: int = 0
    classes: int = 0
    work: float = Field(0.0, description="units of work the plan spent")
    stopped_by: Literal["work", "time"] | None = Field(
        None,
        description="what ended the plan early: its work budget (deterministic) or the "
        "wall-clock cap budget_ms; null: it finished",
    )
    version: int = Field(ge=1, description="session version the plan was made for")


class ViewLinkOut(BaseModel):
    """A link to one session's viewer that works without the API key until it expires."""

    url: str = Field(description="the page, with its token (relative to the service)")
    token: str = Field(description="opens the page's reads of this session only")
    expires_at: float = Field(description="Unix time after which the link is refused")


class ObjectCreated(BaseModel):
    name: str


class SliceOut(BaseModel):
    height: float
    outline: list[Vec2Out]
    holes: list[list[Vec2Out]] | None = None
    normal_z: list[float] | None = None


class StablePoseOut(BaseModel):
    """One stable pose: its `outline` (with holes), or its `slices` at several
    probing heights, the first at the default height."""

    outline: list[Vec2Out] | None = None
    holes: list[list[Vec2Out]] | None = None
    probability: float
    normal_z: list[float] | None = None
    slices: list[SliceOut] | None = None


class ObjectOut(BaseModel):
    """An object in the §8 format (always the ``stable_poses`` form)."""

    name: str
    stable_poses: list[StablePoseOut]
    prior: float | None = None


class ObjectList(BaseModel):
    """A §8 object file: every registered object, by name."""

    objects: list[ObjectOut]
