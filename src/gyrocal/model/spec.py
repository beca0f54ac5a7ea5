"""One model's parameters, declared once: the model specification.

Built from a model's resolved effects (the baseline's included) and the campaign's
channels, it lists every parameter with its label, unit, SI factor, prior, physical
bound and column of the linear error model. The point-estimate step saves it with
the estimate; every later step derives units, priors and columns from it. The
effects' `Parameter` declarations are the only source of these facts; the config's
``priors:`` section and an earlier campaign (``prior_from``) may override the priors.
"""

import json
from dataclasses import asdict, dataclass, replace

import numpy as np

from gyrocal.model import channels as ch
from gyrocal.model import effects as fx
from gyrocal.model.sensorclass import class_priors

__all__ = ["CONFIG_PRIOR_KEYS", "ModelSpec", "ParameterSpec", "baseline"]


@dataclass(frozen=True)
class ParameterSpec:
    """One sampled parameter; values in ``unit`` (``value_si = value * si_per_unit``)."""

    label: str
    """``<owner>.<name>``, e.g. ``dtg2_yaw.sf_pos`` or ``st_latency.latency``."""
    owner: str
    """The channel of a per-channel copy, else the effect (calibration.csv's ``channel``)."""
    name: str
    effect: str
    unit: str
    si_per_unit: float
    prior_mean: float
    prior_sd: float
    bound: float
    """Physical bound on ``|value|``."""
    channel: int | None = None
    """Index of the channel a per-channel copy belongs to."""
    core: bool = False
    """A term of the channel model (eq. 3): part of the uplinked correction."""
    prior_only: str = ""
    """Why the data cannot inform this parameter (e.g. "no -pitch maneuver"); empty when they can.
    A prior-only parameter is kept out of the fit: its column is zero, its posterior its prior."""
    prior_dof: float = np.inf
    """The prior's family (`gyrocal.model.effects.Parameter.prior_dof`): ``inf`` normal, else Student-t."""


CONFIG_PRIOR_KEYS = {"sf_sd_ppm": (fx.SCALE_FACTORS, "prior_sd"), "sf_bound_ppm": (fx.SCALE_FACTORS, "bound"),
                     "mis_sd_arcsec": (("misalignment",), "prior_sd"),
                     "mis_bound_arcsec": (("misalignment",), "bound")}
"""The config's ``priors:`` keys that override the declared prior sd or bound of the effects
named; each key ends in the unit they declare."""


def _specs_of(effect, parameter, channels, core) -> list:
    if not parameter.per_channel:
        return [_spec(effect, parameter, effect.name, None, core)]
    return [_spec(effect, parameter, c.name, i, core) for i, c in enumerate(channels)
            if parameter in effect.channel_parameters(c)]


def _spec(effect, p, owner, channel, core) -> ParameterSpec:
    return ParameterSpec(f"{owner}.{p.name}", owner, p.name, effect.name, p.unit, float(p.si_per_unit), 0.0,
                         float(p.prior_sd), float(p.bound), channel, core, prior_dof=float(p.prior_dof))


class ModelSpec:
    """The parameters of one model on one campaign's channels, in column order.

    The channel model's terms come first, channel by channel (eq. 3); then the
    parameters of the other effects in the model's order.
    """

    def __init__(self, model: str, channels, parameters, effect_names, correlated_noise=False, effects=None):
        self.model = model
        self.channels = tuple(channels)
        self.parameters = tuple(parameters)
        self.effect_names = tuple(effect_names)
        self.correlated_noise = bool(correlated_noise)
        """A noise-model effect makes the star-tracker noise time-correlated."""
        self._effects = dict(effects or {})
        self.labels = [p.label for p in self.parameters]
        self.units = [p.unit for p in self.parameters]
        self.si_per_unit = np.array([p.si_per_unit for p in self.parameters])
        self.n_core = sum(p.core for p in self.parameters)
        if any(p.core for p in self.parameters[self.n_core:]):
            raise ValueError(f"model {model}: the channel model's parameters must come first")
        self._index = {label: i for i, label in enumerate(self.labels)}

    @classmethod
    def build(cls, model: str, effects, channels) -> "ModelSpec":
        """The specification of a model from its resolved effects (`effects.resolve`)."""
        core = [s for i, c in enumerate(channels) for e in effects if e.core
                for p in e.channel_parameters(c) for s in [_spec(e, p, c.name, i, True)]]
        extra = [s for e in effects if not (e.core or e.noise) for p in e.parameters
                 for s in _specs_of(e, p, channels, False)]
        correlated = any(e.noise and not e.rate_noise for e in effects)
        return cls(model, channels, core + extra, [e.name for e in effects], correlated,
                   {e.name: e for e in effects})

    @property
    def jitter_noise(self) -> bool:
        """The reference's timing jitter (`effects.StJitter`) is one more noise scale, after the others."""
        return "st_jitter" in self.effect_names

    def __len__(self) -> int:
        return len(self.parameters)

    def index(self, label: str) -> int:
        return self._index[label]

    @property
    def core(self) -> slice:
        return slice(0, self.n_core)

    @property
    def extra(self) -> slice:
        return slice(self.n_core, len(self.parameters))

    @property
    def extras(self) -> tuple:
        """The parameters the effects beyond the channel model add, in column order."""
        return self.parameters[self.n_core:]

    @property
    def free(self) -> np.ndarray:
        """Mask of the parameters the data inform (not `ParameterSpec.prior_only`)."""
        return np.array([not p.prior_only for p in self.parameters], dtype=bool)

    def with_prior_only(self, reasons: dict) -> "ModelSpec":
        """This model with the parameters named in ``reasons`` (label: why) marked prior-only."""
        parameters = [replace(p, prior_only=reasons.get(p.label, p.prior_only)) for p in self.parameters]
        return ModelSpec(self.model, self.channels, parameters, self.effect_names, self.correlated_noise,
                         self._effects)

    def effect(self, name: str):
        """The effect object behind a parameter (needs a spec built or loaded with its effects)."""
        if name not in self._effects:
            raise ValueError(f"model {self.model}: effect {name} is not loaded; load the specification "
                             f"with the library and the configured plugins")
        return self._effects[name]

    def to_unit(self, values_si: np.ndarray) -> np.ndarray:
        """SI values (last axis in column order) in each parameter's unit."""
        return np.asarray(values_si) * (1.0 / self.si_per_unit)

    def to_si(self, values: np.ndarray) -> np.ndarray:
        return np.asarray(values) * self.si_per_unit

    @property
    def prior_mean_si(self) -> np.ndarray:
        return self.to_si([p.prior_mean for p in self.parameters])

    @property
    def prior_sd_si(self) -> np.ndarray:
        return self.to_si([p.prior_sd for p in self.parameters])

    @property
    def prior_dof(self) -> np.ndarray:
        """Each parameter's prior degrees of freedom (``inf``: normal; `gyrocal.model.priorfamily`)."""
        return np.array([p.prior_dof for p in self.parameters], dtype=float)

    @property
    def bound_si(self) -> np.ndarray:
        return self.to_si([p.bound for p in self.parameters])

    def channel_params(self, theta_si, bias_rad_s=None) -> ch.ChannelParams:
        """The channel-model terms of a parameter vector (its first `n_core` entries)."""
        params = ch.ChannelParams.zeros(self.channels)
        for p, value in zip(self.parameters[:self.n_core], np.asarray(theta_si, dtype=float)):
            params.set(p.channel, p.name, value)
        if bias_rad_s is not None:
            params.bias_rad_s = np.asarray(bias_rad_s, dtype=float).reshape(len(self.channels))
        return params

    def core_vector(self, params: ch.ChannelParams) -> np.ndarray:
        """Inverse of `channel_params`: the channel-model terms as a vector (SI)."""
        return np.array([params.get(p.channel, p.name) for p in self.parameters[:self.n_core]])

    def contract(self, params: ch.ChannelParams) -> dict:
        """``{channel: {parameter: value}}`` of the channel-model terms, in their units."""
        out = {c.name: {} for c in self.channels}
        core = self.core_vector(params) * (1.0 / self.si_per_unit[self.core])
        for p, value in zip(self.parameters[:self.n_core], core):
            out[p.owner][p.name] = float(value)
        return out

    def params_from_contract(self, values: dict) -> ch.ChannelParams:
        """Inverse of `contract`; missing entries are zero."""
        theta = [values.get(p.owner, {}).get(p.name, 0.0) for p in self.parameters[:self.n_core]]
        return self.channel_params(np.asarray(theta, dtype=float) * self.si_per_unit[self.core])

    def augmented(self, effects) -> "ModelSpec":
        """This model with the parameters of further effects appended (candidate columns)."""
        extra = [s for e in effects for p in e.parameters for s in _specs_of(e, p, self.channels, False)]
        return ModelSpec(self.model, self.channels, self.parameters + tuple(extra),
                         self.effect_names + tuple(e.name for e in effects), self.correlated_noise,
                         {**self._effects, **{e.name: e for e in effects}})

    def with_sensor_class(self, sensor_class: str | None) -> "ModelSpec":
        """This model with the default priors of a gyro sensor class (`gyrocal.model.sensorclass`;
        None: the declared ones, a DTG's); the config's ``priors:`` still override them."""
        table = class_priors(sensor_class)
        parameters = [replace(p, **table.get((p.effect, p.name), {})) for p in self.parameters]
        return ModelSpec(self.model, self.channels, parameters, self.effect_names, self.correlated_noise,
                         self._effects)

    def with_priors(self, priors: dict | None = None, earlier=None, source: str = "prior_from") -> "ModelSpec":
        """Priors overridden by the config (`CONFIG_PRIOR_KEYS`; ``priors.sd``, the prior sd of
        ``<effect>.<parameter>`` in its declared unit) and by an earlier campaign's
        ``calibration.csv`` (its posterior mean and sd, where it holds the parameter)."""
        overrides = {}
        for key, value in ((priors or {}).get("sd") or {}).items():
            effect, _, name = key.partition(".")
            if effect not in self.effect_names:
                continue
            matched = [p for p in self.parameters if p.effect == effect and p.name == name]
            if not matched:
                known = sorted({f"{p.effect}.{p.name}" for p in self.parameters if p.effect == effect})
                raise ValueError(f"priors.sd.{key}: {effect} has no parameter {name!r}; it has {known}")
            for p in matched:
                overrides.setdefault(p.label, {})["prior_sd"] = float(value)
        for key, value in (priors or {}).items():
            if key not in CONFIG_PRIOR_KEYS:
                continue
            owners, field = CONFIG_PRIOR_KEYS[key]
            unit = key.rsplit("_", 1)[1]
            for p in self.parameters:
                if p.effect in owners:
                    if p.unit != unit:
                        raise ValueError(f"priors.{key}: {p.effect} declares {p.name} in {p.unit}, not {unit}")
                    overrides.setdefault(p.label, {})[field] = float(value)
        if earlier is not None:
            for row in earlier.itertuples():
                label = f"{row.channel}.{row.parameter}"
                if label not in self._index:
                    continue
                unit = self.parameters[self._index[label]].unit
                if row.unit != unit:
                    raise ValueError(f"{source}: {label} is in {row.unit}, but this model declares it in {unit}")
                # an earlier posterior, normal to the sampler's accuracy
                overrides.setdefault(label, {}).update(prior_mean=float(row.mean), prior_sd=float(row.sd),
                                                       prior_dof=np.inf)
        parameters = [replace(p, **overrides.get(p.label, {})) for p in self.parameters]
        return ModelSpec(self.model, self.channels, parameters, self.effect_names, self.correlated_noise,
                         self._effects)

    def to_json(self) -> str:
        rows = [{**asdict(p), "bound": None if np.isinf(p.bound) else p.bound,
                 "prior_dof": None if np.isinf(p.prior_dof) else p.prior_dof} for p in self.parameters]
        return json.dumps({"model": self.model, "effects": list(self.effect_names),
                           "correlated_noise": self.correlated_noise,
                           "channels": [asdict(c) for c in self.channels], "parameters": rows})

    @classmethod
    def from_json(cls, text: str, known_effects: dict | None = None) -> "ModelSpec":
        """Read `to_json`. Steps that evaluate the effects again pass ``known_effects``
        (library and plugins, by name); the others need only the declarations."""
        doc = json.loads(text)
        effects = None
        if known_effects is not None:
            missing = [n for n in doc["effects"] if n not in known_effects]
            if missing:
                raise ValueError(f"model {doc['model']} uses effect(s) {missing}, which are neither in the "
                                 f"library nor in the configured plugins")
            effects = {n: known_effects[n] for n in doc["effects"]}
        parameters = [ParameterSpec(**{**p, "bound": np.inf if p["bound"] is None else p["bound"],
                                       "prior_dof": np.inf if p.get("prior_dof") is None else p["prior_dof"]})
                      for p in doc["parameters"]]
        return cls(doc["model"], [ch.Channel(**c) for c in doc["channels"]], parameters, doc["effects"],
                   doc["correlated_noise"], effects)


def baseline(channels) -> ModelSpec:
    """The paper's model (eq. 3: scale factors and misalignments) on these channels."""
    return ModelSpec.build("baseline", fx.resolve("baseline", fx.BASELINE, {}), channels)
