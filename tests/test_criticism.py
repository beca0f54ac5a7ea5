"""The model-criticism loop, proven on data with a hidden effect (issue: compare, diagnose, extend).

For each hidden effect: the baseline misfits, the effect (or its residual signature)
ranks first, and the variant that adds it fits within the noise, wins by PSIS-LOO and
covers the truth again. Once more for an effect that exists only in a plugin file.
"""

import json

import pandas as pd
import pytest

from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.calibration import core_rows
from gyrocal.model import effects
from gyrocal.simulation import simulate
from gyrocal.study.hidden import BASE, CASES

from conftest import DATA, ROOT, config_with, run_campaign

CASE_PARAMS = [pytest.param(case, marks=pytest.mark.full) for case in CASES]
"""Every case in the full tier (bash tests/run.sh --full): the fast tier names a hidden effect through the
review (test_report's hidden bias drift) and runs a plugin's model end to end (test_spec's arcsec plugin)."""


@pytest.fixture(scope="module")
def runs(tmp_path_factory, config):
    """Each hidden-effect campaign run with the baseline and the variant that adds the effect, made
    when a test first asks for it."""
    made = {}

    def run(case):
        if case not in made:
            effect, _, plugin = CASES[case]
            root = tmp_path_factory.mktemp(case)
            simulate.run(DATA / f"hidden_{case}.yaml", root / "sim")
            cfg = config_with(config, {"baseline": BASE, "extended": BASE + [effect]},
                              [str(ROOT / plugin)] if plugin else [])
            run_campaign(root / "sim" / "campaign", root / "out", cfg, ("baseline", "extended"),
                         root / "sim" / "truth.json")
            made[case] = root
        return made[case]

    return run


def load(root, model):
    return json.loads((root / "out" / model / "diagnostics.json").read_text())


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_baseline_misfits_on_data_with_a_hidden_effect(runs, case):
    assert load(runs(case), "baseline")["misfit"] is True


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_the_hidden_effect_or_its_signature_ranks_first(runs, case):
    ranking = load(runs(case), "baseline")["ranking"]
    assert ranking[0]["name"] in CASES[case][1], ranking[:3]


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_the_variant_that_adds_it_fits_within_the_noise(runs, case):
    d = load(runs(case), "extended")
    assert abs(d["residual_rms_arcsec"] / d["noise_rms_arcsec"] - 1) < 0.10
    assert d["misfit"] is False, [c for c in d["checks"] if not c["passed"]]


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_the_variant_wins_by_loo_by_more_than_4_se(runs, case):
    table = pd.read_csv(runs(case) / "out" / "model_comparison.csv").set_index("model")
    diff, se = table.loc["extended", "elpd_diff_vs_first"], table.loc["extended", "elpd_diff_se"]
    assert diff > 4 * se, (diff, se)


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_the_variant_covers_the_truth_again(runs, case):
    root = runs(case)
    t = json.loads((root / "sim/truth.json").read_text())["parameters"]
    spec = PointEstimate.load(root / "out" / "extended" / "point_estimate.npz").spec
    table = core_rows(spec, pd.read_csv(root / "out" / "extended" / "calibration.csv"))
    truth_values = [t[r.channel][r.parameter] for r in table.itertuples()]
    inside = (table["ci95_low"] <= truth_values) & (truth_values <= table["ci95_high"])
    assert inside.sum() >= 22, table[~inside.to_numpy()]


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_the_review_rests_on_the_true_effect(runs, case):
    table = pd.read_csv(runs(case) / "out" / "model_comparison.csv").set_index("model")
    assert table.loc["extended", "reviewed"] and table.loc["extended", "plausible"]
    assert not table.loc["baseline", "plausible"] and table.loc["baseline", "loo_rejected"]
    assert "model reviewed: <b>extended</b>" in (runs(case) / "out" / "report.html").read_text()


@pytest.mark.parametrize("case", CASE_PARAMS)
def test_exact_leave_one_maneuver_out_prefers_the_true_effect(runs, case):
    table = pd.read_csv(runs(case) / "out" / "model_comparison.csv").set_index("model")
    diff, se = table.loc["extended", "elpd_lomo_diff_vs_first"], table.loc["extended", "elpd_lomo_diff_se"]
    assert diff > 2.5 * se, (diff, se)


@pytest.mark.full
def test_on_clean_data_no_variant_wins_and_nothing_misfits(tiny, tmp_path, config):
    variants = {"baseline": BASE, "drift": BASE + ["bias_drift"], "latency": BASE + ["st_latency"]}
    run_campaign(tiny[0], tmp_path, config_with(config, variants), tuple(variants), tiny[0].parent / "truth.json")
    table = pd.read_csv(tmp_path / "model_comparison.csv").set_index("model")
    for model in variants:
        assert load_from(tmp_path, model)["misfit"] is False
        if model != "baseline":
            assert table.loc[model, "elpd_diff_vs_first"] < 4 * max(table.loc[model, "elpd_diff_se"], 1.0)
            assert table.loc[model, "elpd_lomo_diff_vs_first"] < 4 * max(table.loc[model, "elpd_lomo_diff_se"], 1.0)
    assert table["plausible"].all() and table.loc["baseline", "reviewed"]


def load_from(out, model):
    return json.loads((out / model / "diagnostics.json").read_text())


def test_a_broken_plugin_is_refused_saying_what_is_missing(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("from gyrocal.model.effects import Effect\nclass E(Effect):\n    name = 'e'\nEFFECTS = [E()]\n")
    with pytest.raises(effects.PluginError, match="parameters is empty"):
        effects.load_plugins([bad])
    (tmp_path / "none.py").write_text("x = 1\n")
    with pytest.raises(effects.PluginError, match="must define EFFECTS"):
        effects.load_plugins([tmp_path / "none.py"])
    (tmp_path / "syntax.py").write_text("def (\n")
    with pytest.raises(effects.PluginError, match="failed to import"):
        effects.load_plugins([tmp_path / "syntax.py"])


def test_an_unknown_effect_or_a_model_without_the_baseline_is_refused():
    with pytest.raises(ValueError, match="unknown effect"):
        effects.resolve("m", BASE + ["nope"], {})
    with pytest.raises(ValueError, match="builds on the paper's baseline"):
        effects.resolve("m", ["scale_factor", "bias_drift"], {})
