"""What the white baseline names first, on the validation's kinds of campaign (issue 30).

    OPENBLAS_NUM_THREADS=1 python studies/explanation_ranking.py --n 16            # every kind, ~15 min
    OPENBLAS_NUM_THREADS=1 python studies/explanation_ranking.py --n 50 --kinds gm30,gm3,gm0
    OPENBLAS_NUM_THREADS=1 python studies/explanation_ranking.py --n 8 --factor 3     # effects 3x larger

Per campaign: the baseline model's point estimate, the whiteness statistics and the ranking of
explanations of `gyrocal.criticism.diagnostics`, as the diagnostics step computes them. The kinds:
``clean`` and each hidden effect of ``config/study.yaml`` at its two larger magnitudes (truths
drawn from the configured prior, as the validation study's), and the Gauss-Markov validation's
campaigns (`gauss_markov.scenario_for`) with tau 0 (white), 3 and 30 s. Printed per kind: how often
the hidden effect (``st_latency``: or its signature, ``acceleration``) is ranked first and in the
top two, for the ranking as it is and for the ranking as it was with the lag-1 score alone for
``st_correlated_noise`` (``n rho^2`` on one degree of freedom); on clean and white campaigns, how
often ``st_correlated_noise`` is first, and how often the structure test is failed.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]


def kinds(study: dict, factor: float = 1.0) -> dict:
    """Kind name -> (scenario path, hidden simulator keys, Gauss-Markov tau or None); the hidden effects'
    magnitudes times ``factor``."""
    out = {"clean": (ROOT / study["scenario"], {}, None)}
    for name, effect in study["effects"].items():
        for magnitude in effect["magnitudes"][1:]:
            out[f"{name}@{factor * magnitude:g}"] = (ROOT / effect.get("scenario", study["scenario"]),
                                                     {effect["simulator_key"]: float(factor * magnitude)}, None)
    out.update({f"gm{tau:g}": (None, {}, tau) for tau in (0.0, 3.0, 30.0)})
    return out


def named(kind: str) -> set:
    """What counts as naming the hidden effect of ``kind`` (empty: none is hidden)."""
    if kind.startswith("gm"):
        return set() if kind == "gm0" else {"st_correlated_noise"}
    if kind == "clean":
        return set()
    effect = kind.split("@")[0]
    return {effect, "acceleration"} if effect == "st_latency" else {effect}


def one(job) -> dict:
    """The baseline's ranking (names, best first) and the lag-1-only ranking of campaign ``index``."""
    kind, (path, hidden, tau), index = job
    from gauss_markov import scenario_for
    from scipy import stats

    from gyrocal.simulation import simulate
    from gyrocal.study.baseline import baseline_ranking
    from gyrocal.study.campaign import campaign_scenario, draw_truth, prior_spec

    cfg = yaml.safe_load((ROOT / "config/config.yaml").read_text())
    study = yaml.safe_load((ROOT / "config/study.yaml").read_text())
    rng = np.random.default_rng([int(study["seed"]), index])
    base = simulate.load_scenario(ROOT / "tests/data/hidden_st_correlated_noise.yaml" if tau is not None else path)
    truth = draw_truth(prior_spec(simulate.scenario_channels(base), cfg["priors"]), rng)
    if tau is None:
        scenario = campaign_scenario(base, truth, hidden, f"{kind}_{index}", int(study["seed"]) * 100003 + index)
    else:
        scenario = scenario_for(tau, index, truth)
    _, _, white, ranking = baseline_ranking(simulate.simulate(scenario)[0], cfg["noise"])
    lag1 = stats.chi2.logsf(white["z"] ** 2, 1) / np.log(10)
    others = [r for r in ranking if r["name"] != "st_correlated_noise"]
    at = next((i for i, r in enumerate(others) if lag1 < r["log10_p"]), len(others))
    before = [r["name"] for r in others[:at]] + ["st_correlated_noise"] + [r["name"] for r in others[at:]]
    return {"kind": kind, "now": [r["name"] for r in ranking], "before": before,
            "structure_failed": bool(ranking[0]["log10_p"] < cfg["diagnostics"]["structure_log10_p_min"])}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=16, help="campaigns per kind")
    parser.add_argument("--kinds", default="", help="comma-separated kinds (default: all)")
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--factor", type=float, default=1.0, help="the hidden effects' magnitudes times this")
    args = parser.parse_args(argv)
    study = yaml.safe_load((ROOT / "config/study.yaml").read_text())
    chosen = {k: v for k, v in kinds(study, args.factor).items() if not args.kinds or k in args.kinds.split(",")}
    jobs = [(k, v, i) for k, v in chosen.items() for i in range(args.n)]
    with ProcessPoolExecutor(args.processes) as pool:
        records = list(pool.map(one, jobs))
    print("| kind | campaigns | named first | in the top two | lag-1 score alone: first | top two | structure failed |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for kind in chosen:
        rows = [r for r in records if r["kind"] == kind]
        target = named(kind) or {"st_correlated_noise"}

        def count(order, top, rows=rows, target=target):
            return sum(bool(set(r[order][:top]) & target) for r in rows)

        print(f"| {kind} | {len(rows)} | {count('now', 1)} | {count('now', 2)} | {count('before', 1)} | "
              f"{count('before', 2)} | {sum(r['structure_failed'] for r in rows)} |", flush=True)


if __name__ == "__main__":
    main()
