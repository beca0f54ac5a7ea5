"""The model against the measurements: residual diagnostics and the ranking of what is missing,
model comparison and choice, the loop's next effect, agreement between campaigns and their joint fit,
the linear model's validity, and the GO/NO-GO verdict. Its entry points, below, are imported when first
asked for (`gyrocal.exports`); ``from gyrocal.criticism import diagnostics`` gives the module."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"diagnose": "diagnostics", "rank": "diagnostics", "compare": "comparison",
                 "reviewed_model": "modelchoice", "next_effect": "extension", "compare_files": "agreement",
                 "joint_fit": "joint"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
