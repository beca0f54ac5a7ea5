"""Rule ``diagnostics``: the misfit verdict and the ranking of candidate effects of one model."""

import pandas as pd

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.outputs import write_json
from gyrocal.model import effects
from gyrocal.pipeline.settings import DiagnosticsSettings
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(maneuver_files, point_estimate_npz, fit_csv, summary_csv, out_json, settings: DiagnosticsSettings):
    """``out_json`` (``diagnostics.json``) per docs/interface.md section 5: misfit verdict and ranking of
    one model, from its point estimate, model fit and posterior summary on the maneuvers
    (``maneuver_files``, the preprocessed ``.npz``)."""
    maneuvers = load_maneuvers(maneuver_files)
    known = effects.known(settings.plugins)
    est = PointEstimate.load(point_estimate_npz, known)
    plugins = [e for name, e in known.items() if name not in effects.LIBRARY]
    doc = diagnostics.diagnose(maneuvers, est, pd.read_csv(fit_csv), pd.read_csv(summary_csv).set_index("label"),
                               settings.diagnostics, plugins)
    write_json(doc, out_json)
