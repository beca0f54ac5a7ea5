"""The pipeline: one function per step, the paths of a run, the fleet and the ``gyrocal`` command.
Only this package (and the study above it) reads and writes files by step; the library below never imports it.
Its entry points, below, are imported when first asked for (`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"run_campaign": "run", "main": "cli", "CampaignPaths": "paths", "ModelPaths": "paths"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
