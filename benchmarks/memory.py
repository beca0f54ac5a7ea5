"""Peak memory and wall time per rule against the campaign's length: prints a table, asserts nothing.

    python benchmarks/memory.py [--factors 1 3 10] [--repeats 1] [--tree DIR ...]

The default MOM-like campaign flown k times over (its six maneuvers repeated, each copy its own
maneuver: ``benchmarks/scaling.py``'s ``repeated``) runs through the workflow as a user runs it,
``snakemake --cores 2`` with the default config from an empty directory, one BLAS thread a job. Each
job's peak resident memory is the one ``gyrocal.pipeline.steps.common.finish`` records beside its log
(``logs/<campaign>/**/<rule>.peak_rss.json``, from ``getrusage``: exact however short the peak, where
Snakemake's ``benchmark.tsv`` samples every few seconds); its wall time is from the rule's
benchmark file. A rule with a job per model shows its larger job. preprocess and the report draw
their figures in two forked worker processes: their column shows the job's own process and, after
``+``, its largest worker, whose resident pages are mostly the job's, shared. The PSS column is the
job's own memory, shared pages counted once: the summed proportional set size of the job's process
and its workers, sampled every 50 ms while the workflow runs.

``--repeats N`` runs each factor N times and shows the medians (the machine is shared: compare
ratios within one call). ``--tree DIR`` runs another checkout of gyrocal (its Snakefile and its
``src``), e.g. an older commit; given more than once, the checkouts' runs take turns (factor by
factor, repeat by repeat), so that a before-and-after comparison shares the machine's load, and
each gets its table, with the whole run's wall time over the first checkout's.
"""

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import yaml
from scaling import repeated

ROOT = Path(__file__).resolve().parents[1]
RULES = ("simulate", "preprocess", "point_estimate", "posterior", "diagnostics", "report")


def run(tree: Path, k: int) -> dict:
    """One run of the campaign flown ``k`` times: the whole run's wall seconds, and each rule's
    largest job's peak memory (MB, own process and largest child) and wall seconds."""
    from gyrocal.simulation.simulate import load_scenario

    scenario = repeated(load_scenario(tree / "config/scenarios/mom.yaml"), k)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scenario.yaml"
        path.write_text(yaml.safe_dump(scenario))
        work = Path(tmp) / "work"
        env = {**os.environ, "PYTHONPATH": str(tree / "src"), "OPENBLAS_NUM_THREADS": "1"}
        start = time.perf_counter()
        snakefile = next(s for s in (tree / "workflow" / "Snakefile", tree / "Snakefile") if s.is_file())  # older: top level
        proc = subprocess.Popen([sys.executable, "-m", "snakemake", "-s", str(snakefile), "--cores", "2", "-q",
                                 "-d", str(work), "--config", f"scenario={path}"], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, env=env)
        pss = {}
        sampler = threading.Thread(target=sample_pss, args=(proc, pss), daemon=True)
        sampler.start()
        output = proc.communicate()[0]
        wall = time.perf_counter() - start
        sampler.join()
        if proc.returncode:
            raise subprocess.CalledProcessError(proc.returncode, proc.args, output)
        rules = {}
        for peak_file in sorted((work / "logs").rglob("*.peak_rss.json")):
            rule = peak_file.name.split(".")[0]
            peak = json.loads(peak_file.read_text())
            bench = peak_file.with_name(f"{rule}.benchmark.tsv").read_text().splitlines()
            seconds = float(bench[1].split("\t")[0])
            old = rules.get(rule, {"mb": 0.0, "child_mb": 0.0, "s": 0.0})
            rules[rule] = {"mb": max(old["mb"], peak["self_mb"]), "child_mb": max(old["child_mb"], peak["children_mb"]),
                           "s": max(old["s"], seconds), "pss_mb": pss.get(rule, float("nan"))}
    return {"wall": wall, "rules": rules}


def _children(pid: int) -> list:
    """The process's children, whichever of its threads started them (Snakemake starts jobs from a
    thread of its own)."""
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with contextlib.suppress(OSError):
            out += [int(c) for c in (task / "children").read_text().split()]
    return out


def _pss_mb(pid: int) -> float:
    """The process's proportional set size (MB of 10^6 bytes): its shared pages divided among their sharers."""
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            return next(int(line.split()[1]) for line in f if line.startswith("Pss:")) * 1024 / 1e6
    except (OSError, StopIteration):
        return 0.0


def sample_pss(proc, peaks: dict, every_s: float = 0.05):
    """Every ``every_s``, each job's summed PSS, its process and every process under it (the forked
    figure workers): the job's own memory, pages shared with its workers counted once. A job is the
    process that runs the rule's script, ``.snakemake/scripts/tmp....<rule>.py``; ``peaks`` gets the
    largest sum seen per rule (sampled: a peak shorter than ``every_s`` may be missed)."""
    while proc.poll() is None:
        stack = [proc.pid]
        while stack:
            pid = stack.pop()
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as f:
                    argv = f.read().split(b"\0")
            except OSError:
                continue
            script = next((a.decode() for a in argv if b".snakemake/scripts/" in a and a.endswith(b".py")), None)
            if script is None:
                stack += _children(pid)
                continue
            rule = script.rsplit(".", 2)[-2]
            tree, total = [pid], 0.0
            while tree:
                member = tree.pop()
                total += _pss_mb(member)
                tree += _children(member)
            peaks[rule] = max(peaks.get(rule, 0.0), total)
        time.sleep(every_s)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factors", type=int, nargs="+", default=[1, 3, 10])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--tree", type=Path, action="append",
                        help="a checkout to run (default: this one); more than one take turns")
    args = parser.parse_args()
    trees = [t.resolve() for t in args.tree or [ROOT]]
    runs = {tree: {k: [] for k in args.factors} for tree in trees}
    for k in args.factors:
        for _ in range(args.repeats):
            for tree in trees:
                runs[tree][k].append(run(tree, k))
        print(f"{k}x: {6 * k} maneuvers, run wall "
              + ", ".join(f"{wall(runs[tree][k]):.0f} s" for tree in trees) + f" (median of {args.repeats})", flush=True)
        for tree in trees:  # as measured, for a call stopped before its table
            print(f"  {tree}: " + json.dumps([r["rules"] for r in runs[tree][k]]), flush=True)
    for tree in trees:
        table(tree, runs[tree], args.factors, args.repeats)
    for tree in trees[1:]:
        print(f"\nwhole run's wall, {tree} over {trees[0]}: "
              + ", ".join(f"{k}x {wall(runs[tree][k]) / wall(runs[trees[0]][k]):.2f}" for k in args.factors))


def wall(runs) -> float:
    return statistics.median(r["wall"] for r in runs)


def table(tree: Path, runs: dict, factors, repeats: int):
    """One checkout's table: per rule, the median peaks and wall times at each factor."""

    def median(k, rule, key):
        values = [r["rules"][rule][key] for r in runs[k] if rule in r["rules"]]
        return statistics.median(values) if values else float("nan")

    first = factors[0]
    head = ("".join(f"{f'{k}x MB':>14s}" for k in factors) + "".join(f"{f'{k}x PSS':>9s}" for k in factors)
            + "".join(f"{f'{k}x s':>9s}" for k in factors))
    print(f"\n{tree}: peak RSS per job (own process + largest worker), the job's peak summed PSS (sampled) "
          f"and wall time of the rule's largest job, medians of {repeats}")
    print(f"{'rule':16s}{head}{'s ratio':>9s}")
    for rule in RULES:
        mem = ""
        for k in factors:
            own, child = median(k, rule, "mb"), median(k, rule, "child_mb")
            mem += f"{own:>14.0f}" if child < 1 else f"{f'{own:.0f} + {child:.0f}':>14s}"
        pss = "".join(f"{median(k, rule, 'pss_mb'):9.0f}" for k in factors)
        secs = "".join(f"{median(k, rule, 's'):9.1f}" for k in factors)
        ratio = median(factors[-1], rule, "s") / median(first, rule, "s")
        print(f"{rule:16s}{mem}{pss}{secs}{ratio:9.1f}")
    walls = "".join(f"{wall(runs[k]):9.1f}" for k in factors)
    print(f"{'whole run':16s}{' ' * 23 * len(factors)}{walls}")
    print(f"s ratio: the rule's wall time at {factors[-1]}x over {first}x")


if __name__ == "__main__":
    main()
