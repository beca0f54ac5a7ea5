"""Rule ``fleet``: every campaign's reviewed model and verdict in one table and figure."""

import pandas as pd

from gyrocal.io.outputs import write_csv, write_with
from gyrocal.pipeline.steps.common import read_json
from gyrocal.report import figures as plots
from gyrocal.report import fleet

__all__ = ["run"]


def run(verdict_paths, out_csv, out_png):
    """``results/fleet/``: every campaign's reviewed model and verdict in one table and figure."""
    verdicts = [read_json(p) for p in verdict_paths]
    calibrations = {(v["campaign"], v["model"]): pd.read_csv(fleet.calibration_path(p, v["model"]))
                    for v, p in zip(verdicts, verdict_paths)}
    table = fleet.summary(verdicts, calibrations)
    write_csv(table, out_csv)
    fig = fleet.figure(table)
    write_with(lambda handle: plots.save(fig, handle), out_png)
