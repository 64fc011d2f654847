from enum import StrEnum

class ReportResultOutMissingItem(StrEnum):
    ACCURACY = "accuracy"
    ONE_CLASS = "one_class"

    def __str__(self) -> str:
        return str(self.value)
