"""A finished run's files read back: a campaign's preprocessed maneuvers and one model's point
estimate, for the commands that inspect a run (``gyrocal linearity``)."""

import json
from pathlib import Path

from gyrocal.criticism import linearity
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.model import effects
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["linearity_report", "load_model_run"]


def load_model_run(results, model: str, plugin_paths=()) -> tuple:
    """The maneuvers (in the campaign's order) and the point estimate of ``model`` in a run's
    ``results/<campaign>`` folder; a clear error where the run is missing or inconsistent."""
    results = Path(results)
    point = results / model / "point_estimate.npz"
    if not point.is_file():
        raise FileNotFoundError(f"{point}: no point estimate of model {model!r} in {results} (run the pipeline first)")
    ids = json.loads((results / "input.json").read_text())["maneuvers"]
    maneuvers = load_maneuvers([results / "preprocess" / f"{i}.npz" for i in ids])
    estimate = PointEstimate.load(point, effects.known(list(plugin_paths)))
    if estimate.biases.shape[0] != len(maneuvers):
        raise ValueError(f"{point}: {estimate.biases.shape[0]} maneuvers' biases, but {results}/input.json lists "
                         f"{len(maneuvers)} maneuvers")
    return maneuvers, estimate


def linearity_report(results, model: str, plugin_paths=()) -> str:
    """``gyrocal linearity``: `gyrocal.criticism.linearity.check` on one model of a finished run, as
    a table and a summary line."""
    table = linearity.check(*load_model_run(results, model, plugin_paths))
    return f"{results}, model {model}\n{table.round(3).to_string()}\n{linearity.summary(table)}"
