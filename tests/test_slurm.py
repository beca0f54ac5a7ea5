"""A fleet through Slurm with profiles/slurm gives the same numbers as the same fleet run locally.

Needs a Slurm with an idle node and snakemake-executor-plugin-slurm (pip install -e '.[cluster]'):

    bash cluster/slurm-single-node.sh && python -m pytest -m slurm -s

Marked `slurm`, so the default run leaves it out; it skips, saying why, where there is no Slurm.
"""

import os
import re
import shutil
import subprocess
import sys
import time

import pytest

from conftest import DATA, ROOT

pytestmark = pytest.mark.slurm

SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "workflow" / "Snakefile")]
NAMES = ("sat_a", "sat_b", "sat_c")
TIMEOUT_S = 1800                      # each run; here 2 to 8 minutes


def _slurm_missing():
    """Why this machine cannot run the test, or None."""
    if shutil.which("sinfo") is None or shutil.which("sbatch") is None:
        return "no Slurm client (sinfo, sbatch): start one with `bash cluster/slurm-single-node.sh`"
    try:
        import snakemake_executor_plugin_slurm  # noqa: F401
    except ImportError:
        return "snakemake-executor-plugin-slurm is not installed: pip install -e '.[cluster]'"
    run = subprocess.run(["sinfo", "-h", "-N", "-o", "%n %T"], capture_output=True, text=True, check=False)
    if run.returncode != 0:
        return f"sinfo failed (is slurmctld running?): {run.stderr.strip()}"
    # `sinfo -t idle` would list a drained node too (IDLE+DRAIN); %T says "drained" for it.
    if not any(line.split()[1] in ("idle", "mixed") for line in run.stdout.splitlines() if len(line.split()) == 2):
        return "no Slurm node is idle: " + (run.stdout.strip() or "sinfo lists no node")
    return None


@pytest.fixture(scope="session")
def status_options():
    """Skips where there is no Slurm (before the fleet is made); else the plugin's status options.
    It queries job states with sacct, which needs accounting (slurmdbd); without it, squeue."""
    missing = _slurm_missing()
    if missing:
        pytest.skip(missing)
    run = subprocess.run(["sacct", "-n", "-X", "-o", "JobID"], capture_output=True, text=True, check=False)
    return [] if run.returncode == 0 else ["--slurm-status-command", "squeue"]


@pytest.fixture(scope="module")
def fleet(tiny, tmp_path_factory):
    """Three copies of the tiny campaign under three names, and the speed-up config."""
    root = tmp_path_factory.mktemp("slurm_fleet")
    for name in NAMES:
        shutil.copytree(tiny[0], root / "fleet" / name)
        meta = root / "fleet" / name / "campaign.yaml"
        meta.write_text(meta.read_text().replace("name: tiny", f"name: {name}"))
    shutil.copy(DATA / "short_chains.yaml", root / "fast.yaml")
    return root


def _run(fleet, work, options):
    work.mkdir()
    # The jobs run this checkout's gyrocal: sbatch passes the environment on (--export=ALL).
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")]))}
    start = time.monotonic()
    try:
        run = subprocess.run(SNAKEMAKE + options + ["-d", str(work), "--configfile", str(fleet / "fast.yaml"),
                                                    "--config", f"campaigns={fleet / 'fleet'}"],
                             cwd=work, env=env, capture_output=True, text=True, check=False, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired as hung:
        # A job the status query never sees end (sacct without accounting), or pending forever, would
        # hang Snakemake, which ignores SIGTERM while it waits; subprocess kills it. Its jobs go too.
        said = "".join(b.decode() if isinstance(b, bytes) else (b or "") for b in (hung.stdout, hung.stderr))
        run_id = re.search(r"SLURM run ID: (\S+)", said)
        if run_id:
            subprocess.run(["scancel", "--name", run_id.group(1)], check=False)
        pytest.fail(f"snakemake did not finish in {TIMEOUT_S} s:\n{said[-3000:]}")
    elapsed = time.monotonic() - start
    (work / "snakemake.out").write_text(run.stdout + run.stderr)
    assert run.returncode == 0, (run.stdout + run.stderr)[-4000:]
    return run.stdout + run.stderr, elapsed


def test_a_fleet_of_three_through_slurm_gives_the_local_runs_numbers_byte_for_byte(status_options, fleet):
    status = status_options
    said, slurm_s = _run(fleet, fleet / "slurm", ["--profile", str(ROOT / "profiles" / "slurm"), "--jobs", "4",
                                                  "--slurm-init-seconds-before-status-checks", "5",
                                                  "--slurm-keep-successful-logs"] + status)
    _, local_s = _run(fleet, fleet / "local", ["--cores", "2"])
    print(f"\nfleet of {len(NAMES)}: through Slurm {slurm_s:.0f} s (status by {'squeue' if status else 'sacct'}),"
          f" locally with --cores 2 {local_s:.0f} s")

    # Every job went through sbatch, with the profile's resources.
    assert "SLURM run ID" in said
    # per campaign: preprocess (with validation and classic), 3 per model (2: point estimate, posterior with
    # calibrate, diagnostics), report (with the comparison); and the fleet summary
    assert said.count("has been submitted with SLURM jobid") == 3 * (1 + 3 * 2 + 1) + 1, said[-3000:]
    logs = fleet / "slurm" / ".snakemake" / "slurm_logs"
    assert {p.name for p in logs.iterdir()} >= {f"rule_{r}" for r in ("preprocess", "point_estimate", "posterior", "diagnostics",
                                                                     "report", "fleet")}

    compared = 0
    for name in NAMES:
        local = fleet / "local" / "results" / name
        for calibration in sorted(local.glob("*/calibration.csv")):
            on_slurm = fleet / "slurm" / calibration.relative_to(fleet / "local")
            assert on_slurm.read_bytes() == calibration.read_bytes(), f"{on_slurm} differs from {calibration}"
            compared += 1
        assert (fleet / "slurm/results" / name / "verdict.json").read_bytes() == (local / "verdict.json").read_bytes()
    assert compared == 3 * 2                                 # three campaigns, two models each
    assert (fleet / "slurm/results/fleet/summary.csv").read_bytes() == (fleet / "local/results/fleet/summary.csv").read_bytes()
