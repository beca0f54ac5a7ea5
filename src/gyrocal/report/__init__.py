"""What a reviewer reads: the pre-uplink HTML report, its figures and the fleet summary. It renders
findings and decides nothing. Its entry points, below, are imported when first asked for
(`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"build_context": "review", "render": "review", "ReviewInputs": "context"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
