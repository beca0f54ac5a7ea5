"""Speed of the default pipeline: prints figures, asserts nothing.

    python benchmarks/pipeline.py

1. wall time of the default ``snakemake --cores 2`` from an empty results directory, and
   per rule (from the benchmark file Snakemake writes beside each job's log): jobs, the
   wall seconds of its slowest job and of all its jobs, and the largest peak memory;
2. log-probability evaluations per second (vectorised over the walkers);
3. effective samples per second of the slowest parameter (the sampling step alone).
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml
from simulated import baseline_fit, evaluations_per_s

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def snakemake_run():
    """Wall seconds of the default run in an empty directory, and its per-rule table."""
    import pandas as pd

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "snakemake", "-s", str(ROOT / "workflow" / "Snakefile"), "--cores", "2",
                        "-d", tmp, "-q"], check=True, capture_output=True)
        wall = time.perf_counter() - start
        jobs = [pd.read_csv(f, sep="\t").assign(rule=f.name.split(".")[0])
                for f in sorted(Path(tmp, "logs").rglob("*.benchmark.tsv"))]
    table = pd.concat(jobs).groupby("rule").agg(jobs=("s", "size"), slowest_s=("s", "max"), all_jobs_s=("s", "sum"),
                                                peak_mb=("max_rss", "max"))
    return wall, table.sort_values("slowest_s", ascending=False).round(2)


def sampler_figures():
    from snakemake.utils import validate

    from gyrocal.inference.sampling import inferencedata, posterior

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    validate(cfg, str(ROOT / "workflow/schemas/config.schema.yaml"))
    fitted = baseline_fit(ROOT / "config/scenarios/mom.yaml", cfg)
    maneuvers, est, priors, spec = fitted.maneuvers, fitted.estimate, fitted.priors, fitted.estimate.spec
    start = time.perf_counter()
    post = posterior.sample(maneuvers, est, priors, cfg["sampler"], cfg["grid"], cfg["seed"])
    sampling_s = time.perf_counter() - start
    ess = inferencedata.summarize(inferencedata.posterior_dataset(post.ensemble_draws(), est.theta, spec),
                                  inferencedata.posterior_dataset(post.walker_draws(), est.theta, spec),
                                  spec.labels, cfg["convergence"])["ess_bulk"].min()
    evals_per_s = evaluations_per_s(post, est, priors, 2000)
    return evals_per_s, ess, sampling_s, post.result


def main():
    wall, rules = snakemake_run()
    print(f"default snakemake --cores 2, empty results: {wall:8.1f} s wall; per rule:")
    print(rules.to_string())
    evals, ess, sampling_s, result = sampler_figures()
    print(f"log-probability evaluations per second:     {evals:8.0f} (batches of 64 walkers)")
    print(f"sampling step:                              {sampling_s:8.1f} s "
          f"({result.steps} steps x {result.walkers} walkers x {result.chains.shape[0]} ensembles)")
    print(f"slowest parameter's bulk ESS:               {ess:8.0f}")
    print(f"effective samples per second (slowest):     {ess / sampling_s:8.0f}")


if __name__ == "__main__":
    main()
