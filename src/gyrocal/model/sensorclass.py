"""The gyro's sensor class, declared once: its physical limits and its default priors.

The effects' `Parameter` declarations are a DTG's (the paper's Mars Orbiter Mission gyros):
the class ``dtg``, and the default where ``campaign.yaml`` declares no ``gyro.sensor_class``, so
that a campaign that declares nothing keeps its numbers. A MEMS triad's residual scale factor,
misalignment and bias drift are an order of magnitude larger than a DTG's, a fibre-optic or ring
laser gyro's smaller. Each class (`SensorClass`) declares

- its physical limits: the largest residual scale factor and misalignment the physics checks
  (`gyrocal.checks`) accept before they look for a unit slip or a wrong column, and which bound
  the priors; the largest bias, the range of angle random walks and the largest rate a part of
  the class has;
- the prior sd of the parameters it names (in the unit the effect declares), which replace the
  declared ones; the config's ``priors:`` still override both.

The limits, and where their figures come from (data sheets of typical parts, as quoted below;
check your own part's; the verdict's physical-bounds check takes the last column and the
misalignment bound, unless the config's ``report.physical_bound_<unit>`` sets one):

| class | scale factor bound | misalignment bound | bias | ARW, deg/rt h | max rate | GO's scale factor bound |
| --- | --- | --- | --- | --- | --- | --- |
| `dtg` | 3 % (declared) | 1 deg (declared) | 10 deg/h (*) | 0.001-0.01 (*) | 100 deg/s (*) | 2 % |
| `mems` | 5 % | 1 deg | 20 deg/s | 0.1-1 | 2000 deg/s | 5 % |
| `fog` | 1 % | 1 deg | 10 deg/h | 0.01-0.1 | 1000 deg/s | 1 % |
| `rlg` | 0.5 % | 1 deg | 10 deg/h | 0.002-0.3 | 1000 deg/s | 0.5 % |

- `dtg`: the paper's Mars Orbiter Mission gyros, as the effects declare them (scale factor
  30000 ppm, misalignment 3600 arcsec); the paper's scenario has an ARW of 0.003 deg/rt h
  (``config/scenarios/mom.yaml``).
- `mems`: sensitivity +/-1-3 % at 25 C and +/-2 % more over temperature, so a 5 % bound;
  cross-axis sensitivity +/-1-2 %, misalignment after mounting 0.1-1 deg; zero-rate offset
  +/-3-20 deg/s; noise 0.005-0.015 deg/s/rt Hz (0.3-0.9 deg/rt h); range +/-2000 deg/s. Parts:
  InvenSense MPU-6050 (sensitivity +/-3 %, +/-2 % over temperature, cross-axis +/-2 %, offset
  +/-20 deg/s, 0.005 deg/s/rt Hz, +/-2000 deg/s); Bosch BMI160 (sensitivity +/-1 %, offset
  +/-3 deg/s, 0.007 deg/s/rt Hz, +/-2000 deg/s); Analog Devices ADIS16470 (misalignment
  +/-0.25 deg, 0.34 deg/rt h, +/-2000 deg/s).
- `fog`: scale-factor stability tens to 100 ppm, bias 0.05-10 deg/h, 0.01-0.1 deg/rt h, up to
  +/-1000 deg/s. Parts: Northrop Grumman LN-200 (scale factor 100 ppm, bias 1-10 deg/h,
  0.04-0.1 deg/rt h, +/-1000 deg/s); KVH DSP-1750 (bias 0.05 deg/h, 0.012 deg/rt h, +/-490 deg/s).
- `rlg`: scale factor 5-150 ppm, bias 0.003-10 deg/h, 0.002-0.3 deg/rt h, +/-1000 deg/s. Parts:
  Honeywell HG1700 (150 ppm, 1 deg/h, 0.125-0.3 deg/rt h, +/-1000 deg/s); Honeywell GG1320AN
  (bias 0.0035 deg/h, 0.0035 deg/rt h).

(*) An order of magnitude for a DTG, not read off a data sheet; no check uses it yet. The
bias, ARW and rate figures are declared for the checks and the planning to come; today the
checks read the scale-factor and misalignment bounds (`gyrocal.checks.sensing.physical_limits`).

The scale-factor bounds of FOG and RLG sit far (tens of times) beyond their data sheets'
stability: a check bound must not refuse a ground calibration's leftover or a launch's shift, only
what no such gyro does (a wrong unit or column, which is 1.7 % or more: deg for rad is 5700 %).
The misalignment bound stays 1 deg (3600 arcsec) for every class, as far as the small-angle model
of eq. 3 and the mounting rule carry.
"""

from dataclasses import dataclass, field

__all__ = ["CLASSES", "DEFAULT_SENSOR_CLASS", "SENSOR_CLASSES", "SensorClass", "class_priors", "limits"]

DEFAULT_SENSOR_CLASS = "dtg"
"""The class of a campaign that declares none: the effects' declarations as they are."""


@dataclass(frozen=True)
class SensorClass:
    """One gyro sensor class: its physical limits and its default priors (the module's table
    gives their sources)."""

    name: str
    what: str
    sf_bound_ppm: float
    """The largest residual scale factor (each direction), in ppm: the physics checks and the prior's bound."""
    mis_bound_arcsec: float
    """The largest misalignment, in arcsec: the physics checks and the prior's bound."""
    bias_bound_deg_h: float
    """The largest bias a part of the class shows (before any calibration), in deg/h."""
    arw_deg_sqrt_h: tuple
    """(lowest, highest) angle random walk of the class's parts, in deg/sqrt(h)."""
    max_rate_deg_s: float
    """The largest rate a part of the class measures, in deg/s (its range; a declared one wins)."""
    prior_sd: dict = field(default_factory=dict)
    """{(effect, parameter): prior sd} in the effect's declared unit; a parameter not named keeps
    its declaration."""
    drift_bound_deg_h_h: float | None = None
    """The bias drift's bound, deg/h/h (None: the declared 100)."""
    go_sf_bound_ppm: float | None = None
    """The largest residual scale factor a GO accepts, in ppm (the verdict's physical-bounds check,
    `gyrocal.criticism.verdict.bounds_check`); None: `sf_bound_ppm`. A DTG's is 2 %, tighter than
    its 3 % check bound: what a calibrated DTG is left with, not what its input may show."""

    def physical_bounds(self) -> dict:
        """``{unit: bound}`` of the channel-model terms a GO accepts (the verdict's ``physical_bound_<unit>``):
        ppm for the scale factors, arcsec for the misalignments."""
        sf = self.sf_bound_ppm if self.go_sf_bound_ppm is None else self.go_sf_bound_ppm
        return {"ppm": float(sf), "arcsec": float(self.mis_bound_arcsec)}

    def priors(self) -> dict:
        """``{(effect, parameter): (prior sd, bound)}``: the prior sds, bounded by the limits."""
        bounds = {"scale_factor": self.sf_bound_ppm, "misalignment": self.mis_bound_arcsec,
                  "bias_drift": self.drift_bound_deg_h_h}
        return {key: (sd, bounds[key[0]]) for key, sd in self.prior_sd.items()}


def _named(sf_sd, mis_sd, drift_sd) -> dict:
    """The prior sds a class sets: scale factor (each direction), misalignment (toward each axis),
    bias drift."""
    return {("scale_factor", "sf_pos"): sf_sd, ("scale_factor", "sf_neg"): sf_sd,
            **{("misalignment", f"mis_{a}"): mis_sd for a in ("roll", "pitch", "yaw")},
            ("bias_drift", "bias_drift"): drift_sd}


CLASSES = {
    "dtg": SensorClass("dtg", "dynamically tuned gyro (the paper's)", 30000.0, 3600.0, 10.0, (0.001, 0.01), 100.0,
                       go_sf_bound_ppm=20000.0),
    "mems": SensorClass("mems", "MEMS vibrating gyro", 50000.0, 3600.0, 72000.0, (0.1, 1.0), 2000.0,
                        _named(10000.0, 2000.0, 10.0), 1000.0),
    "fog": SensorClass("fog", "fibre-optic gyro", 10000.0, 3600.0, 10.0, (0.01, 0.1), 1000.0,
                       _named(1000.0, 600.0, 0.1), 10.0),
    "rlg": SensorClass("rlg", "ring laser gyro", 5000.0, 3600.0, 10.0, (0.002, 0.3), 1000.0,
                       _named(500.0, 600.0, 0.1), 10.0),
}
"""Every class by name. The DTG's limits are the effects' declarations (scale factor 30000 ppm,
misalignment 3600 arcsec), so that it sets no prior."""

SENSOR_CLASSES = {name: c.priors() for name, c in CLASSES.items()}
"""class -> {(effect, parameter): (prior sd, bound)} in the effect's declared unit (ppm, arcsec,
deg/h/h); a parameter a class does not name keeps its declaration. Orders of magnitude of the
residuals left after a ground calibration: MEMS scale factor about 1 %, misalignment about half a
degree, drift up to tens of deg/h/h; FOG and RLG scale factors of 100-1000 ppm."""


def limits(sensor_class: str | None) -> SensorClass:
    """A class by name (None: the default, a DTG)."""
    name = sensor_class or DEFAULT_SENSOR_CLASS
    if name not in CLASSES:
        raise ValueError(f"unknown sensor class {name!r}; known: {sorted(CLASSES)}")
    return CLASSES[name]


def class_priors(sensor_class: str | None) -> dict:
    """``{(effect, parameter): {"prior_sd": sd, "bound": bound}}`` of a class (None: the default)."""
    return {key: {"prior_sd": sd, "bound": bound} for key, (sd, bound) in limits(sensor_class).priors().items()}
