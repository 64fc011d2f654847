from enum import StrEnum

class ReportTouchOutKind(StrEnum):
    CONTACT = "contact"
    MISS = "miss"
    SPURIOUS = "spurious"

    def __str__(self) -> str:
        return str(self.value)
