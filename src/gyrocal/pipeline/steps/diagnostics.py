"""Rule ``diagnostics``: the misfit verdict and the ranking of candidate effects of one model."""

import pandas as pd

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.outputs import write_json
from gyrocal.model import effects
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import DiagnosticsSettings
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(paths: CampaignPaths, maneuver_ids, model: str, settings: DiagnosticsSettings):
    """``diagnostics.json`` per docs/interface.md section 5: misfit verdict and ranking."""
    out = paths.model(model)
    maneuvers = load_maneuvers(paths.maneuvers(maneuver_ids))
    known = effects.known(settings.plugins)
    est = PointEstimate.load(out.point_estimate, known)
    plugins = [e for name, e in known.items() if name not in effects.LIBRARY]
    doc = diagnostics.diagnose(maneuvers, est, pd.read_csv(out.fit), pd.read_csv(out.summary).set_index("label"),
                               settings.diagnostics, plugins)
    write_json(doc, out.diagnostics)
