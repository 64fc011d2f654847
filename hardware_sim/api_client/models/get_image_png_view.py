from enum import StrEnum

class GetImagePngView(StrEnum):
    BOTH = "both"
    GRID = "grid"
    VECTOR = "vector"

    def __str__(self) -> str:
        return str(self.value)
