"""An interrupted run resumes with the plain command, and gives what an uninterrupted run gives.

A run stopped while the posterior runs leaves that job marked incomplete in ``.snakemake/``, and some of
its outputs may exist; without ``rerun-incomplete`` (the workflow profile, ``workflow/profiles/default/``) the
plain rerun stopped with IncompleteFilesException. Each file is written whole or not at all
(`gyrocal.io.outputs`), and Snakemake deletes every output of an incomplete job before it runs again.
"""

import json
import os
import signal
import subprocess
import time

import pytest
from test_workflow import SNAKEMAKE

TARGET = "results/tiny/baseline/calibration.csv"
"""The run stops at the baseline model's posterior job (preprocess, point estimate, posterior): the
rest of the workflow adds time, not another way to be interrupted."""
COMPARED = ("calibration.csv", "posterior_summary.csv", "fit.csv", "elpd_blocks.csv", "elpd_maneuvers.csv",
            "correction.json", "sampler.json", "posterior.nc")
"""The posterior rule's outputs, compared byte for byte (the InferenceData carries no creation time)."""


def plain(tiny, work):
    return SNAKEMAKE + [TARGET, "--cores", "2", "-d", str(work), "--config", f"telemetry={tiny[0]}"]


@pytest.fixture(scope="module")
def uninterrupted(tiny_run):
    """The baseline model's files of an uninterrupted run: `tiny_run`'s, the same steps at the same config
    and seed run by `gyrocal.pipeline.run` (the rules call the same step functions, and give the same
    bytes), made once for the whole test run."""
    return tiny_run[0] / "baseline"


def _default_sigint():
    """A terminal's Ctrl-C reaches Snakemake with SIGINT's default disposition; a pytest-xdist worker
    ignores SIGINT, and an ignored signal stays ignored in its children (Python then installs no
    KeyboardInterrupt handler), so the test restores the default in the child."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupted(tiny, work, sig, whole_group):
    """The plain command, stopped by ``sig`` once the posterior job has started: sent to Snakemake
    alone (``kill -INT PID``) or to its whole process group (Ctrl-C in a terminal, a batch system's
    kill), then waited for until every process of the run has ended."""
    run = subprocess.Popen(plain(tiny, work), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           start_new_session=True, preexec_fn=_default_sigint)
    started = work / "logs" / "tiny" / "baseline" / "posterior.log"
    deadline = time.monotonic() + 120
    while not started.exists():
        assert run.poll() is None and time.monotonic() < deadline, "the run ended before its posterior job started"
        time.sleep(0.05)
    time.sleep(0.5)  # the job is in its sampler (the default chains: several seconds on tiny, where short
    # chains ended within the wait on a quiet machine and nothing was interrupted)
    if whole_group:
        os.killpg(run.pid, sig)
    else:
        run.send_signal(sig)
    said, _ = run.communicate(timeout=120)
    while True:  # every job of the run has ended too
        try:
            os.killpg(run.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    return run.returncode, said


@pytest.mark.parametrize("sig, whole_group", [
    (signal.SIGINT, False),
    pytest.param(signal.SIGINT, True, marks=pytest.mark.full),
    pytest.param(signal.SIGTERM, True, marks=pytest.mark.full),
], ids=["SIGINT-to-snakemake", "SIGINT-to-the-group", "SIGTERM-to-the-group"])
def test_an_interrupted_run_resumes_with_the_plain_command(tiny, uninterrupted, tmp_path, sig, whole_group):
    work = tmp_path / "work"
    code, said = interrupted(tiny, work, sig, whole_group)
    assert code != 0, said[-3000:]
    results = work / "results" / "tiny" / "baseline"
    if not whole_group:
        # Snakemake alone stops: its running job ends, and leaves its outputs marked incomplete, the
        # case the plain rerun refused (IncompleteFilesException)
        assert any((results / name).exists() for name in COMPARED), said[-3000:]
        assert any((work / ".snakemake" / "incomplete").iterdir()), said[-3000:]

    rerun = subprocess.run(plain(tiny, work), capture_output=True, text=True, check=False)
    assert rerun.returncode == 0, rerun.stderr[-3000:]
    assert "IncompleteFilesException" not in rerun.stderr
    assert "rule posterior:" in rerun.stderr, rerun.stderr[-3000:]  # the job ran again
    for name in COMPARED:
        assert (results / name).read_bytes() == (uninterrupted / name).read_bytes(), name
    assert not [p for p in (work / "results").rglob(".*.tmp")], "a temporary file was left behind"
    # each job records its peak memory beside its log and benchmark file (common.finish)
    peak = json.loads((work / "logs" / "tiny" / "baseline" / "posterior.peak_rss.json").read_text())
    assert peak["self_mb"] > 50 and peak["children_mb"] >= 0
    assert "peak memory (RSS)" in (work / "logs" / "tiny" / "baseline" / "posterior.log").read_text()
