"""The pre-uplink review report, in a real browser."""

import re
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest

from gyrocal.simulation import simulate

from conftest import DATA, config_with, run_campaign

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def hidden_run(tmp_path_factory, config):
    """The campaign with a hidden bias drift, run with the baseline model only."""
    root = tmp_path_factory.mktemp("hidden")
    simulate.run(DATA / "hidden_bias_drift.yaml", root / "sim")
    cfg = config_with(config, {"baseline": ["scale_factor", "misalignment", "bias"]})
    run_campaign(root / "sim" / "campaign", root / "out", cfg, ("baseline",), root / "sim" / "truth.json",
                 figures=True)  # the browser test counts its figures
    return root / "out"


def browser(report, shot):
    """Render in headless Chromium: the DOM it built, and a screenshot for a person to look at."""
    common = FLAGS + [f"--user-data-dir={shot.parent / 'profile'}"]
    dom = subprocess.run([CHROMIUM, *common, "--dump-dom", report.as_uri()], capture_output=True, text=True,
                         timeout=120, check=True).stdout
    subprocess.run([CHROMIUM, *common, "--window-size=1300,900", f"--screenshot={shot}", report.as_uri()],
                   capture_output=True, timeout=120, check=True)
    return dom


def test_default_campaign_review_says_go_with_the_papers_tables(mom_run):
    text = (mom_run[0] / "report.html").read_text()
    assert "class='verdict go'>GO<" in text
    for table in ("table1", "table2", "table3", "checks", "ranking", "comparison", "before-after", "accounting",
                  "orthogonality"):
        assert f'id="{table}"' in text or f"id='{table}'" in text
    assert "truth -1712" in text and "mc12" in text and "mis_roll" in text
    assert "<td>dtg1_roll.mis_pitch + dtg2_pitch.mis_roll</td>" in text  # the selected set's first pair
    assert "<p id='confounded'>None: every pair is told apart.</p>" in text
    assert ("<p id='reference-interval'>Reference interval (reference_interval_s): Every reference sample is used: "
            "the nominal error is not smooth at the sampling interval") in text
    all_channels = text[text.index('id="table2"'):text.index("The model against the measurements")]
    combined = [c for c in re.findall(r"<td>(.*?)</td>", all_channels) if "OUTSIDE" in c]
    of_combinations = [c for c in re.findall(r"<tr>(.*?)</tr>", all_channels, re.S)
                       for c in re.findall(r"<td>(.*?)</td>", c)[6:] if "OUTSIDE" in c]   # table 2's sf_mean, sf_asym
    assert len(combined) - len(of_combinations) <= 2   # at least 22 of the 24 parameters' intervals cover the truth
    assert len(of_combinations) <= 2                   # and 10 of the 12 combinations'


def test_hidden_effect_with_baseline_only_is_no_go_naming_the_reason(hidden_run):
    text = (hidden_run / "report.html").read_text()
    assert "class='verdict nogo'>NO-GO<" in text
    assert "misfit: structure" in text
    assert "Best explanation: effect bias_drift" in text or "Best explanation: signature time" in text


@pytest.mark.full
def test_a_plan_that_cannot_tell_two_effects_apart_gives_no_go_naming_both(tmp_path_factory, config):
    """One rate per direction: a rate-squared scale factor (hidden here, 2000 ppm at the flown
    rate) looks like the scale factor itself. Both variants fit; the baseline's intervals are
    narrow and wrong, the other's honestly wide. The review must not say GO."""
    root = tmp_path_factory.mktemp("confounded")
    simulate.run(DATA / "onerate_nonlinearity.yaml", root / "sim")
    variants = {"baseline": ["scale_factor", "misalignment", "bias"],
                "nonlinear": ["scale_factor", "misalignment", "bias", "sf_nonlinearity"]}
    run_campaign(root / "sim" / "campaign", root / "out", config_with(config, variants), tuple(variants),
                 root / "sim" / "truth.json")
    text = (root / "out" / "report.html").read_text()
    assert "class='verdict nogo'>NO-GO<" in text
    why = text[text.index("the answer does not hang on the model"):]
    why = why[:why.index("</tr>")]
    assert "the data cannot tell baseline from nonlinear" in why
    assert "under nonlinear known only within" in why and "sf_nonlinearity: a second rotation rate in each direction" in why
    # the two yaw channels, both read against the one star tracker with its boresight near yaw
    confounded = text[text.index("Pairs the data cannot separate"):text.index("What the residuals point to")]
    assert 'id="confounded"' in confounded and "<td>dtg2_yaw.sf_pos</td>\n      <td>dtg3_yaw.sf_pos</td>" in confounded


@pytest.mark.browser
@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (tests/run.sh installs it)")
def test_report_renders_in_a_real_browser_with_verdict_and_tables(mom_run, hidden_run, tmp_path):
    """The DOM Chromium builds holds the verdict banner first, styled by its class, and every
    table; the screenshot is kept beside the test's files for a person to look at."""
    import matplotlib.image as mpimg
    for run, verdict in ((mom_run[0], "GO"), (hidden_run, "NO-GO")):
        css_class = "go" if verdict == "GO" else "nogo"
        shot = tmp_path / f"{css_class}.png"
        dom = browser(run / "report.html", shot)
        banner = f'<div id="verdict" class="verdict {css_class}">{verdict}</div>'
        assert banner in dom
        assert dom.index(banner) < dom.index("Checks behind the verdict") < dom.index('id="table1"')
        assert {"go": ".go{background:#1e7d32}", "nogo": ".nogo{background:#c62828}"}[css_class] in dom
        for table in ("table1", "table2", "table3", "checks", "ranking", "comparison", "before-after", "accounting"):
            assert f'id="{table}"' in dom
        assert dom.count("<img") >= 8
        assert mpimg.imread(shot).shape[:2] == (900, 1300)


def test_figures_drawn_by_two_processes_are_the_same_png_bytes(tmp_path):
    from gyrocal.report import figures as plots
    t = np.arange(50.0)
    table = pd.DataFrame({"time": t, "rate_roll_deg_s": np.sin(t), "rate_pitch_deg_s": 0.0, "rate_yaw_deg_s": 0.1,
                          **{f"set0_error_{a}_arcsec": np.cos(t * k) for k, a in enumerate(("yaw", "roll", "pitch"))}})
    jobs = [("maneuver_figure", (table, f"figure {i}")) for i in range(3)]
    one = plots.render_all(jobs, 1, dpi=40)
    two = plots.render_all(jobs, 2, dpi=40)
    assert one == two and len(one) == 3 and all(p.startswith(b"\x89PNG") for p in one)


def test_a_review_without_figures_says_so_in_each_ones_place(tiny_short_run):
    """``report.figures: false`` (the test runs' default, `conftest.run_campaign`): no figure is
    drawn, and each one's place says why; the tables and the verdict are there as ever."""
    from gyrocal.report.review import NOT_DRAWN
    html = (tiny_short_run[0] / "report.html").read_text()
    assert "<img" not in html and html.count(NOT_DRAWN) >= 8
    assert "id='verdict'" in html and 'id="table1"' in html and "id='checks'" in html
    assert '<td>sigma_cross_arcsec</td>' in html[html.index('id="noise-scales"'):]   # white noise: no clock
    assert "id='noise-clock'" not in html
