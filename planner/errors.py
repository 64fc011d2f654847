"""One exception tree for the planner; `app/` maps it to HTTP status codes.

Every error names the field or the problem so that a caller can fix its input.
"""

from __future__ import annotations

__all__ = [
    "InvalidModelError",
    "InvalidObservationError",
    "ModelFileError",
    "PlannerError",
    "PlanningNotPossibleError",
]


class PlannerError(Exception):
    """Base class of every error the planner raises on purpose.

    `field` names the offending input (a dotted path such as
    ``objects[0].stable_poses[1].outline``) when there is one.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.field = field

    def __str__(self) -> str:
        return f"{self.field}: {self.message}" if self.field else self.message


class InvalidModelError(PlannerError):
    """An object model is malformed (bow-tie outline, too few vertices, ...)."""


class ModelFileError(PlannerError):
    """An object file cannot be read or does not follow the object file format."""


class InvalidObservationError(PlannerError):
    """An observation is malformed (zero direction, NaN, negative length, ...)."""


class PlanningNotPossibleError(PlannerError):
    """Planning was asked of a session where no path is needed or none can help."""
