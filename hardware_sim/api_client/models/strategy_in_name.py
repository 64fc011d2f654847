from enum import StrEnum

class StrategyInName(StrEnum):
    LOOKAHEAD = "lookahead"
    OPTIMAL = "optimal"
    PDM = "pdm"
    PRUNING = "pruning"
    RANDOM = "random"
    THESIS = "thesis"

    def __str__(self) -> str:
        return str(self.value)
