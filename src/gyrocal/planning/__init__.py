"""Before flying: what a planned campaign will tell (Cramér-Rao bounds, detection) and a gyro's
noise from a static recording (Allan deviation). Its entry points, below, are imported when first asked
for (`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"Plan": "plan", "crlb_sd": "plan", "static_report": "allan"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
