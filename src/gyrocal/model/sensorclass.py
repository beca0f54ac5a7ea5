"""Default priors by the gyro's sensor class, declared once.

The effects' `Parameter` declarations are a DTG's (the paper's Mars Orbiter Mission gyros):
the class ``dtg``, and the default where ``campaign.yaml`` declares no ``gyro.sensor_class``, so
that a campaign that declares nothing keeps its numbers. A MEMS triad's residual scale factor,
misalignment and bias drift are an order of magnitude larger than a DTG's, a fibre-optic or ring
laser gyro's smaller: each class here replaces the declared prior sd and bound of the parameters
it names (in the unit the effect declares), and the config's ``priors:`` still overrides both.
"""

__all__ = ["DEFAULT_SENSOR_CLASS", "SENSOR_CLASSES", "class_priors"]

DEFAULT_SENSOR_CLASS = "dtg"
"""The class of a campaign that declares none: the effects' declarations as they are."""

SENSOR_CLASSES = {
    "dtg": {},
    "mems": {("scale_factor", "sf_pos"): (10000.0, 50000.0), ("scale_factor", "sf_neg"): (10000.0, 50000.0),
             ("misalignment", "mis_roll"): (2000.0, 3600.0), ("misalignment", "mis_pitch"): (2000.0, 3600.0),
             ("misalignment", "mis_yaw"): (2000.0, 3600.0), ("bias_drift", "bias_drift"): (10.0, 1000.0)},
    "fog": {("scale_factor", "sf_pos"): (1000.0, 10000.0), ("scale_factor", "sf_neg"): (1000.0, 10000.0),
            ("misalignment", "mis_roll"): (600.0, 3600.0), ("misalignment", "mis_pitch"): (600.0, 3600.0),
            ("misalignment", "mis_yaw"): (600.0, 3600.0), ("bias_drift", "bias_drift"): (0.1, 10.0)},
    "rlg": {("scale_factor", "sf_pos"): (500.0, 5000.0), ("scale_factor", "sf_neg"): (500.0, 5000.0),
            ("misalignment", "mis_roll"): (600.0, 3600.0), ("misalignment", "mis_pitch"): (600.0, 3600.0),
            ("misalignment", "mis_yaw"): (600.0, 3600.0), ("bias_drift", "bias_drift"): (0.1, 10.0)},
}
"""class -> {(effect, parameter): (prior sd, bound)} in the effect's declared unit (ppm, arcsec,
deg/h/h); a parameter a class does not name keeps its declaration. Orders of magnitude of the
residuals left after a ground calibration: MEMS scale factor about 1 %, misalignment about half a
degree (the misalignment bound stays 3600 arcsec, as far as the small-angle model of eq. 3 and the
mounting rule carry), drift up to tens of deg/h/h; FOG and RLG scale factors of 100-1000 ppm."""


def class_priors(sensor_class: str | None) -> dict:
    """``{(effect, parameter): {"prior_sd": sd, "bound": bound}}`` of a class (None: the default)."""
    name = sensor_class or DEFAULT_SENSOR_CLASS
    if name not in SENSOR_CLASSES:
        raise ValueError(f"unknown sensor class {name!r}; known: {sorted(SENSOR_CLASSES)}")
    return {key: {"prior_sd": sd, "bound": bound} for key, (sd, bound) in SENSOR_CLASSES[name].items()}
