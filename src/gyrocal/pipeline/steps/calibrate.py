"""Step ``calibrate``, the last of the posterior rule's job: ``calibration.csv`` and the gyro correction of
one model."""

import pandas as pd

from gyrocal import __version__
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.fit.operating import operating_params, operating_shift
from gyrocal.io.calibration import calibration_table, posterior_mean_extras, posterior_mean_params
from gyrocal.io.outputs import write_csv, write_json
from gyrocal.model import effects
from gyrocal.model.correction import campaign_correction
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(maneuver_files, point_estimate_npz, summary_csv, calibration_csv, correction_json, plugins=()):
    """``calibration_csv`` per the contract, from the point estimate's specification and the posterior's
    ``summary_csv``, and the correction file ``correction_json`` for every channel set of the maneuvers
    (``maneuver_files``, the preprocessed ``.npz``), its scale factors those at the campaign's rates
    (`operating_shift`, which evaluates the model's effects: the library's and those of ``plugins``)."""
    maneuvers = load_maneuvers(maneuver_files)
    est = PointEstimate.load(point_estimate_npz, effects.known(list(plugins)), linearizations=False)
    table = calibration_table(est.spec, est.theta, pd.read_csv(summary_csv).set_index("label"))
    write_csv(table, calibration_csv)
    shift = operating_shift(maneuvers, est.spec, posterior_mean_extras(est.spec, table), est.biases)
    source = "posterior mean" + (", scale factors at the campaign's rates" if shift.any() else "")
    doc = campaign_correction(operating_params(posterior_mean_params(est.spec, table), shift), maneuvers, source)
    doc["gyrocal_version"] = __version__
    write_json(doc, correction_json)
