"""The validation study's figures, from `gyrocal.study.tables`."""

import matplotlib.pyplot as plt
import numpy as np

from gyrocal.study.tables import ESTIMATORS, SBC_BINS, sbc_bin_shares

__all__ = ["accuracy_figure", "coverage_figure", "detection_figure", "sbc_figure"]


def accuracy_figure(table):
    """RMSE of every estimator per parameter, over its Cramér-Rao bound (1 is the bound)."""
    fig, ax = plt.subplots(figsize=(10, 4.5))
    x = np.arange(len(table))
    for i, (key, name) in enumerate(ESTIMATORS.items()):
        ax.plot(x + 0.1 * (i - 1.5), table[f"rmse_{key}"] / table["crlb"], "o", ms=4, label=name)
    ax.axhline(1.0, color="k", lw=1, ls="--", label="Cramér-Rao bound")
    ax.set_yscale("log")
    ax.set_xticks(x, table["label"], rotation=80, fontsize=7)
    ax.set_ylabel("RMSE / CRLB")
    ax.legend(fontsize=8, ncol=3)
    ax.set_title(f"accuracy over {int(table['n'].iloc[0])} campaigns")
    fig.tight_layout()
    return fig


def coverage_figure(overall, per_parameter):
    """Observed against nominal coverage, overall with its binomial band and per parameter."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), gridspec_kw={"width_ratios": [1, 2.2]})
    ax = axes[0]
    ax.errorbar(overall["level"], overall["rate"], yerr=[overall["rate"] - overall["rate_lo"],
                                                         overall["rate_hi"] - overall["rate"]], fmt="o", capsize=3)
    ax.plot([0.4, 1], [0.4, 1], "k--", lw=1)
    ax.set_xlabel("nominal")
    ax.set_ylabel("observed")
    ax.set_title("all channel parameters")
    ax = axes[1]
    for level, g in per_parameter.groupby("level"):
        x = np.arange(len(g))
        ax.errorbar(x, g["rate"], yerr=[g["rate"] - g["rate_lo"], g["rate_hi"] - g["rate"]], fmt="o", ms=3,
                    capsize=2, label=f"{level:.0%}")
        ax.axhline(level, color="k", lw=0.8, ls=":")
    ax.set_xticks(x, g["label"], rotation=80, fontsize=7)
    ax.set_ylabel("coverage")
    ax.legend(fontsize=8, title="interval")
    fig.tight_layout()
    return fig


def sbc_figure(table):
    """SBC rank histograms: every parameter, the log-likelihood and all pooled, with the 99 % band
    of a uniform histogram."""
    n_rows = int(np.ceil(len(table) / 6))
    fig, axes = plt.subplots(n_rows, 6, figsize=(13, 2 * n_rows), sharex=True)
    bins = [f"bin{i}" for i in range(SBC_BINS)]
    for ax, row in zip(axes.ravel(), table.itertuples()):
        counts = np.array([getattr(row, b) for b in bins])
        share = sbc_bin_shares(int(row.draws))
        expected = row.n * share
        band = 2.576 * np.sqrt(expected * (1 - share))
        ax.bar(np.arange(SBC_BINS), 2 * band, bottom=expected - band, width=1.0, color="0.85")
        ax.bar(np.arange(SBC_BINS), counts, width=0.9)
        ax.set_title(f"{row.quantity}\np = {row.p:.2g}", fontsize=7)
        ax.tick_params(labelsize=6)
    for ax in axes.ravel()[len(table):]:
        ax.axis("off")
    fig.tight_layout()
    return fig


def detection_figure(table, predicted=None):
    """Per effect: how often the baseline's misfit is raised with the effect ranked first, against
    its magnitude; the plan's predicted 90 %-detection magnitude as a vertical line."""
    effects = list(dict.fromkeys(table["effect"]))
    if not effects:  # a study of clean campaigns alone: the figure says so
        fig, ax = plt.subplots(figsize=(4, 1.5))
        ax.text(0.5, 0.5, "no hidden effect in this study", ha="center", va="center")
        ax.set_axis_off()
        return fig
    fig, axes = plt.subplots(1, len(effects), figsize=(3.2 * len(effects), 3.2), squeeze=False)
    for ax, effect in zip(axes[0], effects):
        g = table[table["effect"] == effect]
        ax.errorbar(g["magnitude"], g["detected_and_first"],
                    yerr=[g["detected_and_first"] - g["detected_and_first_lo"],
                          g["detected_and_first_hi"] - g["detected_and_first"]], fmt="o-", capsize=3,
                    label="misfit, ranked first")
        ax.plot(g["magnitude"], g["misfit"], "s--", ms=3, label="misfit")
        if predicted is not None and effect in predicted:
            ax.axvline(predicted[effect], color="k", ls=":", lw=1, label="plan: 90 %")
        ax.set_xscale("log")
        ax.set_ylim(-0.05, 1.05)
        ax.set_title(effect, fontsize=9)
        ax.set_xlabel("magnitude")
    axes[0][0].set_ylabel("rate")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return fig
