"""The physics, declared once: units, the channel model (eq. 3), attitude kinematics, the effect
library, a model's specification, what the data resolve, the channel sets' non-orthogonality and the
correction to uplink. Pure functions on arrays. Its entry points, below, are imported when first asked
for (`gyrocal.exports`); a plugin imports `Effect` and `Parameter` from `gyrocal.effects`."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"ModelSpec": "spec", "resolve": "effects", "ChannelParams": "channels", "propagate": "kinematics",
                 "campaign_correction": "correction"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
