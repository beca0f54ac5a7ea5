"""The figure of docs/real-data.md, step 5: each trial's residual (reference minus model, arcsec)
under two models of one run, and the samples validation left out.

    python docs/real-data/residuals.py RESULTS/CAMPAIGN baseline gravity_latency docs/real-data/residuals.png
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

AXES = ("roll", "pitch", "yaw")


def main(results, first, second, out):
    results = Path(results)
    fits = {m: pd.read_csv(results / m / "fit.csv") for m in (first, second)}
    left_out = pd.DataFrame(json.loads((results / "input.json").read_text())["star_tracker_outliers"])
    trials = list(dict.fromkeys(fits[first]["maneuver"]))
    fig, axes = plt.subplots(len(trials), 2, figsize=(13, 3.2 * len(trials)), sharey="row", squeeze=False)
    for row, trial in enumerate(trials):
        for col, model in enumerate((first, second)):
            ax = axes[row, col]
            fit = fits[model][fits[model]["maneuver"] == trial]
            for axis in AXES:
                ax.plot(fit["time"], fit[f"residual_{axis}"], ".-", lw=0.7, ms=2.5, label=axis)
            gone = left_out[left_out["maneuver"] == trial] if len(left_out) else left_out
            for _, o in gone.iterrows():
                ax.axvline(o["time_s"], color="k", lw=0.6, ls=":")
            rms = (fit[[f"residual_{a}" for a in AXES]] ** 2).mean() ** 0.5
            ax.set_title(f"{trial}, {model}: RMS " + ", ".join(f"{v:.0f}" for v in rms) + " arcsec", fontsize=9)
            ax.grid(alpha=0.3)
        axes[row, 0].set_ylabel("reference - model (arcsec)")
    axes[0, 0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("campaign time (s); dotted: samples left out by validation")
    fig.tight_layout()
    fig.savefig(out, dpi=80)


if __name__ == "__main__":
    main(*sys.argv[1:])
