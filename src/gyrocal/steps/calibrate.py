"""Step ``calibrate``, the last of the posterior rule's job: ``calibration.csv`` and the gyro correction of
one model."""

import pandas as pd

from .. import __version__
from ..calibration import calibration_table, posterior_mean_params
from ..correction import campaign_correction
from ..estimate import PointEstimate
from ..outputs import write_csv, write_json
from .common import load_maneuvers


def run(point_npz, summary_csv, npz_paths, out_csv, out_correction):
    """``calibration.csv`` per the contract and the correction file for every channel set."""
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(point_npz)
    table = calibration_table(est.spec, est.theta, pd.read_csv(summary_csv).set_index("label"))
    write_csv(table, out_csv)
    doc = campaign_correction(posterior_mean_params(est.spec, table), maneuvers, "posterior mean")
    doc["gyrocal_version"] = __version__
    write_json(doc, out_correction)
