from enum import StrEnum

class PlanOutStoppedByType0(StrEnum):
    TIME = "time"
    WORK = "work"

    def __str__(self) -> str:
        return str(self.value)
