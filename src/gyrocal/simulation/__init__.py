"""A Mars-Orbiter-like spacecraft simulated from a scenario: the truth, telemetry and campaign files.
Its entry points, below, are imported when first asked for (`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"run": "simulate", "truth_parameters": "simulate"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
