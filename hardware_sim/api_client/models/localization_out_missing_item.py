from enum import StrEnum

class LocalizationOutMissingItem(StrEnum):
    ACCURACY = "accuracy"
    ONE_CLASS = "one_class"

    def __str__(self) -> str:
        return str(self.value)
