"""The model-criticism loop closed in one run (gyrocal.criticism.extension, pipeline.steps.extend), and
the review a person can read (report.review): the checks one table, each detail folded past three
lines, the loop's error before and after."""

import copy
import json
import re
from html import unescape
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml

from gyrocal.criticism.extension import extension_names, next_effect
from gyrocal.pipeline import run
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.report.review import FOLD_CHARS, fold
from gyrocal.simulation import simulate

from conftest import DATA

BASE = ["scale_factor", "misalignment", "bias"]


def diagnostics(misfit=True, ranking=(("effect", "st_correlated_noise", -40.0),)):
    return {"misfit": misfit, "ranking": [{"kind": k, "name": n, "log10_p": p} for k, n, p in ranking]}


def test_a_misfit_a_significant_library_effect_explains_is_extended_by_it():
    step = next_effect("baseline", BASE, diagnostics(), -6.0)
    assert step.fitted and step.effect == "st_correlated_noise" and step.effects == BASE + ["st_correlated_noise"]
    assert step.as_dict()["fitted"] is True and step.base == "baseline"


@pytest.mark.parametrize("doc, present", [
    (diagnostics(misfit=False), BASE),                                               # no misfit
    (diagnostics(ranking=(("effect", "bias_drift", -3.0),)), BASE),                  # not significant
    (diagnostics(ranking=(("signature", "rate_sign", -30.0),)), BASE),               # a signature, no effect
    (diagnostics(ranking=(("effect", "cyclic_error", -30.0),)), BASE),               # a plugin's, not the library's
    (diagnostics(ranking=(("effect", "bias_drift", -30.0),)), BASE + ["bias_drift"]),  # has it already
    (diagnostics(ranking=()), BASE),                                                 # nothing ranked
])
def test_anything_else_stops_the_loop_with_its_reason(doc, present):
    step = next_effect("m", present, doc, -6.0)
    assert not step.fitted and step.effects == present and step.why.startswith("model m ")


def test_a_gauss_markov_model_whose_ranking_names_the_jitter_is_extended_by_it_and_the_model_builds():
    """The reviewed model has Gauss-Markov reference noise and its ranking names the timing jitter (a
    RepoIMU run with config/tstick.yaml): the loop extends it by st_jitter, and the model with both has
    the two noise models (`covariance.noise_scales`: six scales)."""
    from gyrocal.model import effects
    from gyrocal.model.channels import Channel
    from gyrocal.model.spec import ModelSpec

    present = BASE + ["st_correlated_noise"]
    step = next_effect("m", present, diagnostics(ranking=(("effect", "st_jitter", -30.0),)), -6.0)
    assert step.fitted and step.effect == "st_jitter" and step.effects == present + ["st_jitter"]
    both = ModelSpec.build("both", effects.resolve("both", step.effects, {}), [Channel("gyro_x", None, "roll")])
    assert both.correlated_noise and both.jitter_noise


def test_the_loops_variants_are_named_by_their_step():
    assert extension_names(0) == [] and extension_names(2) == ["extended", "extended_2"]


def test_a_long_detail_shows_three_lines_and_folds_the_rest_a_short_one_is_whole():
    short = "every parameter has r_hat < 1.01"
    assert unescape(str(fold(short))) == short and "<details" not in str(fold(short))
    long = "; ".join(f"dtg{k}_roll.sf_pos differs by {k},000.0 ppm ({k}.5 sd)" for k in range(40))
    folded = str(fold(long))
    shown, rest = folded.split("<details", 1)
    assert len(shown) <= FOLD_CHARS and shown.rstrip().endswith(";") and "</details>" in rest
    assert re.sub(r"<[^>]+>|more", "", folded).replace(" ", "") == long.replace(" ", "")
    assert "&lt;b&gt;" in str(fold("<b>" + long))   # escaped, folded or not


class _Review(HTMLParser):
    """The parts of report.html the tests read: the rows of each table by id, the text of a paragraph by id."""

    def __init__(self):
        super().__init__()
        self.tables, self.paragraphs, self._table, self._row, self._cell, self._p, self._fold = {}, {}, None, None, None, None, 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table":
            self._table = attrs.get("id")
            self.tables.setdefault(self._table, [])
        elif tag == "tr" and self._table is not None:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = {"shown": "", "folded": ""}
        elif tag == "details":
            self._fold += 1
        elif tag == "p" and attrs.get("id"):
            self._p = attrs["id"]
            self.paragraphs[self._p] = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell)
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag == "table":
            self._table = None
        elif tag == "details":
            self._fold -= 1
        elif tag == "p":
            self._p = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell["folded" if self._fold else "shown"] += data
        if self._p is not None:
            self.paragraphs[self._p] += data


def test_the_review_shows_the_checks_as_one_table_of_short_details_and_a_one_sentence_reason(tiny_run):
    out, _ = tiny_run
    page = _Review()
    page.feed((out / "report.html").read_text())
    verdict = json.loads((out / "verdict.json").read_text())
    checks = page.tables["checks"]
    assert [c["shown"] for c in checks[0]][:3] == ["check", "result", "detail"]
    assert [r[0]["shown"] for r in checks[1:]] == [c["check"] for c in verdict["checks"]]
    assert all(len(r[2]["shown"]) <= FOLD_CHARS for r in checks[1:])
    reason = page.paragraphs["reviewed-why"].strip()
    assert reason.startswith("baseline is reviewed") and reason.count(". ") == 0 and not re.search(r"\d\.\d", reason)
    assert "loop" not in page.tables and "disagreement" not in page.tables   # nothing fitted, nothing disagrees


def test_where_the_reviewed_model_fits_the_loop_skips_its_variant_with_the_reason(tiny_run, config, tmp_path):
    """The default campaign's case: the loop's step reads the diagnostics and stops, fitting nothing."""
    import shutil

    from gyrocal.pipeline.steps import common
    out, _ = tiny_run
    shutil.copytree(out, tmp_path / "run")
    paths = CampaignPaths.under(tmp_path / "run")
    ids = json.loads(Path(paths.input_json).read_text())["maneuvers"]
    cfg = copy.deepcopy(config)
    cfg["models"] = {"baseline": BASE}
    assert json.loads(Path(paths.model("baseline").diagnostics).read_text())["misfit"] is False
    assert run.extend_models(paths, ids, cfg, ["baseline"]) == ["extended"]
    step = json.loads(Path(paths.model("extended").extension).read_text())
    assert not step["fitted"] and step["why"] == "model baseline has no misfit: nothing to extend"
    assert common.read_refusal(paths.model("extended").refusal)["status"] == "skipped"
    assert common.compared(["baseline", "extended"], paths.per_model(["baseline", "extended"]).diagnostics) == ["baseline"]
    assert common.read_refusal(paths.model("extended").point_estimate)["reason"].startswith("not fitted")


@pytest.fixture(scope="module")
def loop_run(tmp_path_factory, short_chains):
    """The tiny campaign with Gauss-Markov star-tracker noise (tau 3 s, as large as the white), run as
    the workflow runs it with one variant, the white baseline: the loop fits the correlated model."""
    out = tmp_path_factory.mktemp("loop")
    scenario = yaml.safe_load((DATA / "hidden_st_correlated_noise.yaml").read_text())
    scenario["star_tracker"].update(gm_sigma_cross_arcsec=5.0, gm_sigma_about_arcsec=20.0, gm_tau_s=3.0)
    scenario["effects"] = {}
    (out / "scenario.yaml").write_text(yaml.safe_dump(scenario))
    simulate.run(out / "scenario.yaml", out)
    cfg = copy.deepcopy(short_chains)
    cfg["models"], cfg["run_models"] = {"baseline": BASE}, []
    paths = CampaignPaths.under(out / "results")
    run.run_campaign(out / "campaign", paths, cfg, truth_json=out / "truth.json")
    return paths


@pytest.mark.full  # the correlated model's posterior: about 2 minutes
def test_the_white_models_misfit_is_named_and_the_extended_model_is_fitted_in_the_same_run(loop_run):
    step = json.loads(Path(loop_run.model("extended").extension).read_text())
    assert step["fitted"] and (step["base"], step["effect"]) == ("baseline", "st_correlated_noise")
    before = json.loads(Path(loop_run.model("baseline").diagnostics).read_text())
    after = json.loads(Path(loop_run.model("extended").diagnostics).read_text())
    assert before["misfit"] and before["ranking"][0]["name"] == "st_correlated_noise"
    assert abs(after["whiteness"]["z"]) < abs(before["whiteness"]["z"]) / 2
    verdict = json.loads(Path(loop_run.verdict).read_text())
    assert verdict["model"] == "extended"


@pytest.mark.full
def test_the_review_shows_the_loop_before_and_after(loop_run):
    page = _Review()
    page.feed(Path(loop_run.report).read_text())
    verdict = json.loads(Path(loop_run.verdict).read_text())
    checks = page.tables["checks"][1:]
    assert [r[0]["shown"] for r in checks] == [c["check"] for c in verdict["checks"]]
    assert all(len(r[2]["shown"]) <= FOLD_CHARS for r in checks)
    loop = page.tables["loop"]
    header = [c["shown"] for c in loop[0]]
    assert [r[header.index("model")]["shown"] for r in loop[1:]] == ["baseline", "extended"]
    z = [abs(float(r[header.index("whiteness z")]["shown"])) for r in loop[1:]]
    assert z[1] < z[0] / 2
    reason = page.paragraphs["reviewed-why"].strip()
    assert reason.count(". ") == 0 and not re.search(r"\d+\.\d", reason)


def test_a_latency_the_acceleration_signature_also_explains_is_ranked_first_and_extends_the_model():
    """tests/data/hidden_st_latency.yaml at 50 ms, seed 7: the latency and the acceleration signature each
    leave nothing significant given the other (leftover log10 p -0.49 and -0.01, noise), so the latency,
    the more significant (one parameter against six), leads, and the loop fits it; ordered by the leftover
    alone the signature would lead and the loop would stop at it."""
    from gyrocal.study.baseline import baseline_ranking

    scenario = simulate.load_scenario(DATA / "hidden_st_latency.yaml")
    scenario["effects"]["st_latency_s"] = 0.05
    cfg = yaml.safe_load((DATA.parents[1] / "config" / "config.yaml").read_text())
    _, _, _, ranking = baseline_ranking(simulate.simulate(scenario)[0], cfg["noise"])
    latency, signature = ranking[0], ranking[1]
    assert (latency["name"], signature["name"]) == ("st_latency", "acceleration")
    assert latency["log10_p"] < signature["log10_p"] < -1000
    assert -2 < latency["leftover_log10_p"] < signature["leftover_log10_p"]
    step = next_effect("baseline", BASE, {"misfit": True, "ranking": ranking}, cfg["diagnostics"]["structure_log10_p_min"])
    assert step.effect == "st_latency"


def test_a_signature_a_library_effect_explains_as_well_extends_the_model_by_that_effect():
    """One rate per direction (battery campaign 6): rate_sign leads (log10 p -200.6), sf_nonlinearity
    explains the same misfit (each leaves the other nothing: leftover log10 p -0.04 and -0.0); the loop
    fits sf_nonlinearity, where it stopped at the signature. Where the effect leaves the signature
    significant, or the signature leaves the effect so, it still stops."""
    def doc(lead_left, effect_left):
        return {"misfit": True, "ranking": [
            {"kind": "signature", "name": "rate_sign", "log10_p": -200.6, "leftover_log10_p": lead_left},
            {"kind": "effect", "name": "sf_nonlinearity", "log10_p": -104.0, "leftover_log10_p": effect_left},
            {"kind": "effect", "name": "st_correlated_noise", "log10_p": -62.0}]}

    step = next_effect("baseline", BASE, doc(-0.04, -0.0), -6.0)
    assert step.fitted and step.effect == "sf_nonlinearity"
    assert step.why.endswith("signature rate_sign (log10 p = -200.6), first, is no library effect, and "
                             "sf_nonlinearity explains the same misfit (given it, the other leaders' log10 p = -0.0)")
    for lead_left, effect_left in ((-0.04, -30.0), (-30.0, -0.0)):
        assert not next_effect("baseline", BASE, doc(lead_left, effect_left), -6.0).fitted


def test_where_every_variant_is_refused_the_loop_extends_the_first_whose_refusal_advises_a_library_effect():
    from gyrocal.pipeline.steps.extend import advised
    plain = {"model": "symmetric", "status": "refused", "step": "posterior", "reason": "a gap"}
    advising = {"model": "baseline", "status": "refused", "step": "posterior", "reason": "correlated: add it",
                "advice": "st_correlated_noise", "effects": ["scale_factor", "misalignment", "bias"]}
    step = advised(["symmetric", "baseline"], [plain, advising])
    assert (step.base, step.effect, step.effects, step.fitted) == (
        "baseline", "st_correlated_noise", ["scale_factor", "misalignment", "bias", "st_correlated_noise"], True)
    assert "every variant was refused; model baseline's refusal (posterior) advises adding st_correlated_noise" in step.why
    assert not advised(["symmetric"], [plain]).fitted
    unknown = {**advising, "advice": "no_such_effect"}
    assert not advised(["baseline"], [unknown]).fitted


def test_a_later_step_whose_base_was_refused_takes_the_advice_of_its_refusal(tmp_path):
    """BROAD's slow trial at the default variants: the first step added st_jitter, whose fit was refused
    advising st_correlated_noise; the second step extends the model the first one extended by that advice,
    leaving out the effect whose fit was refused, instead of stopping. A refusal without advice still stops
    the loop with its reason."""
    from types import SimpleNamespace

    from gyrocal.pipeline.steps import extend

    settings = SimpleNamespace(loop={"depth": 2})   # a later step reads the loop's depth alone
    effects = ["scale_factor_symmetric", "misalignment", "bias", "st_jitter"]
    refused = {"model": "extended", "status": "refused", "step": "point_estimate", "reason": "white noise cannot fit",
               "advice": "st_correlated_noise", "effects": effects}
    (tmp_path / "diagnostics.json").write_text(json.dumps(refused))
    files = SimpleNamespace(diagnostics=[tmp_path / "diagnostics.json"])
    step = extend.decide("extended_2", ["extended"], files, settings)
    assert (step.base, step.effect) == ("extended", "st_correlated_noise")
    assert step.effects == ["scale_factor_symmetric", "misalignment", "bias", "st_correlated_noise"]  # no st_jitter
    assert step.why.startswith("the loop's step extended (+ st_jitter) was refused (point_estimate), and its refusal")
    (tmp_path / "diagnostics.json").write_text(json.dumps({k: v for k, v in refused.items()
                                                           if k not in ("advice", "effects")}))
    step = extend.decide("extended_2", ["extended"], files, settings)
    assert not step.fitted and step.why == "the loop stopped at extended: white noise cannot fit"


def test_a_refusal_that_advises_an_effect_is_recorded_with_it_and_read_back_as_a_refusal(tmp_path):
    from gyrocal.inference.sampling.refusals import EstimateError
    from gyrocal.pipeline.steps import common

    def refuse():
        raise EstimateError("the fitted noise is not a noise these sensors can have", advice="st_correlated_noise",
                            effects=("scale_factor", "misalignment", "bias"))

    record = common.variant_step(tmp_path / "refused.json", "baseline", "posterior", refuse, [tmp_path / "fit.csv"])
    assert record["advice"] == "st_correlated_noise" and record["effects"] == ["scale_factor", "misalignment", "bias"]
    assert common.read_refusal(tmp_path / "fit.csv") == record
    import jsonschema
    schema = json.loads((Path(common.__file__).parents[2] / "io" / "schemas" / "refusal.schema.json").read_text())
    jsonschema.validate(record, schema)
