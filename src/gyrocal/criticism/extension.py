"""The model-criticism loop closed in one run: which library effect extends the reviewed model.

Where the reviewed model misfits (its ``diagnostics.json``) and the ranking's best explanation is a
library effect whose score test is significant (log10 p below the config's
``diagnostics.structure_log10_p_min``, the misfit check's own rule), the run fits the model
extended by that effect as one more variant (``extended``; ``extended_<k>`` for the k-th step,
up to the config's ``loop.depth``), and the comparison and the review show the error before and
after. A leading signature that a significant library effect explains as well (`equivalent_effect`)
extends the model by that effect. Anything else (no misfit, a signature or a plugin's effect no library
effect stands in for, nothing significant, an effect the model has already) stops the loop with its reason.
"""

from dataclasses import asdict, dataclass

import pandas as pd

from gyrocal.model.effects import LIBRARY

__all__ = ["EXTENDED", "Extension", "before_after", "equivalent_effect", "extension_names", "next_effect", "outside_share"]

EXTENDED = "extended"
"""The first extended variant's name; the k-th step's is ``extended_<k>`` (`extension_names`)."""


def extension_names(depth: int) -> list:
    """The extended variants' names of a loop ``depth`` steps deep, in order."""
    return [EXTENDED if k == 1 else f"{EXTENDED}_{k}" for k in range(1, int(depth) + 1)]


@dataclass(frozen=True)
class Extension:
    """What one step of the loop decided: the model it extends (``base``), the effect it adds
    (empty where it stops), the extended model's effects, and why."""

    base: str
    effect: str
    effects: list
    why: str

    @property
    def fitted(self) -> bool:
        return bool(self.effect)

    def as_dict(self) -> dict:
        return {**asdict(self), "fitted": self.fitted}


def next_effect(base: str, base_effects, diagnostics: dict, log10_p_min: float) -> Extension:
    """The step from the model ``base`` (its effects ``base_effects`` and ``diagnostics.json``):
    extended by the ranking's best explanation where the model misfits and that is a library effect
    it lacks, significant below ``log10_p_min``; otherwise not extended, with the reason."""
    effects = list(base_effects)

    def stop(why):
        return Extension(base, "", effects, why)

    if not diagnostics["misfit"]:
        return stop(f"model {base} has no misfit: nothing to extend")
    ranking = diagnostics.get("ranking") or []
    if not ranking:
        return stop(f"model {base} misfits, but nothing is ranked to explain it")
    best = ranking[0]
    if best["log10_p"] >= log10_p_min:
        return stop(f"model {base} misfits, but its best explanation, {best['kind']} {best['name']} "
                    f"(log10 p = {best['log10_p']:.1f}), is not significant below {log10_p_min:g}")
    as_well = ""
    if best["kind"] != "effect" or best["name"] not in LIBRARY:
        alike = equivalent_effect(ranking, effects, log10_p_min)
        if alike is None:
            return stop(f"model {base} misfits and its best explanation is {best['kind']} {best['name']} "
                        f"(log10 p = {best['log10_p']:.1f}), which is not a library effect: model it (plugins:)")
        as_well = (f"; {best['kind']} {best['name']} (log10 p = {best['log10_p']:.1f}), first, is no library "
                   f"effect, and {alike['name']} explains the same misfit (given it, the other leaders' "
                   f"log10 p = {alike['leftover_log10_p']:.1f})")
        best = alike
    if best["name"] in effects:
        return stop(f"model {base} has {best['name']} already")
    return Extension(base, best["name"], effects + [best["name"]],
                     f"model {base} misfits and its best explanation is effect {best['name']} "
                     f"(log10 p = {best['log10_p']:.1f}, significant below {log10_p_min:g}){as_well}")


def equivalent_effect(ranking, effects, log10_p_min: float):
    """A library effect that explains the misfit as well as the leading signature does, or None: among
    the ranking's leaders (`diagnostics.rank`'s encompassing test gives each its ``leftover_log10_p``, the
    most significant other leader given it), the first significant library effect the model lacks,
    given which no other leader is significant, where the signature leaves nothing either.
    One rate per direction makes a rate-squared scale factor and a bias that flips with the rotation
    (``rate_sign``) one misfit: the loop fits the one the library holds."""
    lead = ranking[0].get("leftover_log10_p")
    if lead is None or lead < log10_p_min:
        return None
    for r in ranking[1:]:
        if r.get("leftover_log10_p") is None:
            return None
        if (r["kind"] == "effect" and r["name"] in LIBRARY and r["name"] not in effects
                and r["log10_p"] < log10_p_min <= r["leftover_log10_p"]):
            return r
    return None


def outside_share(fit) -> float:
    """The share of a model's fitted points (``fit.csv``: every sample, set and axis) outside their 95 % bands."""
    outside = fit[[c for c in fit.columns if c.startswith("outside_")]].to_numpy(dtype=float)
    return float(outside.mean())


def before_after(steps: list, diagnostics: dict, fits: dict, comparison):
    """The loop's error before and after, a row per model of each fitted step (``steps``: (name,
    `Extension.as_dict`) pairs, the model each extends first, then the extended one): residual RMS against
    what the noise model predicts, the innovations' whiteness, the share outside the 95 % bands and
    both leave-out elpd (``model_comparison.csv``'s); ``diagnostics`` and ``fits`` by model. A base that
    was refused (the loop then extends it by the effect its refusal advises) has no row of its own."""
    elpd = comparison.set_index("model")
    rows = []
    for name, step in steps:
        for model, role in ((step["base"], "before"), (name, f"after: + {step['effect']}")):
            if model not in diagnostics:
                continue
            d = diagnostics[model]
            rows.append({"step": name, "model": model, "": role, "misfit": bool(d["misfit"]),
                         "residual RMS (arcsec)": round(d["residual_rms_arcsec"], 2),
                         "noise model predicts (arcsec)": round(d["noise_rms_arcsec"], 2),
                         "whiteness z": round(d["whiteness"]["z"], 1),
                         "outside 95 % bands": round(outside_share(fits[model]), 4),
                         "elpd_loo": round(float(elpd.loc[model, "elpd_loo"]), 1),
                         "elpd_lomo": round(float(elpd.loc[model, "elpd_lomo"]), 1)})
    return pd.DataFrame(rows)
