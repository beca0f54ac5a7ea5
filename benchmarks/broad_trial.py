"""A BROAD trial through the plain commands: import, validate and the whole pipeline, its time,
CPU and peak memory, whole and per rule. Prints figures, asserts nothing.

    python benchmarks/broad_trial.py [TRIAL.mat] [--reference-interval S] [--keep DIR]

The trial (default: the fast one, ``../shared/data/broad/06_undisturbed_fast_rotation_A.mat``) is
taken whole: 197 s of rows at 285.714 Hz (about 2 minutes of motion between two rests), the gyro at
every row; the mapping keeps the reference every 0.1 s (``--reference-interval 0``: every row). Each
command is its own process, as a user runs it (`gyrocal import broad`, `gyrocal validate`,
``snakemake --cores 2 --config telemetry=...`` in an empty results directory); its wall time, CPU
(user + system, its child processes included) and peak resident memory (its largest process) come from
``wait4``. Per job: Snakemake's benchmark file (wall; its CPU and peak memory sampled every few
seconds) and the job's exact CPU and peak memory from ``peak_rss.json`` (`common.finish`). The load
average is printed before and after: the machine is shared, so compare ratios measured in one run.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TRIAL = ROOT.parent / "shared" / "data" / "broad" / "06_undisturbed_fast_rotation_A.mat"


def timed(command, cwd=None) -> dict:
    """Wall seconds, CPU seconds (user + system, its waited-for children included) and peak RSS (MB)
    of one command run as its own process; its output is kept for a failure's message."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), OPENBLAS_NUM_THREADS="1")
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        proc = subprocess.Popen(command, cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read().decode(errors="replace")
    if proc.returncode:
        sys.exit(f"{' '.join(map(str, command))} failed ({proc.returncode}):\n{text[-3000:]}")
    return {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime, "peak_mb": usage.ru_maxrss / 1024}


def per_rule(workdir: Path):
    """Per job: Snakemake's benchmark file (wall, sampled CPU and max RSS) and the job's exact CPU and peak."""
    import pandas as pd

    rows = []
    for f in sorted(Path(workdir, "logs").rglob("*.benchmark.tsv")):
        b = pd.read_csv(f, sep="\t").iloc[-1]
        peak = f.with_name(f.name.replace(".benchmark.tsv", ".peak_rss.json"))
        exact = json.loads(peak.read_text()) if peak.is_file() else {}
        rows.append({"job": str(f.relative_to(workdir / "logs")).replace(".benchmark.tsv", ""),
                     "wall_s": b["s"], "cpu_s": exact.get("cpu_s"), "sampled_cpu_s": b["cpu_time"],
                     "max_rss_mb": b["max_rss"], "peak_mb": exact.get("self_mb"), "children_mb": exact.get("children_mb")})
    return pd.DataFrame(rows).set_index("job").sort_values("wall_s", ascending=False)


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trial", nargs="?", type=Path, default=TRIAL, help="a BROAD trial (.mat)")
    parser.add_argument("--reference-interval", type=float, default=None,
                        help="passed to gyrocal import (0: every reference row); default: the mapping's")
    parser.add_argument("--keep", type=Path, default=None, help="run in this directory and keep it")
    args = parser.parse_args()
    if not args.trial.is_file():
        sys.exit(f"{args.trial}: no such BROAD trial (../shared/data/broad/README.md says where they come from)")
    gyrocal = [sys.executable, "-m", "gyrocal.pipeline.cli"]
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        campaign = work / "campaign"
        interval = [] if args.reference_interval is None else ["--reference-interval", str(args.reference_interval)]
        print(f"load average before: {load()}")
        figures = {"import": timed(gyrocal + ["import", "broad", *interval, str(campaign), str(args.trial)])}
        figures["validate"] = timed(gyrocal + ["validate", str(campaign)])
        figures["snakemake --cores 2"] = timed([sys.executable, "-m", "snakemake", "-s", str(ROOT / "workflow" / "Snakefile"),
                                                "--cores", "2", "-d", str(work), "-q", "--config",
                                                f"telemetry={campaign}"])
        rules = per_rule(work)
        verdict = json.loads(next((work / "results").glob("*/verdict.json")).read_text())
        print(f"load average after:  {load()}")
    kept = "the mapping's interval" if args.reference_interval is None else f"{args.reference_interval} s"
    print(f"trial {args.trial.name}, reference kept every {kept}")
    for name, f in figures.items():
        print(f"{name:22s} {f['wall_s']:7.1f} s wall {f['cpu_s']:7.1f} s CPU {f['peak_mb']:7.0f} MB peak RSS")
    print(f"verdict: {verdict.get('verdict')}")
    print("per job (wall_s, sampled_cpu_s, max_rss_mb: Snakemake's benchmark files; "
          "cpu_s, peak_mb: exact, the job's own):")
    print(rules.round(2).to_string())


if __name__ == "__main__":
    main()
