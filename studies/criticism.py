"""The model-criticism loop on every hidden-effect scenario: prints a table, asserts nothing.

    python studies/criticism.py

Each scenario in tests/data/hidden_*.yaml is simulated (its own seed) and run with the
baseline and with the variant that adds the hidden effect, as the tests do.
"""

import json
import tempfile
from pathlib import Path

import pandas as pd
import yaml

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.calibration import core_rows
from gyrocal.simulation import simulate
from gyrocal.study.hidden import CASES, calibrate, with_variant

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests/data"


def coverage(out, model, campaign, truth):
    t = truth["parameters"]
    spec = PointEstimate.load(out / model / "point_estimate.npz").spec
    table = core_rows(spec, pd.read_csv(out / model / "calibration.csv"))
    values = [t[r.channel][r.parameter] for r in table.itertuples()]
    return int(((table["ci95_low"] <= values) & (values <= table["ci95_high"])).sum())


def main():
    from snakemake.utils import validate
    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    validate(cfg, str(ROOT / "workflow/schemas/config.schema.yaml"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case, (effect, _, plugin) in CASES.items():
            root = Path(tmp) / case
            simulate.run(DATA / f"hidden_{case}.yaml", root / "sim")
            campaign, truth = root / "sim/campaign", json.loads((root / "sim/truth.json").read_text())
            calibrate(campaign, root / "out", with_variant(cfg, effect, ROOT / plugin if plugin else None),
                      truth_path=root / "sim/truth.json")
            comp = pd.read_csv(root / "out/model_comparison.csv").set_index("model")
            base = json.loads((root / "out/baseline/diagnostics.json").read_text())
            ext = json.loads((root / "out/extended/diagnostics.json").read_text())
            rows.append({
                "hidden effect": case, "baseline misfit": base["misfit"], "ranked first": base["ranking"][0]["name"],
                "rms base": base["residual_rms_arcsec"], "rms variant": ext["residual_rms_arcsec"],
                "noise rms": ext["noise_rms_arcsec"], "variant misfit": ext["misfit"],
                "elpd gain": round(comp.loc["extended", "elpd_diff_vs_first"], 1),
                "se": round(comp.loc["extended", "elpd_diff_se"], 1),
                "covered base": coverage(root / "out", "baseline", campaign, truth),
                "covered variant": coverage(root / "out", "extended", campaign, truth)})
    print(pd.DataFrame(rows).to_string(index=False))


if __name__ == "__main__":
    main()
