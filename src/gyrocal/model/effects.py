"""The effect library: the physical terms a model is built from.

A model is a named list of effects (docs/interface.md section 6). Each effect says which
parameters it adds and how it changes what the gyro channels put out or what the
star tracker measures; gyrocal turns that into columns of the linear error model, so
an effect costs no code anywhere else. The baseline's own terms (`scale_factor`,
`misalignment`, `bias`) are effects too; their columns come from the exact channel
model (`errormodel`). A user's effect lives in a plugin file (see `load_plugins`).

Writing an effect (the whole API)::

    from gyrocal.model.effects import Effect, Parameter

    class MyEffect(Effect):
        name = "my_effect"                     # what models list in the config
        description = "one line on the physics"
        parameters = (Parameter("k", unit="ppm/K", si_per_unit=1e-6, prior_sd=100.0),)

        def gyro(self, m):                     # m: a ManeuverView
            # d(raw channel increment, rad) / d(parameter, SI): (K, n_channels) per parameter.
            # For a per-channel parameter, column i belongs to channel i's own copy.
            return {"k": (m.extras["temp_dtg1"] - 20.0)[:, None] * m.increments}

        def star_tracker(self, m):             # optional
            # d(star-tracker error in body axes, rad) / d(parameter, SI): (M, 3).
            return {}

    EFFECTS = [MyEffect()]                     # what a plugin file exports
"""

import importlib.util
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gyrocal.errors import InputError
from gyrocal.model.channels import MOVING_RATE_FRACTION
from gyrocal.model.priorfamily import EFFECT_PRIOR_DOF
from gyrocal.model.units import AXES, DEG_H_RAD_S, PPM, STANDARD_GRAVITY_M_S2, arcsec_to_rad

__all__ = [
    "BASELINE", "LIBRARY", "SCALE_FACTORS", "SF_BOUND_PPM", "SF_PRIOR_SD_PPM", "Bias", "BiasDrift", "Effect",
    "GSensitivity", "GravityOffset", "ManeuverView", "Misalignment", "Parameter", "PluginError", "ScaleFactor",
    "ScaleFactorSymmetric", "SfNonlinearity", "StCorrelatedNoise", "StLatency", "check_effect", "known",
    "load_plugins", "resolve"
]


@dataclass(frozen=True)
class Parameter:
    """One parameter an effect adds; values in ``unit`` at the edges, SI inside."""

    name: str
    unit: str
    si_per_unit: float
    prior_sd: float
    """Prior scale in ``unit`` (zero mean unless configured): the standard deviation of a normal
    prior, the scale of a Student-t one (`prior_dof`)."""
    bound: float = np.inf
    """Physical bound on ``|value|`` in ``unit``."""
    per_channel: bool = True
    """One copy per gyro channel (named ``<channel>.<name>``) or one for the campaign
    (named ``<effect>.<name>``)."""
    prior_dof: float = np.inf
    """The prior's family, declared here once (`gyrocal.model.priorfamily`): ``inf``, normal (the
    channel model's terms); finite, Student-t with this many degrees of freedom at scale
    ``prior_sd`` (the library's other effects: `EFFECT_PRIOR_DOF`)."""


class Effect:
    """Base class: override `gyro` and/or `star_tracker`; see the module docstring."""

    name = ""
    description = ""
    parameters: tuple = ()
    core = False
    """Baseline terms whose columns come from the exact channel model."""
    noise = False
    """A noise-model effect: it changes the covariance, not the mean."""
    rate_noise = False
    """A noise-model effect whose variance follows the body rate (`StJitter`), not a correlated one."""
    signature = ""
    """The residual signature whose columns are this effect's own (ranked once, under the effect)."""
    operating_scale = False
    """A scale factor that changes with the rate (`SfNonlinearity`): a linear onboard correction cannot
    follow it, so the uplink takes the scale factor at the campaign's rates (`gyrocal.inference.fit.operating`)."""

    def channel_parameters(self, channel) -> tuple:
        """The per-channel parameters a channel carries (all of them, unless an effect says otherwise)."""
        return tuple(p for p in self.parameters if p.per_channel)

    def gyro(self, m) -> dict:
        return {}

    def star_tracker(self, m) -> dict:
        return {}


class ManeuverView:
    """What an effect may look at in one maneuver (all SI, nominal gyro parameters).

    K gyro intervals, M star-tracker samples, channels in campaign order.
    """

    def __init__(self, data, body_rate_rad_s):
        self.id = data.id
        self.axis = data.axis
        self.channels = data.channels
        self.gyro_time = data.gyro_time
        self.dt = data.dt
        self.t_mid = 0.5 * (data.gyro_time[1:] + data.gyro_time[:-1])
        self.increments = data.increments
        self.rate = data.increments / data.dt[:, None]
        """(K, n_channels) each channel's rate (rad/s)."""
        self.moving = np.abs(self.rate) > MOVING_RATE_FRACTION * np.abs(self.rate).max()
        """(K, n_channels) where a channel turns faster than `MOVING_RATE_FRACTION` of the
        maneuver's peak rate: there the sign of its rate is the rotation's, not the noise's."""
        self.body_rate = body_rate_rad_s
        """(K, 3) body rate from the in-loop set (rad/s)."""
        self.acceleration = np.gradient(body_rate_rad_s, self.t_mid, axis=0)
        self.st_time = data.st_time
        self.st_interval = data.st_interval()[0]
        """(M,) the gyro interval holding each star-tracker sample: ``x[m.st_interval]`` is a
        per-interval quantity ``x`` at the star-tracker samples."""
        self.st_body_rate = body_rate_rad_s[self.st_interval]
        """(M, 3) body rate at the star-tracker samples (rad/s)."""
        self.extras = data.extras
        self.t_center = 0.5 * (data.gyro_time[0] + data.gyro_time[-1])

    def bias_regressor(self, values) -> np.ndarray:
        """(K, n_channels) the increments a bias proportional to ``values`` (K,) adds, the same
        column for every channel's own copy of the parameter."""
        return np.repeat((values * self.dt)[:, None], len(self.channels), axis=1)


SF_PRIOR_SD_PPM = 5000.0
"""The prior sd of every residual scale factor, per direction or symmetric."""
SF_BOUND_PPM = 30000.0
"""The physical bound of every residual scale factor."""


class ScaleFactor(Effect):
    name = "scale_factor"
    description = "residual scale factor of each channel, separately for positive and negative rate (eq. 3)"
    parameters = (Parameter("sf_pos", "ppm", PPM, SF_PRIOR_SD_PPM, SF_BOUND_PPM),
                  Parameter("sf_neg", "ppm", PPM, SF_PRIOR_SD_PPM, SF_BOUND_PPM))
    core = True


class ScaleFactorSymmetric(Effect):
    name = "scale_factor_symmetric"
    description = ("one residual scale factor of each channel for both directions of rate (eq. 3 with "
                   "sf_pos = sf_neg): where the maneuvers cannot resolve the asymmetry")
    parameters = (Parameter("sf", "ppm", PPM, SF_PRIOR_SD_PPM, SF_BOUND_PPM),)
    core = True


class Misalignment(Effect):
    name = "misalignment"
    description = "misalignment of each channel toward the two other body axes (eq. 3)"
    parameters = tuple(Parameter(f"mis_{a}", "arcsec", arcsec_to_rad(1.0), 1000.0, 3600.0) for a in AXES)
    core = True

    def channel_parameters(self, channel) -> tuple:
        """Only toward the other two axes: a channel is not misaligned toward its own."""
        return tuple(p for p in self.parameters if p.name != f"mis_{channel.axis}")


class Bias(Effect):
    name = "bias"
    description = "residual bias of each channel, one per maneuver (a nuisance, integrated out)"
    core = True


class BiasDrift(Effect):
    name = "bias_drift"
    description = "the residual bias ramps linearly in time within a maneuver"
    parameters = (Parameter("bias_drift", "deg/h/h", DEG_H_RAD_S / 3600.0, 0.5, 100.0, prior_dof=EFFECT_PRIOR_DOF),)
    signature = "time"

    def gyro(self, m):
        return {"bias_drift": m.bias_regressor(m.t_mid - m.t_center)}


class SfNonlinearity(Effect):
    name = "sf_nonlinearity"
    description = "the scale factor grows with the square of the channel's rate"
    # Prior sd as wide as the magnitudes a plan with one rate per direction cannot see (MOM: 90 %
    # detection at 57,800): there the data confound it with the scale factor, and the scale
    # factor's interval is only as wide as this prior lets it be (docs/validation.md).
    parameters = (Parameter("sf_quadratic", "ppm/(deg/s)^2", PPM / np.deg2rad(1.0) ** 2, 1e5, 1e6,
                            prior_dof=EFFECT_PRIOR_DOF),)
    signature = "rate_squared"
    operating_scale = True

    def gyro(self, m):
        return {"sf_quadratic": m.rate**2 * m.increments}


class GSensitivity(Effect):
    name = "g_sensitivity"
    description = "a bias that follows the specific force (the accelerometer's acc_x, acc_y, acc_z columns)"
    # A MEMS rate gyro's g-sensitivity is of order 0.01-0.1 deg/s/g; a DTG's mass unbalance, deg/h/g.
    parameters = tuple(Parameter(f"g_{a}", "deg/s/g", np.deg2rad(1.0) / STANDARD_GRAVITY_M_S2, 0.1, 2.0,
                                 prior_dof=EFFECT_PRIOR_DOF)
                       for a in "xyz")

    def gyro(self, m):
        # Extra gyro.csv columns acc_x, acc_y, acc_z: the specific force along body x, y, z (m/s^2).
        return {f"g_{a}": m.bias_regressor(m.extras[f"acc_{a}"]) for a in "xyz"}


class GravityOffset(Effect):
    name = "gravity_offset"
    description = ("an attitude offset between reference and gyros that follows the specific force (acc_x, "
                   "acc_y, acc_z): a mount that gives under gravity, or a reference whose error depends on the pose")
    # About each body axis per the force along the two others: a tilt toward the force. The offset
    # about an axis per the force along it is left out: their equal part is an offset about the
    # force itself, fixed in the room, which each maneuver's initial attitude takes up; their
    # differences can be told apart only by turns about several axes, and were weakly determined
    # on the T-stick trials (sd 800 arcsec/g). The force's mean over a maneuver acts as a common
    # rotation of the triad, which the misalignments also describe: the report's model check
    # names what moves.
    parameters = tuple(Parameter(f"offset_{e}_acc_{a}", "arcsec/g", arcsec_to_rad(1.0) / STANDARD_GRAVITY_M_S2,
                                 3600.0, 36000.0, per_channel=False, prior_dof=EFFECT_PRIOR_DOF)
                       for i, e in enumerate(AXES) for a in "xyz" if a != "xyz"[i])

    def star_tracker(self, m):
        out = {}
        for i, e in enumerate(AXES):
            for a in "xyz".replace("xyz"[i], ""):
                column = np.zeros((len(m.st_time), 3))
                column[:, i] = m.extras[f"acc_{a}"][m.st_interval]
                out[f"offset_{e}_acc_{a}"] = column
        return out


class StLatency(Effect):
    name = "st_latency"
    description = "time-tag offset of the star tracker behind the gyros (positive: its attitude is late)"
    # In ms: a latency is a few to hundreds of ms, which seconds print as "-0.00".
    parameters = (Parameter("latency", "ms", 1e-3, 1000.0, 10000.0, per_channel=False, prior_dof=EFFECT_PRIOR_DOF),)

    def star_tracker(self, m):
        return {"latency": -m.st_body_rate}


class StCorrelatedNoise(Effect):
    name = "st_correlated_noise"
    description = ("star-tracker noise correlated in time (slow tracker errors, a filtered attitude): white plus "
                   "first-order Gauss-Markov, its share and correlation time estimated with the other noise scales")
    noise = True


class StJitter(Effect):
    name = "st_jitter"
    description = ("timing jitter of the reference against the gyros' clock: each reference attitude is taken a "
                   "random dt off its time tag, an error omega dt along the rotation axis, its sd sigma_t "
                   "(st_jitter_ms) estimated with the other noise scales")
    noise = True
    rate_noise = True


LIBRARY = {e.name: e for e in (ScaleFactor(), ScaleFactorSymmetric(), Misalignment(), Bias(), BiasDrift(), SfNonlinearity(),
                                GSensitivity(), GravityOffset(), StLatency(), StCorrelatedNoise(),
                                StJitter())}
BASELINE = ("scale_factor", "misalignment", "bias")
SCALE_FACTORS = ("scale_factor", "scale_factor_symmetric")
"""The channel model's scale-factor terms: a model holds exactly one of them in place of the baseline's."""


class PluginError(InputError):
    """A plugin file that does not follow the effect API; the message says what is missing."""


def load_plugins(paths) -> dict:
    """Effects exported by plugin files (their module-level ``EFFECTS`` list), by name."""
    found = {}
    for path in paths:
        path = Path(path)
        if not path.exists():
            raise PluginError(f"plugin {path}: file not found")
        spec = importlib.util.spec_from_file_location(f"gyrocal_plugin_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        try:
            spec.loader.exec_module(module)
        except Exception as exc:
            raise PluginError(f"plugin {path}: failed to import: {type(exc).__name__}: {exc}") from exc
        effects = getattr(module, "EFFECTS", None)
        if not isinstance(effects, (list, tuple)) or not effects:
            raise PluginError(f"plugin {path}: must define EFFECTS = [YourEffect(), ...] at module level")
        for effect in effects:
            check_effect(effect, path)
            found[effect.name] = effect
    return found


def check_effect(effect, where):
    """Refuse an effect that lacks what the API needs, saying what."""
    if not isinstance(effect, Effect):
        raise PluginError(f"plugin {where}: {effect!r} is not an instance of gyrocal.model.effects.Effect")
    if not isinstance(effect.name, str) or not effect.name.isidentifier():
        raise PluginError(f"plugin {where}: {type(effect).__name__}.name must be an identifier, got {effect.name!r}")
    if effect.name in LIBRARY:
        raise PluginError(f"plugin {where}: effect name {effect.name!r} is taken by the library")
    if effect.core or effect.noise:
        raise PluginError(f"plugin {where}: {effect.name}: 'core' and 'noise' are reserved for the library's "
                          "channel model and noise model")
    if not effect.parameters:
        raise PluginError(f"plugin {where}: {effect.name}.parameters is empty; declare at least one Parameter")
    for p in effect.parameters:
        if not isinstance(p, Parameter):
            raise PluginError(f"plugin {where}: {effect.name}.parameters must hold Parameter objects, got {p!r}")
        if not (p.prior_sd > 0 and p.si_per_unit > 0):
            raise PluginError(f"plugin {where}: {effect.name}.{p.name}: prior_sd and si_per_unit must be positive")
    if type(effect).gyro is Effect.gyro and type(effect).star_tracker is Effect.star_tracker:
        raise PluginError(f"plugin {where}: {effect.name} overrides neither gyro(m) nor star_tracker(m)")


def resolve(model_name: str, names, plugins: dict) -> list:
    """The effect objects of a model; the baseline's three must be there, its scale factors
    per direction (``scale_factor``) or symmetric (``scale_factor_symmetric``)."""
    known = {**LIBRARY, **plugins}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"model {model_name}: unknown effect(s) {unknown}; known: {sorted(known)}")
    scale = [n for n in names if n in SCALE_FACTORS]
    if len(scale) > 1:
        raise ValueError(f"model {model_name}: takes one of {list(SCALE_FACTORS)}, not both")
    missing = [n for n in BASELINE if n not in names and not (n == "scale_factor" and scale)]
    if missing:
        raise ValueError(f"model {model_name}: every model builds on the paper's baseline; add {missing}")
    return [known[n] for n in names]


def known(plugin_paths) -> dict:
    """The library's effects and the plugins' (each plugin file loaded once), by name."""
    return {**LIBRARY, **load_plugins(plugin_paths or [])}
