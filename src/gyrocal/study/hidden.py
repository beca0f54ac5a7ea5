"""The model-criticism loop's hidden-effect cases: a campaign simulated with one effect the baseline
lacks (``hidden_<case>.yaml``), run with the baseline and the variant that adds it. What the
criticism studies (`studies/criticism.py`, `studies/loo_vs_structure.py`) and their tests share."""

import copy
from pathlib import Path

__all__ = ["BASE", "CASES", "calibrate", "with_variant"]

BASE = ["scale_factor", "misalignment", "bias"]
"""The baseline's effects, the paper's model."""

CASES = {
    # scenario: (variant effect, names that count as the right diagnosis, plugin file from the repository root)
    "bias_drift": ("bias_drift", {"bias_drift", "time"}, None),
    "sf_nonlinearity": ("sf_nonlinearity", {"sf_nonlinearity", "rate_squared"}, None),
    "st_latency": ("st_latency", {"st_latency", "acceleration"}, None),
    "st_correlated_noise": ("st_correlated_noise", {"st_correlated_noise"}, None),
    "temperature": ("sf_temperature", {"sf_temperature", "temp_dtg1", "temp_dtg2", "temp_dtg3"},
                    "examples/temperature/plugin_sf_temperature.py"),
}
"""Each case's scenario (``hidden_<case>.yaml``), the effect its variant adds, the ranking's names that
count as the right diagnosis, and the plugin file that defines the effect, from the repository's root
(the tutorial's own; None: a library effect)."""


def with_variant(cfg: dict, effect: str, plugin=None) -> dict:
    """A copy of ``cfg`` with two models, ``baseline`` and ``extended`` (the baseline plus ``effect``),
    and ``plugin`` (a path) as its only plugin when given, else none."""
    out = copy.deepcopy(cfg)
    out["models"] = {"baseline": BASE, "extended": BASE + [effect]}
    out["plugins"] = [str(plugin)] if plugin else []
    return out


def calibrate(campaign_dir, out, cfg: dict, models=("baseline", "extended"), truth_path=None) -> list:
    """Every workflow step in the order the rules run them (`gyrocal.pipeline.run.run_campaign`), into
    ``out``; the preprocessed maneuvers' files, in the campaign's order."""
    from gyrocal.pipeline import run
    from gyrocal.pipeline.paths import CampaignPaths

    paths = CampaignPaths.under(out)
    ids = run.run_campaign(campaign_dir, paths, cfg, models, truth_path)
    return [Path(p) for p in paths.maneuvers(ids)]
