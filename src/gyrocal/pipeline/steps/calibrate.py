"""Step ``calibrate``, the last of the posterior rule's job: ``calibration.csv`` and the gyro correction of
one model."""

import pandas as pd

from gyrocal import __version__
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.calibration import calibration_table, posterior_mean_params
from gyrocal.io.outputs import write_csv, write_json
from gyrocal.model.correction import campaign_correction
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(maneuver_files, point_estimate_npz, summary_csv, calibration_csv, correction_json):
    """``calibration_csv`` per the contract, from the point estimate's specification and the posterior's
    ``summary_csv``, and the correction file ``correction_json`` for every channel set of the maneuvers
    (``maneuver_files``, the preprocessed ``.npz``)."""
    maneuvers = load_maneuvers(maneuver_files)
    est = PointEstimate.load(point_estimate_npz, linearizations=False)
    table = calibration_table(est.spec, est.theta, pd.read_csv(summary_csv).set_index("label"))
    write_csv(table, calibration_csv)
    doc = campaign_correction(posterior_mean_params(est.spec, table), maneuvers, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, correction_json)
