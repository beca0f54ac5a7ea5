"""A fleet of campaigns side by side: each campaign's reviewed model, its parameters and verdict.

Operators of a constellation calibrate many spacecraft, and a validation study runs many
campaigns: the same shape, many independent campaigns. Each runs as its own jobs; this
module only gathers what they wrote (``verdict.json`` and the reviewed model's
``calibration.csv``) into one table and one figure.
"""

from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["calibration_path", "figure", "summary"]


def summary(verdicts: list, calibrations: dict) -> pd.DataFrame:
    """One row per campaign and parameter of its reviewed model. ``verdicts`` are the campaigns'
    ``verdict.json`` documents; ``calibrations`` maps (campaign, model) to its table."""
    rows = []
    for v in verdicts:
        table = calibrations[v["campaign"], v["model"]]
        rows.append(table.assign(campaign=v["campaign"], model=v["model"], verdict=v["verdict"]))
    frame = pd.concat(rows, ignore_index=True)
    first = ["campaign", "model", "verdict", "channel", "parameter", "unit"]
    return frame[first + [c for c in frame.columns if c not in first]]


def figure(table: pd.DataFrame):
    """Each parameter across the fleet: posterior mean and 95 % interval per campaign, GO in green
    and NO-GO in red; a campaign whose reviewed model lacks the parameter is left blank."""
    import matplotlib.pyplot as plt
    labels = sorted(set(table["channel"] + "." + table["parameter"]))
    cols = 4
    rows = int(np.ceil(len(labels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.2 * rows), squeeze=False)
    campaigns = sorted(table["campaign"].unique())
    for ax, label in zip(axes.ravel(), labels):
        sub = table[table["channel"] + "." + table["parameter"] == label].set_index("campaign").reindex(campaigns)
        x = np.arange(len(campaigns))
        colors = np.where(sub["verdict"] == "GO", "tab:green", "tab:red")
        ax.errorbar(x, sub["mean"], yerr=[sub["mean"] - sub["ci95_low"], sub["ci95_high"] - sub["mean"]], fmt="none",
                    ecolor="0.5", lw=1)
        ax.scatter(x, sub["mean"], c=colors, s=12, zorder=3)
        ax.set_title(f"{label} ({sub['unit'].dropna().iloc[0]})", fontsize=8)
        ax.set_xticks(x, campaigns, rotation=90, fontsize=6)
        ax.tick_params(axis="y", labelsize=7)
    for ax in axes.ravel()[len(labels):]:
        ax.axis("off")
    fig.tight_layout()
    return fig


def calibration_path(verdict_path, model) -> Path:
    """Where a campaign's model wrote ``calibration.csv``, beside its ``verdict.json``."""
    return Path(verdict_path).parent / model / "calibration.csv"
