"""The model against the measurements: residual diagnostics, model comparison and choice,
agreement between campaigns, the linear model's validity, and the GO/NO-GO verdict."""

__all__ = ["agreement", "comparison", "diagnostics", "linearity", "modelchoice", "verdict"]
