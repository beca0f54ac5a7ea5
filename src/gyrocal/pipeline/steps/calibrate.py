"""Step ``calibrate``, the last of the posterior rule's job: ``calibration.csv`` and the gyro correction of
one model."""

import pandas as pd

from gyrocal import __version__
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.calibration import calibration_table, posterior_mean_params
from gyrocal.io.outputs import write_csv, write_json
from gyrocal.model.correction import campaign_correction
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(paths: CampaignPaths, maneuver_ids, model: str):
    """``calibration.csv`` per the contract and the correction file for every channel set."""
    out = paths.model(model)
    maneuvers = load_maneuvers(paths.maneuvers(maneuver_ids))
    est = PointEstimate.load(out.point_estimate, linearizations=False)
    table = calibration_table(est.spec, est.theta, pd.read_csv(out.summary).set_index("label"))
    write_csv(table, out.calibration)
    doc = campaign_correction(posterior_mean_params(est.spec, table), maneuvers, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, out.correction)
