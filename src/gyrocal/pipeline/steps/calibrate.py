"""Step ``calibrate``, the last of the posterior rule's job: ``calibration.csv`` and the gyro correction of
one model."""

import pandas as pd

from gyrocal import __version__
from gyrocal.inference.calibration import calibration_table, posterior_mean_params
from gyrocal.inference.estimate import PointEstimate
from gyrocal.io.outputs import write_csv, write_json
from gyrocal.model.correction import campaign_correction
from gyrocal.pipeline.steps.common import load_maneuvers


def run(point_npz, summary_csv, npz_paths, out_csv, out_correction):
    """``calibration.csv`` per the contract and the correction file for every channel set."""
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(point_npz)
    table = calibration_table(est.spec, est.theta, pd.read_csv(summary_csv).set_index("label"))
    write_csv(table, out_csv)
    doc = campaign_correction(posterior_mean_params(est.spec, table), maneuvers, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, out_correction)
