from enum import StrEnum

class PlannedPathOutScoredBy(StrEnum):
    OUTCOME_MODEL = "outcome_model"
    RECOGNITION = "recognition"

    def __str__(self) -> str:
        return str(self.value)
