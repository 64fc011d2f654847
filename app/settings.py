"""Service settings (DESIGN §6): read from the environment with the prefix ``TACTILE_``.

Every limit the service enforces is a setting here; :func:`app.main.create_app`
takes a :class:`Settings` instance (never a module global), so tests and
``tactile serve`` build apps with their own.

>>> Settings(db_path="/tmp/x.db", max_objects_per_session=4).max_objects_per_session
4
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import Field, SecretStr, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from planner.planning.config import DEFAULT_WORK

__all__ = ["Settings"]


class Settings(BaseSettings):
    """One service instance's configuration (env ``TACTILE_DB_PATH``, ``TACTILE_API_KEY``...)."""

    model_config = SettingsConfigDict(env_prefix="TACTILE_", extra="ignore", frozen=True)

    # storage
    db: str | None = Field(
        None,
        description="the database: a postgresql:// URL or a SQLite file path (env TACTILE_DB);"
        " None: db_path",
    )
    db_path: Path = Field(Path("tactile.db"), description="SQLite file (never ':memory:')")
    busy_timeout_ms: int = Field(5000, ge=0, le=600_000)
    sqlite_synchronous: Literal["NORMAL", "FULL", "EXTRA"] = "FULL"
    db_pool_size: int = Field(4, ge=1, le=64, description="database connections (and DB threads)")
    session_cache_size: int = Field(64, ge=1, le=100_000, description="derived sessions kept")
    plan_cache_size: int = Field(64, ge=1, le=100_000)

    # CPU work
    cpu_workers: int = Field(2, ge=1, le=256, description="fits and plans running at once")
    max_cpu_queue: int = Field(
        64,
        ge=0,
        le=1_000_000,
        description="fits and plans that may wait for a CPU worker; more are answered 503 "
        "with Retry-After (back-pressure instead of an ever longer wait)",
    )
    cpu_job_deadline_s: float | None = Field(
        20.0,
        gt=0,
        le=3600,
        description="a fit, plan or picture still running after this long is stopped and "
        "answered 503 with Retry-After (null: never); above max_plan_budget_ms, which "
        "plans keep to themselves",
    )
    limit_concurrency: int | None = Field(
        512, ge=1, le=1_000_000, description="connections uvicorn serves at once; more get 503"
    )

    # request limits
    max_body_bytes: int = Field(1_000_000, ge=1024, le=1_000_000_000)
    max_outline_vertices: int = Field(
        10_000, ge=3, le=100_000, description="vertices of one ring as given"
    )
    max_worked_vertices: int = Field(
        500,
        ge=3,
        le=100_000,
        description="vertices of one ring a session works with: after a finely drawn "
        "outline is simplified within the session's sensor bounds",
    )
    max_holes: int = Field(16, ge=0, le=10_000)
    max_stable_poses: int = Field(32, ge=1, le=10_000)
    max_slices: int = Field(8, ge=1, le=1_000, description="probing heights per stable pose")
    max_pose_faces: int = Field(
        8_500, ge=3, le=10_000_000, description="faces of one stable pose, every slice and hole"
    )
    max_objects_per_session: int = Field(16, ge=1, le=10_000)
    max_observations_per_session: int = Field(100, ge=1, le=100_000)
    max_outliers: int = Field(3, ge=0, le=100)
    max_mesh_triangles: int = Field(50_000, ge=4, le=10_000_000, description="per upload")
    max_hull_faces: int = Field(
        2_000, ge=4, le=1_000_000, description="convex hull faces of an uploaded mesh"
    )
    max_sliced_poses: int = Field(
        128, ge=1, le=100_000, description="most probable stable poses of a mesh sliced"
    )
    max_memory_bytes: int | None = Field(
        2 * 2**30,
        ge=2**28,
        description="heap and anonymous memory per server process (set by `tactile serve`); "
        "an allocation past it fails its request with 503. None: no cap",
    )
    max_hypotheses: int = Field(
        10_000, ge=1, le=10_000_000, description="hypotheses an observation may leave"
    )
    max_interpretation_work: int = Field(
        1_000_000,
        ge=1,
        le=10_000_000_000,
        description="interpretations an observation leaves to check, times (contacts + "
        "slide samples): known from the interpretation tree before any is checked, "
        "about 5-10 microseconds a unit",
    )
    max_plan_budget_ms: float = Field(10_000.0, gt=0, le=3_600_000)
    max_plan_budget_work: float = Field(
        10_000_000.0, gt=0, le=1e12, description="units of planning work (~us on the reference)"
    )
    max_lookahead_depth: int = Field(4, ge=1, le=64)
    max_plan_paths: int = Field(50, ge=1, le=10_000)
    max_simulations: int = Field(20_000, ge=1, le=10_000_000)
    max_coordinate: float = Field(1e6, gt=0, le=1e12, description="|x|, |y| and lengths")
    max_image_dpi: int = Field(300, ge=10, le=1200)
    max_list_objects: int = Field(1000, ge=1, le=1_000_000)

    # defaults of a new session
    default_strategy: str = "lookahead"
    default_budget_ms: float = Field(1500.0, gt=0, description="the wall-clock cap of a plan")
    default_budget_work: float = Field(DEFAULT_WORK, gt=0, description="a plan's work budget")

    # access and logs
    api_key: SecretStr | None = Field(
        None, description="one bearer token for all clients (the unnamed client)"
    )
    api_keys: dict[str, SecretStr] | None = Field(
        None,
        description="per-client bearer tokens, client name -> key (env TACTILE_API_KEYS, "
        "JSON); each client sees only the sessions and objects it created",
    )
    api_keys_file: Path | None = Field(
        None, description="a JSON file {client: key} of more per-client keys"
    )
    view_link_ttl_s: float = Field(
        3600.0, gt=0, le=30 * 24 * 3600, description="how long a viewer link works"
    )
    open_access: bool = Field(
        False, description="let `tactile serve` bind a non-loopback address without a key"
    )
    public_docs: bool = Field(
        False, description="/docs, /redoc, /openapi.json and /metrics open without the key"
    )
    allowed_hosts: list[str] | None = Field(
        None,
        description='Host header names answered ("*": any); others get 400. None: any, '
        "except that `tactile serve` bound to a loopback address answers only loopback names",
    )
    log_level: Literal["debug", "info", "warning", "error"] = "info"
    log_json: bool = True
    idempotency_ttl_s: float = Field(7 * 24 * 3600.0, gt=0)
    session_ttl_s: float | None = Field(
        30 * 24 * 3600.0, gt=0, description="sessions idle this long are deleted; None: kept"
    )
    retention_interval_s: float = Field(
        3600.0, gt=0, description="how often expired records and sessions are purged"
    )

    @field_validator("db_path")
    @classmethod
    def _not_in_memory(cls, value: Path) -> Path:
        if str(value).strip() in ("", ":memory:") or str(value).startswith("file::memory:"):
            raise ValueError("an in-memory database is not shared between threads; give a file")
        return value

    @field_validator("db")
    @classmethod
    def _database(cls, value: str | None) -> str | None:
        if value is not None:
            from app.store_types import database_url

            database_url(value)  # a URL of a supported backend, or a file path
        return value

    @property
    def keyed(self) -> bool:
        """Whether requests need a key (any of api_key, api_keys, api_keys_file is set)."""
        return bool(self.api_key or self.api_keys or self.api_keys_file)

    @property
    def database(self) -> str:
        """The store's target: `db` when set, else the SQLite file `db_path`."""
        return self.db if self.db is not None else str(self.db_path)

    @model_validator(mode="after")
    def _defaults_within_limits(self) -> Settings:
        from planner.planning.config import STRATEGIES

        if self.default_strategy not in STRATEGIES:
            raise ValueError(f"default_strategy must be one of {list(STRATEGIES)}")
        if self.default_budget_ms > self.max_plan_budget_ms:
            raise ValueError("default_budget_ms must not exceed max_plan_budget_ms")
        if self.default_budget_work > self.max_plan_budget_work:
            raise ValueError("default_budget_work must not exceed max_plan_budget_work")
        if self.cpu_job_deadline_s is not None and (
            self.cpu_job_deadline_s * 1000 <= self.max_plan_budget_ms
        ):
            raise ValueError("cpu_job_deadline_s must exceed max_plan_budget_ms")
        return self
