"""What each step is given of the config: a small, frozen object per step, built from the
config's sections, so that a step takes only what it uses (and a rule reruns only when that
changes). The rules pass the same sections as their ``params``."""

from dataclasses import dataclass, field
from typing import ClassVar

from gyrocal.errors import InputError

__all__ = ["SECTIONS", "DiagnosticsSettings", "ExtendSettings", "ModelChoiceSettings", "PointEstimateSettings",
           "PosteriorSettings", "ReportSettings", "canonical", "models_to_run", "section"]

SECTIONS = {
    "point_estimate": ("noise", "plugins"),
    "posterior": ("priors", "sampler", "grid", "convergence", "seed", "prior_from", "plugins"),
    "diagnostics": ("diagnostics", "plugins"),
}
"""The config keys each model step reads (the report reads the whole config)."""


def canonical(value):
    """``value`` with the keys of every mapping sorted: Snakemake compares a rule's params by their
    repr, so the order a config file happens to give must not rerun a job."""
    return {k: canonical(value[k]) for k in sorted(value)} if isinstance(value, dict) else value


def models_to_run(cfg: dict) -> list:
    """The variants a run calibrates and compares, the first the comparison's reference: the config's
    ``run_models`` in its order, or, where it is empty, every variant under ``models:`` with
    ``baseline`` first. A name ``models:`` does not define is refused, naming those it does."""
    defined = list(cfg["models"])
    chosen = list(cfg.get("run_models") or [])
    reserved = [m for m in defined if m == "extended" or m.startswith("extended_")]
    if reserved:
        raise InputError(f"config: models: {reserved}: the names extended and extended_<k> are the loop's "
                         "(loop.depth), which fits them where the reviewed model misfits; name the variant otherwise")
    if not chosen:
        return sorted(defined, key=lambda m: m != "baseline")
    unknown = [m for m in chosen if m not in defined]
    if unknown:
        raise InputError(f"config: run_models names {unknown}, which models: does not define; defined: {defined}")
    if len(set(chosen)) < len(chosen):
        raise InputError(f"config: run_models lists a model twice: {chosen}")
    return chosen


def section(cfg: dict, step: str) -> dict:
    """The keys of the config ``step`` reads (`SECTIONS`), canonical."""
    return canonical({key: cfg[key] for key in SECTIONS[step]})


class _OfSections:
    """A step's settings made from the config keys its step reads (`SECTIONS`)."""

    step: ClassVar[str]

    @classmethod
    def of(cls, cfg: dict):
        return cls(**section(cfg, cls.step))


@dataclass(frozen=True)
class PointEstimateSettings:
    """The point estimate's: the model's effects, the noise knowledge defaults and the plugins."""

    effects: list
    noise: dict
    plugins: list = field(default_factory=list)

    @classmethod
    def of(cls, cfg: dict, model: str) -> "PointEstimateSettings":
        return cls(effects=list(cfg["models"][model]), **section(cfg, "point_estimate"))


@dataclass(frozen=True)
class PosteriorSettings(_OfSections):
    """The sampler's: priors, sampler, grid, convergence, seed, an earlier campaign's calibration
    as the prior (``prior_from``, or None) and the plugins."""

    priors: dict
    sampler: dict
    grid: dict
    convergence: dict
    seed: int
    prior_from: str | None = None
    plugins: list = field(default_factory=list)

    step: ClassVar[str] = "posterior"

    def __post_init__(self):
        object.__setattr__(self, "prior_from", self.prior_from or None)  # the config's "" is none


@dataclass(frozen=True)
class DiagnosticsSettings(_OfSections):
    """The criticism's thresholds and the plugins whose effects it may name."""

    diagnostics: dict
    plugins: list = field(default_factory=list)
    step: ClassVar[str] = "diagnostics"


@dataclass(frozen=True)
class ModelChoiceSettings:
    """The model-choice rule's (docs/usage.md, "Which model is reviewed")."""

    reject_se: float
    agree_sd: float

    @classmethod
    def of(cls, cfg: dict) -> "ModelChoiceSettings":
        return cls(**canonical(cfg["model_choice"]))


@dataclass(frozen=True)
class ExtendSettings:
    """An extended variant's (`gyrocal.pipeline.steps.extend`): the sections of the three model steps
    it runs, the model choice that names the model it extends, and the loop's depth."""

    point_estimate: dict
    posterior: dict
    diagnostics: dict
    model_choice: dict
    loop: dict

    @classmethod
    def of(cls, cfg: dict) -> "ExtendSettings":
        return cls(**{step: section(cfg, step) for step in SECTIONS},
                   model_choice=canonical(cfg["model_choice"]), loop=canonical(cfg.get("loop") or {"depth": 1}))


@dataclass(frozen=True)
class ReportSettings:
    """The report's: it shows the whole config, so it takes all of it."""

    config: dict

    @classmethod
    def of(cls, cfg: dict) -> "ReportSettings":
        return cls(canonical(cfg))
