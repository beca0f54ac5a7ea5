"""The physics, declared once: units, the channel model (eq. 3), attitude kinematics, the effect
library, a model's specification and the correction to uplink. Pure functions on arrays."""

__all__ = ["channels", "combinations", "correction", "effects", "kinematics", "spec", "units"]
