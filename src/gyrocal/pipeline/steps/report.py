"""Rule ``report``: the pre-uplink review of a campaign and its verdict."""

import arviz as az
import pandas as pd

from gyrocal.inference.estimate import PointEstimate
from gyrocal.io.outputs import write_json, write_text
from gyrocal.pipeline.steps.common import load_maneuvers, read_json
from gyrocal.report import review


def run(models, model_files, npz_paths, table_paths, input_json, comparison_csv, truth_json, cfg, out_html,
        out_verdict, processes: int = 1):
    """``report.html``: the pre-uplink review of a campaign (see `gyrocal.report.review`), and its verdict
    with the checks behind it in ``verdict.json``, for scripts and fleets.

    ``model_files`` maps each name of `outputs.MODEL_FILES` to its paths, one per model in
    the order of ``models``; the reviewed model's are read. Its figures are drawn by
    ``processes`` processes.
    """
    table = pd.read_csv(comparison_csv)
    model = str(table.loc[table["reviewed"], "model"].iloc[0])
    files = {name: paths[models.index(model)] for name, paths in model_files.items()}
    calibrations = {m: pd.read_csv(p) for m, p in zip(models, model_files["calibration"])}
    maneuvers = load_maneuvers(npz_paths)
    est = PointEstimate.load(files["point"])
    with az.rc_context(rc={"data.load": "eager"}):  # in memory: the figures are drawn by forked processes
        posterior = az.from_netcdf(str(files["posterior"]))
    ctx = review.build_context(
        model, maneuvers, [pd.read_csv(p) for p in table_paths], est, read_json(files["diagnostics"]),
        read_json(files["sampler"]), read_json(files["correction"]), files["correction"], pd.read_csv(files["fit"]),
        posterior, table, read_json(input_json),
        read_json(truth_json)["parameters"] if truth_json else None, cfg, calibrations, processes)
    write_text(review.render(ctx), out_html)
    write_json(review.verdict(ctx), out_verdict)
