"""Tables of the Gauss-Markov validation (`gauss_markov.py summary FOLDER ...`): prints markdown."""

import json
from pathlib import Path

import numpy as np
import pandas as pd

from gyrocal.study.tables import binomial_interval, clustered_interval, efficiency_confidence

LEVELS = {50: 0.674489750196, 90: 1.644853626951, 95: 1.959963984540}
"""Each central interval's level (%) and its normal quantile."""
CORRELATED = "st_correlated_noise"


def records(folders) -> list:
    return [json.loads(p.read_text()) for f in folders for p in sorted(Path(f).glob("tau*.json"))]


def _by_tau(recs):
    taus = sorted({r["tau_s"] for r in recs})
    return [(t, [r for r in recs if r["tau_s"] == t]) for t in taus]


def parameter_rows(recs, model: str) -> pd.DataFrame:
    """One row per campaign and free channel parameter of ``model``: truth, WLS, conditional mean and sd, CRB."""
    rows = []
    for r in (r for r in recs if model in r["models"]):
        m = r["models"][model]
        crlb = r["models"][CORRELATED]["crlb_sd"] if CORRELATED in r["models"] else [np.nan] * len(m["labels"])
        for i, label in enumerate(m["labels"]):
            if m["core"][i] and m["free"][i]:
                rows.append({"tau_s": r["tau_s"], "index": r["index"], "label": label, "truth": m["truth"][i],
                             "wls": m["wls"][i], "mean": m["mean"][i], "sd": m["sd"][i], "crlb": crlb[i]})
    return pd.DataFrame(rows)


def true_noise_rows(recs) -> pd.DataFrame:
    """The correlated model's conditional intervals at the REML noise and at the true noise, on the
    campaigns whose records hold both (one row each, the second with ``mean``/``sd`` at the truth)."""
    recs = [r for r in recs if "at_true_noise" in r["models"].get(CORRELATED, {})]
    reml = parameter_rows(recs, CORRELATED).assign(noise="REML")
    true = [dict(zip(("mean", "sd"), (r["models"][CORRELATED]["at_true_noise"][k] for k in ("mean", "sd"))))
            for r in recs]
    rows = []
    for r, t in zip(recs, true):
        m = r["models"][CORRELATED]
        for i in range(len(m["labels"])):
            if m["core"][i] and m["free"][i]:
                rows.append({"tau_s": r["tau_s"], "index": r["index"], "truth": m["truth"][i], "mean": t["mean"][i],
                             "sd": t["sd"][i], "noise": "true"})
    return pd.concat([reml, pd.DataFrame(rows)], ignore_index=True)


def coverage_table(params: pd.DataFrame, by=("tau_s",)) -> pd.DataFrame:
    out = []
    for key, g in params.groupby(list(by)):
        z = np.abs(g["mean"] - g["truth"]) / g["sd"]
        row = {**dict(zip(by, key)), "campaigns": g["index"].nunique(), "intervals": len(g)}
        for level, q in LEVELS.items():
            hit = (z <= q).to_numpy()
            lo, hi, _ = clustered_interval(hit, g["index"].to_numpy())
            row[f"{level} %"] = f"{100 * hit.mean():.1f} ({100 * lo:.1f}-{100 * hi:.1f})"
        out.append(row)
    return pd.DataFrame(out)


def efficiency_table(params: pd.DataFrame) -> pd.DataFrame:
    """CRB^2 over the WLS's mean squared error, pooled (``1 / mean(((wls - truth) / crlb)^2)``) and per parameter."""
    out = []
    for tau, g in params.groupby("tau_s"):
        pooled = 1 / np.mean(((g["wls"] - g["truth"]) / g["crlb"]) ** 2)
        per = g.groupby("label").apply(lambda h: np.mean(h["crlb"] ** 2) / np.mean((h["wls"] - h["truth"]) ** 2),
                                       include_groups=False)
        n = g["index"].nunique()
        lo, hi = efficiency_confidence(float(np.median(per)), n)
        sd_ratio = np.sqrt(np.mean(g["sd"] ** 2) / np.mean(g["crlb"] ** 2))
        out.append({"tau_s": tau, "pooled CRB/MSE": round(pooled, 3), "per parameter median": round(np.median(per), 3),
                    "per parameter min-max": f"{per.min():.2f}-{per.max():.2f}",
                    "median's 95 % CI (one parameter)": f"{lo:.2f}-{hi:.2f}",
                    "interval sd / CRB (rms)": round(sd_ratio, 3)})
    return pd.DataFrame(out)


def noise_table(recs) -> pd.DataFrame:
    """The correlated model's REML noise against the truth: tau, the GM share, the total sd and the ARW."""
    out = []
    for tau, rs in _by_tau(recs):
        est = np.array([r["models"][CORRELATED]["log_sigma"] for r in rs])
        true = np.array([r["true_log_sigma"] for r in rs])
        share = 1 / (1 + np.exp(-est[:, 3]))
        share_true = 1 / (1 + np.exp(-true[0, 3]))
        log_tau = est[:, 4] - true[:, 4]
        gmean = np.exp(log_tau.mean())
        out.append({"tau_s": tau, "n": len(rs),
                    "tau est/true median": round(float(np.exp(np.median(log_tau))), 3),
                    "tau geometric mean (se)": f"{gmean:.3f} ({gmean * log_tau.std() / np.sqrt(len(rs)):.3f})",
                    "tau 10-90 %": f"{np.exp(np.quantile(log_tau, 0.1)):.2f}-{np.exp(np.quantile(log_tau, 0.9)):.2f}",
                    "share mean (se), true": f"{share.mean():.3f} ({share.std() / np.sqrt(len(rs)):.3f}), {share_true:.2f}",
                    "share 10-90 %": f"{np.quantile(share, 0.1):.2f}-{np.quantile(share, 0.9):.2f}",
                    "sigma_cross est/true": round(float(np.exp(np.mean(est[:, 0] - true[:, 0]))), 3),
                    "sigma_about est/true": round(float(np.exp(np.mean(est[:, 1] - true[:, 1]))), 3),
                    "ARW est/true": round(float(np.exp(np.mean(est[:, 2] - true[:, 2]))), 3)})
    return pd.DataFrame(out)


def baseline_table(recs, cfg) -> pd.DataFrame:
    """The white model on the same data: its whiteness and structure checks, its noise against the
    stated white noise, and where ``st_correlated_noise`` stands in its ranking."""
    out = []
    d = cfg["diagnostics"]
    recs = [r for r in recs if "baseline" in r["models"]]
    for tau, rs in _by_tau(recs):
        b = [r["models"]["baseline"] for r in rs]
        white = np.array([abs(x["whiteness_z"]) > d["whiteness_z_max"] for x in b])
        structure = np.array([x["ranking"][0]["log10_p"] < d["structure_log10_p_min"] for x in b])
        names = [[e["name"] for e in x["ranking"]] for x in b]
        top1 = np.array([n[0] == CORRELATED for n in names])
        top2 = np.array([CORRELATED in n[:2] for n in names])
        ratio = np.array([[s / x["stated"][k] for s, k in zip(x["scales"], ("sigma_cross_arcsec", "sigma_about_arcsec",
                                                                         "arw_deg_sqrt_h"))] for x in b])
        noise = np.any((ratio > d["noise_ratio_max"]) | (ratio < 1 / d["noise_ratio_max"]), axis=1)
        flagged = white | structure | noise

        def pct(x):
            lo, hi = binomial_interval(int(x.sum()), len(x))
            return f"{100 * x.mean():.1f} ({100 * lo:.0f}-{100 * hi:.0f})"

        out.append({"tau_s": tau, "n": len(rs), "whiteness |z| > 5": pct(white), "structure p < 1e-6": pct(structure),
                    "noise off stated": pct(noise), "any of these": pct(flagged),
                    "st_correlated_noise first": pct(top1), "st_correlated_noise in top two": pct(top2),
                    "median |z|": round(float(np.median([abs(x["whiteness_z"]) for x in b])), 1)})
    return pd.DataFrame(out)


def sampled_table(recs) -> pd.DataFrame:
    """The default sampler against the conditional Gaussian at the REML noise, and both models' diagnostics."""
    out = []
    for tau, rs in _by_tau([r for r in recs if "sampled" in r]):
        sd_ratio, shift, hit_s, hit_c, misfit_c, misfit_b, top2, conv = [], [], [], [], [], [], [], []
        refused = [r for r in rs if "refused" in r["sampled"][CORRELATED]]
        for r in (r for r in rs if "refused" not in r["sampled"][CORRELATED]):
            m, s = r["models"][CORRELATED], r["sampled"][CORRELATED]
            summ = {row["label"]: row for row in s["summary"]}
            for i, label in enumerate(m["labels"]):
                if not (m["core"][i] and m["free"][i]):
                    continue
                row = summ[label]
                sd_ratio.append(row["sd"] / m["sd"][i])
                shift.append((row["mean"] - m["mean"][i]) / m["sd"][i])
                hit_s.append(row["ci95_low"] <= m["truth"][i] <= row["ci95_high"])
                hit_c.append(abs(m["mean"][i] - m["truth"][i]) <= LEVELS[95] * m["sd"][i])
            misfit_c.append(s["misfit"])
            conv.append(s["converged"])
            misfit_b.append(r["sampled"]["baseline"]["misfit"])
            top2.append(CORRELATED in r["sampled"]["baseline"]["ranking"][:2])
        out.append({"tau_s": tau, "campaigns": len(rs), "sd sampler / conditional (median, 5-95 %)":
                    f"{np.median(sd_ratio):.3f} ({np.quantile(sd_ratio, 0.05):.3f}-{np.quantile(sd_ratio, 0.95):.3f})",
                    "mean shift / sd (max abs)": round(float(np.max(np.abs(shift))), 3),
                    "95 % coverage sampler / conditional": f"{100 * np.mean(hit_s):.1f} / {100 * np.mean(hit_c):.1f}",
                    "correlated model converged": f"{sum(conv)}/{len(rs)}",
                    "correlated model stopped by the sampler's budget": f"{len(refused)}/{len(rs)}",
                    "correlated model misfit": f"{sum(misfit_c)}/{len(rs)}",
                    "baseline misfit": f"{sum(misfit_b)}/{len(rs)}",
                    "st_correlated_noise in baseline's top two": f"{sum(top2)}/{len(rs)}"})
    return pd.DataFrame(out)


def summary(folders):
    import yaml

    from gyrocal.study.tables import markdown_table

    cfg = yaml.safe_load((Path(__file__).resolve().parents[1] / "config/config.yaml").read_text())
    recs = records(folders)
    tables = {"coverage of the correlated model's conditional intervals (%, 95 % CI)":
              coverage_table(parameter_rows(recs, CORRELATED)),
              "the same, at the REML noise and at the true noise, on the campaigns that hold both":
              coverage_table(true_noise_rows(recs), ("tau_s", "noise")) if any(
                  "at_true_noise" in r["models"].get(CORRELATED, {}) for r in recs) else pd.DataFrame(),
              "the white model's conditional intervals on the same data (%)": coverage_table(parameter_rows(recs, "baseline")),
              "efficiency of the correlated model's WLS against its Cramér-Rao bound": efficiency_table(
                  parameter_rows(recs, CORRELATED)),
              "the correlated model's REML noise against the truth": noise_table([r for r in recs if r["tau_s"] > 0]),
              "the white model on the same data": baseline_table(recs, cfg),
              "the default sampler (--sampled campaigns)": sampled_table(recs)}
    for title, table in tables.items():
        if len(table):
            print(f"\n**{title}**\n\n{markdown_table(table)}")
    seconds = [r["seconds"] for r in recs]
    print(f"\n{len(recs)} campaigns, median {np.median(seconds):.1f} s each")
