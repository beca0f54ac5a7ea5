"""The validation study's tables: accuracy against the Cramér-Rao bound, coverage, SBC and the
criticism loop's error rates, from the campaigns' records (`gyrocal.study.campaign.run`).

Pure pandas and numpy on the records; the figures are `gyrocal.study.figures`, the I/O `gyrocal.study.steps`.
"""

import numpy as np
import pandas as pd
from scipy import stats as sps

__all__ = [
    "ESTIMATORS", "LEVELS", "SBC_BINS", "SUMMARY_COLUMNS", "accuracy", "binomial_interval", "clean_baseline",
    "clustered_interval", "coverage", "detection", "efficiency_confidence", "efficiency_interval", "error_rates",
    "extended_coverage", "markdown", "markdown_table", "model_table", "parameter_table", "plan_check",
    "pooled_efficiency", "sbc", "sbc_bin_shares", "sbc_histogram", "uniformity_p"
]

LEVELS = {0.5: ("q25", "q75"), 0.9: ("q5", "q95"), 0.95: ("q2.5", "q97.5")}
"""Each central interval's level and the quantile columns of a record that bound it."""

ESTIMATORS = {"classic_paper": "classic, bias trusted (paper)", "classic_holds": "classic, bias from holds",
              "wls": "WLS", "mean": "posterior mean"}

SBC_BINS = 10


def parameter_table(records) -> pd.DataFrame:
    """One row per campaign, model and parameter."""
    rows = []
    for r in records:
        for p in r["parameters"]:
            rows.append({"group": r["group"], "magnitude": r["magnitude"], "index": r["index"], **p})
    frame = pd.DataFrame(rows)
    return frame.astype({c: float for c in ("truth", "wls", "mean", "sd", "crlb_sd", "classic_paper",
                                              "classic_holds")})


def model_table(records) -> pd.DataFrame:
    """One row per campaign and model: the misfit checks and the ranking's top."""
    rows = []
    for r in records:
        for m in r["models"]:
            top = m["ranking"][0]
            rows.append({"group": r["group"], "magnitude": r["magnitude"], "index": r["index"], "model": m["model"],
                         "misfit": m["misfit"], **{f"failed:{k}": not v for k, v in m["checks"].items()},
                         "top": top["name"], "top_log10_p": top["log10_p"], "candidates": len(m["ranking"]),
                         "whiteness_z": m["whiteness_z"], "residual_rms_ratio": m["residual_rms_ratio"],
                         "loglik_sbc_rank": m["loglik_sbc_rank"], "sbc_draws": m["sbc_draws"],
                         "converged": m["converged"]})
    return pd.DataFrame(rows)


def clean_baseline(params: pd.DataFrame) -> pd.DataFrame:
    """The baseline's channel parameters on campaigns without a hidden effect."""
    return params[(params["group"] == "clean") & (params["model"] == "baseline") & params["core"]]


def efficiency_interval(n: int, level: float = 0.9) -> tuple:
    """Where CRLB/MSE falls ``level`` of the time over ``n`` campaigns for an efficient, unbiased
    estimator: MSE/CRLB is then chi2(n)/n."""
    lo, hi = sps.chi2.ppf([(1 + level) / 2, (1 - level) / 2], n) / n
    return 1 / lo, 1 / hi


def efficiency_confidence(efficiency, n: int, level: float = 0.95) -> tuple:
    """Confidence interval of a true efficiency CRLB/sigma^2 from one estimated over ``n``
    campaigns of unbiased, normal errors: the estimate over `efficiency_interval`'s band."""
    lo, hi = efficiency_interval(n, level)
    return efficiency / hi, efficiency / lo


def accuracy(params: pd.DataFrame) -> pd.DataFrame:
    """RMSE per parameter of every estimator, the Cramér-Rao bound (root mean of the campaigns'
    bounds), the posterior mean's efficiency CRLB/MSE with its 95 % confidence interval and the 90 %
    band in which an efficient estimator's would fall, and the ratios the targets name;
    ``paper_over_crlb`` is the most an estimator could gain over the paper's classic method on
    these campaigns (the bound includes the prior the truths are drawn from)."""
    rows = []
    for label, g in clean_baseline(params).groupby("label", sort=False):
        err = {k: g[k] - g["truth"] for k in ESTIMATORS}
        rmse = {k: float(np.sqrt(np.mean(e**2))) for k, e in err.items()}
        crlb = float(np.sqrt(np.mean(g["crlb_sd"] ** 2)))
        lo, hi = efficiency_interval(len(g))
        efficiency = crlb**2 / rmse["mean"] ** 2
        ci_lo, ci_hi = efficiency_confidence(efficiency, len(g))
        rows.append({"label": label, "unit": g["unit"].iloc[0], "n": len(g),
                     **{f"rmse_{k}": v for k, v in rmse.items()}, "crlb": crlb,
                     "efficiency": efficiency, "efficiency_lo": ci_lo, "efficiency_hi": ci_hi,
                     "efficient_band_lo": lo, "efficient_band_hi": hi,
                     "bias_over_crlb": float(err["mean"].mean() / crlb),
                     "paper_over_posterior": rmse["classic_paper"] / rmse["mean"],
                     "paper_over_crlb": rmse["classic_paper"] / crlb,
                     "holds_over_posterior": rmse["classic_holds"] / rmse["mean"],
                     "holds_over_crlb": rmse["classic_holds"] / crlb})
    return pd.DataFrame(rows)


def pooled_efficiency(params: pd.DataFrame) -> float:
    """CRLB/MSE over every channel parameter and campaign: ``1 / mean(((mean - truth) / crlb)^2)``."""
    g = clean_baseline(params)
    return float(1 / np.mean(((g["mean"] - g["truth"]) / g["crlb_sd"]) ** 2))


def binomial_interval(k: float, n: float, level: float = 0.95) -> tuple:
    """Clopper-Pearson interval of a rate ``k / n`` (counts may be effective ones, not whole)."""
    a = 1 - level
    lo = sps.beta.ppf(a / 2, k, n - k + 1) if k > 0 else 0.0
    hi = sps.beta.ppf(1 - a / 2, k + 1, n - k) if k < n else 1.0
    return float(lo), float(hi)


def clustered_interval(hit: np.ndarray, cluster: np.ndarray, level: float = 0.95) -> tuple:
    """Clopper-Pearson interval of a rate whose trials come in clusters, and its effective number
    of trials (Korn and Graubard 1998): the binomial's ``n`` divided by the design effect of the
    clusters' totals (never below 1), then shrunk by ``(t_{n-1} / t_{m-1})^2`` for the ``m``
    clusters the variance rests on. A campaign's parameters share its noise, so they are not
    independent trials; with one trial per cluster this is the binomial interval."""
    hit = np.asarray(hit, dtype=float)
    _, codes = np.unique(cluster, return_inverse=True)
    k_c, n_c = np.bincount(codes, hit), np.bincount(codes).astype(float)
    n, m, rate = len(hit), len(n_c), hit.mean()
    var_binomial = rate * (1 - rate) / n
    var_cluster = np.sum((k_c - rate * n_c) ** 2) / n**2
    n_eff = n / max(var_cluster / var_binomial, 1.0) if var_binomial > 0 else float(n)
    if 1 < m < n:
        q = (1 + level) / 2
        n_eff *= (sps.t.ppf(q, n - 1) / sps.t.ppf(q, m - 1)) ** 2
    return (*binomial_interval(rate * n_eff, n_eff, level), float(n_eff))


def coverage(params: pd.DataFrame, by=None) -> pd.DataFrame:
    """How often each central interval holds the truth, with its 95 % interval, the campaigns taken
    as clusters (`clustered_interval`: on the per-parameter rows, one trial per campaign, it is
    the binomial interval)."""
    rows = []
    groups = [((), params)] if by is None else params.groupby(by, sort=False)
    for key, g in groups:
        key = key if isinstance(key, tuple) else (key,)
        campaign = (g["group"].astype(str) + ":" + g["index"].astype(str)).to_numpy()
        for level, (lo, hi) in LEVELS.items():
            hit = ((g[lo] <= g["truth"]) & (g["truth"] <= g[hi])).to_numpy()
            k, n = int(hit.sum()), len(hit)
            rate_lo, rate_hi, n_eff = clustered_interval(hit, campaign)
            rows.append({**dict(zip(by or [], key)), "level": level, "covered": k, "n": n, "rate": k / n,
                         "rate_lo": rate_lo, "rate_hi": rate_hi, "n_effective": n_eff})
    return pd.DataFrame(rows)


def sbc_histogram(ranks: np.ndarray, draws: int, bins: int = SBC_BINS) -> np.ndarray:
    """Counts of ranks ``0..draws`` in ``bins`` bins of (nearly) equal width."""
    return np.bincount(np.asarray(ranks, dtype=int) * bins // (draws + 1), minlength=bins)


def sbc_bin_shares(draws: int, bins: int = SBC_BINS) -> np.ndarray:
    """Share of the ``draws + 1`` equally likely ranks in each bin of `sbc_histogram`: unequal
    where ``bins`` does not divide ``draws + 1`` (100 draws: the first bin holds 11 ranks, the
    others 10)."""
    return np.bincount(np.arange(draws + 1) * bins // (draws + 1), minlength=bins) / (draws + 1)


def uniformity_p(counts: np.ndarray, draws: int) -> float:
    """Chi-square test of a rank histogram against uniform ranks ``0..draws``."""
    counts = np.asarray(counts)
    return float(sps.chisquare(counts, counts.sum() * sbc_bin_shares(draws, len(counts))).pvalue)


def sbc(params: pd.DataFrame, models: pd.DataFrame) -> pd.DataFrame:
    """Rank histogram and uniformity p-value per parameter, for the log-likelihood, and pooled.

    Also the Bonferroni-corrected smallest p-value: the test the targets ask for over all rows.
    """
    g = clean_baseline(params)
    draws = int(g["sbc_draws"].iloc[0])
    rows = [_sbc_row(label, part["sbc_rank"], draws) for label, part in g.groupby("label", sort=False)]
    clean = models[(models["group"] == "clean") & (models["model"] == "baseline")]
    rows.append(_sbc_row("log-likelihood", clean["loglik_sbc_rank"], draws))
    rows.append(_sbc_row("all channel parameters", g["sbc_rank"], draws))
    frame = pd.DataFrame(rows)
    frame["p_bonferroni"] = np.minimum(1.0, frame["p"] * len(frame))
    return frame


def _sbc_row(quantity: str, ranks, draws: int) -> dict:
    """One row of the SBC table: the rank histogram of ``quantity`` and its uniformity p-value."""
    counts = sbc_histogram(ranks, draws)
    return {"quantity": quantity, "n": len(ranks), "draws": draws, "p": uniformity_p(counts, draws),
            **{f"bin{i}": int(c) for i, c in enumerate(counts)}}


def error_rates(models: pd.DataFrame, thresholds: dict) -> pd.DataFrame:
    """How often the misfit checks fire on clean campaigns, against their nominal rates.

    At the configured thresholds the nominal rate of ``misfit`` is of order 1e-5 (its tests sit at
    5 sd and p = 1e-6), too small to measure on hundreds of campaigns; so each test is also read
    at looser thresholds, where its null distribution predicts a measurable rate: the top of the
    ranking (the smallest of the candidates' p-values, about independent) and the whiteness z.
    """
    clean = models[(models["group"] == "clean") & (models["model"] == "baseline")]
    n = len(clean)
    k_cand = int(clean["candidates"].median())
    rows = []

    def add(name, fired, nominal):
        k = int(np.sum(fired))
        lo, hi = binomial_interval(k, n)
        rows.append({"test": name, "fired": k, "n": n, "rate": k / n, "rate_lo": lo, "rate_hi": hi,
                     "nominal": nominal, "ratio": (k / n) / nominal if nominal > 0 else np.nan})

    p_min = 10.0 ** thresholds["structure_log10_p_min"]
    z_max = thresholds["whiteness_z_max"]
    nominal_structure = 1 - (1 - p_min) ** k_cand
    nominal_white = 2 * sps.norm.sf(z_max)
    add("misfit (configured thresholds)", clean["misfit"], nominal_structure + nominal_white)
    for check in [c for c in clean.columns if c.startswith("failed:")]:
        add(f"{check[7:]} check", clean[check], np.nan)
    for alpha in (0.1, 0.05, 0.01, 0.001):
        add(f"structure, top p < {alpha:g}", clean["top_log10_p"] < np.log10(alpha), 1 - (1 - alpha) ** k_cand)
    for z in (1.645, 1.96, 2.576, 3.0):
        add(f"whiteness |z| > {z:g}", clean["whiteness_z"].abs() > z, 2 * sps.norm.sf(z))
    return pd.DataFrame(rows)


def detection(models: pd.DataFrame, signatures: dict | None = None) -> pd.DataFrame:
    """Per hidden effect and magnitude, with the baseline fitted: how often ``misfit`` is raised,
    how often the effect tops the ranking under its own name, and how often it is detected with
    the top naming it: its own name or a residual signature that names the same physics
    (``signatures``: effect -> signature names, e.g. a timing offset's ``acceleration``)."""
    base = models[(models["group"] != "clean") & (models["model"] == "baseline")]
    signatures = signatures or {}
    rows = []
    for (effect, magnitude), g in base.groupby(["group", "magnitude"], sort=True):
        own = g["top"] == effect
        first = g["top"].isin([effect, *signatures.get(effect, [])])
        n = len(g)
        rows.append({"effect": effect, "magnitude": magnitude, "n": n, "misfit": g["misfit"].mean(),
                     "ranked_first": own.mean(), "named_first": first.mean(),
                     "detected_and_first": (g["misfit"] & first).mean(),
                     "detected_and_first_lo": binomial_interval(int((g["misfit"] & first).sum()), n)[0],
                     "detected_and_first_hi": binomial_interval(int((g["misfit"] & first).sum()), n)[1]})
    return pd.DataFrame(rows, columns=[*SUMMARY_COLUMNS["detection"], "detected_and_first_lo",
                                       "detected_and_first_hi"])


def extended_coverage(params: pd.DataFrame) -> pd.DataFrame:
    """Coverage of each extended model on the campaigns that carry its effect, for its channel
    parameters and its added ones, with how much wider its intervals are than the baseline's."""
    ext = params[(params["group"] != "clean") & (params["model"] == params["group"])].copy()
    if ext.empty:  # a study of clean campaigns alone (``effects: {}``) has no extended model
        return pd.DataFrame(columns=["group", "kind", "level", "covered", "n", "rate", "rate_lo", "rate_hi",
                                     "n_effective", "max_abs_z", "median_sd_over_baseline"])
    ext["kind"] = np.where(ext["core"], "channel parameters", "added effect")
    table = coverage(ext, by=["group", "kind"])
    base = params[(params["group"] != "clean") & (params["model"] == "baseline")]
    widen = (ext[ext["core"]].set_index(["group", "index", "label"])["sd"]
             / base.set_index(["group", "index", "label"])["sd"]).groupby(level="group").median()
    z = ext.assign(z=(ext["mean"] - ext["truth"]) / ext["sd"]).groupby(["group", "kind"])["z"]
    table = table.merge(z.apply(lambda s: float(np.abs(s).max())).rename("max_abs_z").reset_index(),
                        on=["group", "kind"])
    table["median_sd_over_baseline"] = [widen.get(g, np.nan) if k == "channel parameters" else np.nan
                                        for g, k in zip(table["group"], table["kind"])]
    return table


def plan_check(params: pd.DataFrame, predicted: pd.DataFrame) -> pd.DataFrame:
    """The plan's predicted posterior sd beside the study's empirical sd of the posterior mean's
    error and its mean posterior sd, per parameter."""
    g = clean_baseline(params)
    empirical = g.assign(err=g["mean"] - g["truth"]).groupby("label", sort=False).agg(
        empirical_sd=("err", "std"), mean_posterior_sd=("sd", "mean"), n=("err", "size"))
    out = predicted.set_index("label")[["predicted_sd"]].join(empirical, how="inner").reset_index()
    out["empirical_over_predicted"] = out["empirical_sd"] / out["predicted_sd"]
    out["posterior_over_predicted"] = out["mean_posterior_sd"] / out["predicted_sd"]
    return out


def markdown_table(frame: pd.DataFrame, digits: int = 3) -> str:
    """A table as GitHub markdown, numbers to ``digits`` significant figures."""
    def cell(v):
        if isinstance(v, (float, np.floating)):
            return "" if np.isnan(v) else f"{v:.{digits}g}"
        return str(v)
    lines = ["| " + " | ".join(map(str, frame.columns)) + " |", "|" + "---|" * len(frame.columns)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in frame.itertuples(index=False)]
    return "\n".join(lines)


SUMMARY_COLUMNS = {
    "accuracy": ["label", "unit", "rmse_classic_paper", "rmse_classic_holds", "rmse_wls", "rmse_mean", "crlb",
                 "efficiency", "efficiency_lo", "efficiency_hi", "paper_over_posterior", "paper_over_crlb",
                 "holds_over_posterior"],
    "coverage": ["level", "covered", "n", "n_effective", "rate", "rate_lo", "rate_hi"],
    "sbc": ["quantity", "n", "p", "p_bonferroni"],
    "error_rates": ["test", "fired", "n", "rate", "rate_lo", "rate_hi", "nominal"],
    "detection": ["effect", "magnitude", "n", "misfit", "ranked_first", "named_first", "detected_and_first"],
    "extended_coverage": ["group", "kind", "level", "covered", "n", "rate", "max_abs_z", "median_sd_over_baseline"],
    "plan_check": ["label", "predicted_sd", "empirical_sd", "empirical_over_predicted", "posterior_over_predicted"],
}
"""The columns of each table that `markdown` shows (the CSV files have them all)."""


def markdown(tables: dict) -> str:
    """Every table of the study as one markdown document (``tables.md``), for docs/validation.md."""
    parts = []
    for name, columns in SUMMARY_COLUMNS.items():
        table = tables[name]
        parts += [f"### {name}", "", markdown_table(table[columns]) if len(table) else "None in this study.", ""]
    return "\n".join(parts)
