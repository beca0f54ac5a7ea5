"""Rule ``diagnostics``: the misfit verdict and the ranking of candidate effects of one model."""

import pandas as pd

from gyrocal.criticism import diagnostics
from gyrocal.inference.estimate import PointEstimate
from gyrocal.io.outputs import write_json
from gyrocal.model import effects
from gyrocal.pipeline.steps.common import known_effects, load_maneuvers


def run(npz_paths, point_npz, summary_csv, fit_csv, plugin_paths, thresholds, out_json):
    """``diagnostics.json`` per docs/interface.md section 5: misfit verdict and ranking."""
    maneuvers = load_maneuvers(npz_paths)
    known = known_effects(plugin_paths)
    est = PointEstimate.load(point_npz, known)
    plugins = [e for name, e in known.items() if name not in effects.LIBRARY]
    doc = diagnostics.diagnose(maneuvers, est, pd.read_csv(fit_csv), pd.read_csv(summary_csv).set_index("label"),
                               thresholds, plugins)
    write_json(doc, out_json)
