"""Studies of many runs: the Table 1 validation, the accuracy-cost study, process launching."""

__all__ = ["validate", "accuracy_cost", "processes"]
