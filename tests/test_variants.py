"""Which model variants run (config ``run_models``), a variant refused or skipped without stopping the
others, and a report that says nothing empty or wrong about them."""

import json
import re
import shutil

import pandas as pd
import pytest
import yaml

from gyrocal.errors import InputError
from gyrocal.inference.sampling.refusals import VariantSkipped, check_variant_informed
from gyrocal.io.calibration import parameter_rows
from gyrocal.model import effects
from gyrocal.model.channels import MOM_CHANNELS, Channel
from gyrocal.model.spec import ModelSpec
from gyrocal.pipeline import run
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.settings import models_to_run
from gyrocal.report import review
from gyrocal.simulation import simulate

from conftest import DATA, ROOT, config_with

BASE = ["scale_factor", "misalignment", "bias"]
DEFINED = {"baseline": BASE, "bias_drift": BASE + ["bias_drift"], "symmetric": ["scale_factor_symmetric"] + BASE[1:]}


def test_run_models_chooses_the_variants_and_the_first_is_the_reference():
    assert models_to_run({"models": {"symmetric": [], "baseline": []}}) == ["baseline", "symmetric"]
    assert models_to_run({"models": DEFINED, "run_models": ["symmetric", "baseline"]}) == ["symmetric", "baseline"]
    with pytest.raises(InputError, match=r"run_models names \['latency'\], which models: does not define; defined: "
                                         r"\['baseline', 'bias_drift', 'symmetric'\]"):
        models_to_run({"models": DEFINED, "run_models": ["baseline", "latency"]})


def test_the_default_config_defines_the_symmetric_model_and_runs_every_variant(config):
    assert config["models"]["symmetric"] == ["scale_factor_symmetric", "misalignment", "bias"]
    assert config["run_models"] == [] and models_to_run(config) == ["baseline", "bias_drift", "symmetric"]
    from snakemake.utils import validate
    validate({**config, "run_models": ["symmetric"]}, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))


def test_a_variant_whose_added_parameters_are_all_prior_only_is_skipped_saying_why():
    spec = ModelSpec.build("bias_drift", effects.resolve("bias_drift", DEFINED["bias_drift"], {}), MOM_CHANNELS)
    labels = [p.label for p in spec.extras]
    check_variant_informed(spec.with_prior_only(dict.fromkeys(labels[1:], "weak")))
    with pytest.raises(VariantSkipped, match=r"model bias_drift skipped: every parameter its bias_drift adds is "
                                             r"prior-only.*dtg1_roll\.bias_drift \(weak\); .*; and 3 more"):
        check_variant_informed(spec.with_prior_only(dict.fromkeys(labels, "weak")))
    check_variant_informed(ModelSpec.build("b", effects.resolve("b", BASE, {}), MOM_CHANNELS))


def test_the_report_calls_dtgs_dtgs_and_a_mems_triad_gyros():
    mems = (Channel("gyro_x", None, "roll"), Channel("gyro_y", None, "pitch"), Channel("gyro_z", None, "yaw"))
    assert review.channel_kind(MOM_CHANNELS) == "DTG" and review.channel_kind(mems) == "gyro"
    rows = [{"channel": c.name, "parameter": p, "unit": "ppm", "point": 1.0, "mean": 1.0, "ci95_low": 0.0,
             "ci95_high": 2.0} for c in mems for p in ("sf", "mis_roll", "mis_pitch", "mis_yaw")]
    tables = review.paper_tables(pd.DataFrame(rows), mems, ("gyro_x", "gyro_y", "gyro_z"))
    assert "DTG" not in tables["table2"].columns and "DTG" not in tables["table3"].columns
    assert tables["table2"].loc[0, "positive scale factor (ppm)"] == tables["table2"].loc[0, "negative scale factor (ppm)"]


def test_a_single_short_trial_skips_bias_drift_and_with_nothing_left_the_review_is_refused(tmp_path, short_chains):
    """One 50-s yaw turn: the drift's ramp is below the noise (its data carry under 1 % of its prior's
    information), so bias_drift is skipped, with its record; the only variant skipped, nothing is left."""
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    scenario["maneuvers"] = [{"id": "yaw_pos", "axis": "yaw", "direction": "+", "rate_deg_s": 3.0, "accel_deg_s2": 1.0,
                              "hold_s": 10.0}]
    (tmp_path / "short.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(tmp_path / "short.yaml", tmp_path / "sim")
    cfg = config_with(short_chains, DEFINED)
    cfg["sampler"] = {**cfg["sampler"], "block_s": 10}
    paths = CampaignPaths.under(tmp_path / "out")
    ids = run.calibrate_campaign(tmp_path / "sim" / "campaign", paths, cfg, ["bias_drift"], figures=False)
    record = json.loads((tmp_path / "out" / "bias_drift" / "refused.json").read_text())
    assert record["status"] == "skipped" and record["step"] == "point_estimate"
    assert record["reason"].startswith("model bias_drift skipped: every parameter its bias_drift adds is prior-only")
    assert "of its prior's information" in record["reason"]
    assert json.loads((tmp_path / "out" / "bias_drift" / "posterior.nc").read_text()) == record  # sampled nothing
    with pytest.raises(InputError, match=r"every model variant was refused or skipped.*\[bias_drift, skipped at "
                                         r"point_estimate\] model bias_drift skipped"):
        run.review_campaign(paths, ids, cfg, ["bias_drift"])


EMPTY = re.compile(r":\s*[.;,)]|:\s*$|\(\s*\)|;\s*[.;]|,\s*[.;]")
"""An empty list where a reason expected one: ": .", ": ;", "()", "; ." and the like."""


def reasons(out, models) -> list:
    """Every reason text a run wrote: the verdict's checks, each variant's misfit checks, refusals."""
    texts = [c["why"] for c in json.loads((out / "verdict.json").read_text())["checks"]]
    texts += [c["action"] for c in json.loads((out / "verdict.json").read_text())["checks"] if c.get("action")]
    for m in models:
        if (out / m / "refused.json").exists():
            texts.append(json.loads((out / m / "refused.json").read_text())["reason"])
        else:
            texts += [c["why"] for c in json.loads((out / m / "diagnostics.json").read_text())["checks"]]
    return texts


@pytest.fixture(scope="module")
def variants_run(tiny_run, short_chains, tmp_path_factory):
    """The tiny campaign's baseline run (`tiny_run`) with the symmetric model and a variant refused
    (g_sensitivity: the campaign has no accelerometer columns) beside it, then the review."""
    out = tmp_path_factory.mktemp("variants")
    shutil.copytree(tiny_run[0], out, dirs_exist_ok=True)
    paths = CampaignPaths.under(out)
    ids = json.loads((out / "input.json").read_text())["maneuvers"]
    models = ["baseline", "symmetric", "g_sensitivity"]
    cfg = config_with(short_chains, {**DEFINED, "g_sensitivity": BASE + ["g_sensitivity"]})
    run.calibrate_models(paths, ids, cfg, models[1:])
    run.review_campaign(paths, ids, cfg, models)
    return out, models


def test_a_refused_variant_is_recorded_and_the_others_are_compared_and_reviewed(variants_run):
    out, _ = variants_run
    record = json.loads((out / "g_sensitivity" / "refused.json").read_text())
    assert record["status"] == "refused" and record["step"] == "point_estimate"
    assert "g_sensitivity needs 'acc_x'" in record["reason"] and "leave g_sensitivity out" in record["reason"]
    assert list(pd.read_csv(out / "model_comparison.csv")["model"]) == ["baseline", "symmetric"]
    html = (out / "report.html").read_text()
    refused = html[html.index('<table id="refused"'):]
    assert "effect g_sensitivity needs" in refused[:refused.index("</table>")]
    reviewed = json.loads((out / "verdict.json").read_text())["model"]
    rule = html[html.index("<p id='reviewed-rule'>"):]
    rule = rule[:rule.index("</p>")]
    assert rule.startswith(f"<p id='reviewed-rule'>{reviewed} is reviewed: ") and "plausible variant" in rule
    assert "all DTG channels" in html


def test_the_symmetric_model_writes_one_sf_per_channel_and_the_same_correction_both_ways(variants_run):
    out, _ = variants_run
    full = pd.read_csv(out / "symmetric" / "calibration.csv")
    table = parameter_rows(full)
    assert set(table.loc[table["unit"] == "ppm", "parameter"]) == {"sf"} and (table["parameter"] == "sf").sum() == 6
    derived = full.drop(table.index)  # sf_mean is sf itself; a symmetric model has no sf_asym
    assert set(derived["parameter"]) == {"sf_mean"}
    sf = table[table["parameter"] == "sf"].set_index("channel")["mean"]
    assert derived.set_index("channel")["mean"].loc[sf.index].to_numpy() == pytest.approx(sf.to_numpy(), rel=1e-12)
    for s in json.loads((out / "symmetric" / "correction.json").read_text())["sets"]:
        assert s["scale_correction_pos"] == s["scale_correction_neg"] and s["matrix_pos"] == s["matrix_neg"]


def test_no_reason_text_ends_in_an_empty_list(variants_run, tiny_run):
    out, models = variants_run
    texts = reasons(out, models) + reasons(tiny_run[0], ["baseline"])
    assert texts and not [t for t in texts if EMPTY.search(t) or not t.strip()]
    html = (out / "report.html").read_text()
    assert not re.search(r":\s*\.\s*<", html)


@pytest.mark.full
def test_where_the_gyros_are_symmetric_the_symmetric_model_is_reviewed_by_the_rule(tmp_path, config):
    """The tiny campaign flown with sf_neg = sf_pos on every channel: the per-direction baseline
    spends a parameter per channel on an asymmetry that is not there, so with a maneuver left out
    it knows that direction's scale factor only from its prior, and the symmetric variant, which
    takes it from the other direction, predicts better (by 62 nats at short chains). The rule
    reviews the symmetric variant, and its intervals cover each true sf."""
    scenario = yaml.safe_load((DATA / "tiny.yaml").read_text())
    for terms in scenario["truth"].values():
        terms["sf_neg"] = terms["sf_pos"]
    (tmp_path / "symmetric.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(tmp_path / "symmetric.yaml", tmp_path / "sim")
    cfg = config_with(config, DEFINED)
    cfg["run_models"] = ["baseline", "symmetric"]
    run.run_campaign(tmp_path / "sim" / "campaign", CampaignPaths.under(tmp_path / "out"), cfg)
    table = pd.read_csv(tmp_path / "out" / "model_comparison.csv")
    assert list(table["model"]) == ["baseline", "symmetric"]
    assert table.loc[table["reviewed"], "model"].item() == "symmetric" and table.loc[1, "plausible"]
    assert json.loads((tmp_path / "out" / "verdict.json").read_text())["model"] == "symmetric"
    cal = pd.read_csv(tmp_path / "out" / "symmetric" / "calibration.csv").set_index(["channel", "parameter"])
    for channel, terms in scenario["truth"].items():
        row = cal.loc[(channel, "sf")]
        assert row["ci95_low"] <= terms["sf_pos"] <= row["ci95_high"], (channel, row.to_dict())
    html = (tmp_path / "out" / "report.html").read_text()
    assert "symmetric is reviewed: the only plausible variant of the 2 compared" in html
