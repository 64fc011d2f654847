from enum import StrEnum

class ReportOutStatus(StrEnum):
    AMBIGUOUS = "ambiguous"
    AWAITING_CONTACT = "awaiting_contact"
    INCONSISTENT = "inconsistent"
    LOCALIZED = "localized"

    def __str__(self) -> str:
        return str(self.value)
