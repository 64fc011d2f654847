from enum import StrEnum

class StrategyInName(StrEnum):
    EC2 = "ec2"
    INFOGAIN = "infogain"
    LOOKAHEAD = "lookahead"
    OPTIMAL = "optimal"
    PDM = "pdm"
    POMCP = "pomcp"
    PRUNING = "pruning"
    RANDOM = "random"
    THESIS = "thesis"

    def __str__(self) -> str:
        return str(self.value)
