"""Figures in the style of the paper's Figures 1-3: the rate profile, then the error
along yaw, roll and pitch. Headless use needs the Agg backend, which a workflow step
selects when it starts (`gyrocal.stepenv.start`), not this module on import."""

import io
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import matplotlib.pyplot as plt
import numpy as np

from gyrocal.model.units import PAPER_AXES

__all__ = [
    "SAVE_DPI", "comparison_figure", "maneuver_figure", "pair_figure", "png", "render_all", "residual_figure", "save",
    "trace_figure"
]


def maneuver_figure(table, title, fit=None, flight=True):
    """Rate profile and error per axis (arcsec) of one maneuver. Its margins are fixed rather than
    fitted (tight_layout): fitting them draws the figure twice, a third of its cost.

    ``table`` is `preprocess.error_table`; ``fit`` optionally adds, per axis, the
    model's predicted mean and 95 % band and the residual (columns of the fit table). ``flight``
    false (a lab's campaign): the sets are the first and the others, not in loop and redundant.
    """
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    t = table["time"] - table["time"].iloc[0]
    for axis in ("roll", "pitch", "yaw"):
        axes[0].plot(t, table[f"rate_{axis}_deg_s"], label=axis, lw=1)
    axes[0].set_ylabel("rate (deg/s)")
    axes[0].legend(loc="upper right", fontsize=8, ncol=3)
    sets = sorted({c.split("_")[0] for c in table.columns if c.startswith("set")})
    for ax, axis in zip(axes[1:], PAPER_AXES):
        for s in sets:
            ax.plot(t, table[f"{s}_error_{axis}_arcsec"], lw=0.6,
                    label=f"{s} {('(in loop)' if flight else '(first)') if s == 'set0' else '(redundant)' if flight else ''}")
        if fit is not None:
            tf = fit["time"] - table["time"].iloc[0]
            ax.fill_between(tf, fit[f"lo_{axis}"], fit[f"hi_{axis}"], color="C3", alpha=0.25, lw=0,
                            label="model 95 % band")
            ax.plot(tf, fit[f"mean_{axis}"], color="C3", lw=1, label="model")
            out = fit[f"outside_{axis}"].to_numpy(dtype=bool)
            ax.plot(tf[out], fit[f"observed_{axis}"][out], "kx", ms=3, label="outside the band (5 % expected)")
        ax.set_ylabel(f"error {axis} (arcsec)")
        ax.legend(loc="upper left", fontsize=7)
    axes[-1].set_xlabel("time since t_start (s)")
    fig.suptitle(title)
    fig.subplots_adjust(left=0.11, right=0.98, bottom=0.055, top=0.95, hspace=0.08)
    return fig


SAVE_DPI = 90
"""Resolution of the figures written as files (the report embeds its own at 80 dpi)."""


def save(fig, path):
    fig.savefig(path, dpi=SAVE_DPI, format="png")
    plt.close(fig)


def png(fig, **savefig) -> bytes:
    """The figure as PNG bytes (``savefig``'s keywords), closed after."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", **savefig)
    plt.close(fig)
    return buffer.getvalue()


def _render(job) -> bytes:
    figure, args, savefig = job
    return png(globals()[figure](*args), **savefig)


_INHERITED = ()
"""`render_all`'s jobs while its pool runs: the forked workers find them here, in the memory they share
with the parent, instead of receiving a pickled copy of each job's data (the posterior's, for each of
seven figures, took 110 MB a copy at 10x the default campaign)."""


def _render_inherited(index: int) -> bytes:
    return _render(_INHERITED[index])


def render_all(jobs, processes: int = 1, **savefig) -> list:
    """PNG bytes of each ``(name of a figure function of this module, its arguments)``, in order.
    Drawing is most of the time of the steps that draw, and each figure is independent, so with
    ``processes > 1`` a fork pool of that many draws them; the bytes are the same either way."""
    global _INHERITED
    work = [(figure, args, savefig) for figure, args in jobs]
    if processes <= 1 or len(work) < 2:
        return [_render(job) for job in work]
    _INHERITED = tuple(work)  # before the pool forks its workers
    try:
        with ProcessPoolExecutor(processes, mp_context=multiprocessing.get_context("fork")) as pool:
            return list(pool.map(_render_inherited, range(len(work))))
    finally:
        _INHERITED = ()


def comparison_figure(table):
    """The residual RMS falling across the model variants, against what the noise predicts."""
    fig, ax = plt.subplots(figsize=(7, 3.5))
    x = np.arange(len(table))
    colors = ["C3" if m else "C2" for m in table["misfit"]]
    ax.bar(x, table["residual_rms_arcsec"], color=colors)
    ax.axhline(table["noise_rms_arcsec"].iloc[0], color="k", ls="--", lw=1, label="noise model predicts")
    ax.set_xticks(x, table["model"])
    ax.set_ylabel("residual RMS (arcsec)")
    for xi, (rms, elpd) in enumerate(zip(table["residual_rms_arcsec"], table["elpd_loo"])):
        ax.text(xi, rms, f"{rms:.2f}\nelpd {elpd:.0f}", ha="center", va="bottom", fontsize=8)
    ax.set_ylim(0, 1.25 * table["residual_rms_arcsec"].max())
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("residual RMS per model (red: misfit, green: consistent with the noise)")
    fig.tight_layout()
    return fig


def residual_figure(fit, title):
    """Star tracker minus model per axis and channel set (arcsec), unexplained points marked."""
    fig, axes = plt.subplots(1, 3, figsize=(12, 2.6), sharex=True)
    for ax, axis in zip(axes, PAPER_AXES):
        for s, group in fit.groupby("set"):
            t = group["time"] - fit["time"].min()
            ax.plot(t, group[f"residual_{axis}"], lw=0.5, label=f"set{s}")
            out = group[f"outside_{axis}"].to_numpy(dtype=bool)
            ax.plot(t[out], group[f"residual_{axis}"][out], "kx", ms=3)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_title(f"residual {axis} (arcsec)", fontsize=9)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{title}: residuals", fontsize=10)
    fig.subplots_adjust(left=0.05, right=0.99, bottom=0.1, top=0.8, wspace=0.15)
    return fig


def pair_figure(idata, channel):
    """Pair plot of one channel's four parameters (arviz)."""
    import arviz as az
    labels = [p for p in idata.posterior["parameter"].values if p.startswith(channel + ".")][:4]
    axes = az.plot_pair(idata, var_names=["channel_param"], coords={"parameter": labels}, kind="scatter",
                        marginals=True, figsize=(6, 6), scatter_kwargs={"alpha": 0.15, "s": 2},
                        textsize=8)
    fig = np.asarray(axes).ravel()[0].figure
    fig.suptitle(f"posterior of {channel} (ppm, arcsec)", fontsize=10)
    return fig


def trace_figure(idata, calibration):
    """Traces of the noise scales and of the three parameters with the lowest ESS (sampled
    parameters only: the table's derived combinations have no trace of their own)."""
    import arviz as az
    sampled = (calibration["channel"] + "." + calibration["parameter"]).isin(idata.posterior["parameter"].values)
    worst = calibration[sampled.to_numpy()].nsmallest(3, "ess_bulk")
    labels = [f"{r.channel}.{r.parameter}" for r in worst.itertuples()]
    axes = az.plot_trace(idata, var_names=["channel_param", "sigma_cross_arcsec", "sigma_about_arcsec",
                                           "arw_deg_sqrt_h"], coords={"parameter": labels}, compact=False,
                         figsize=(11, 12))
    fig = np.asarray(axes).ravel()[0].figure
    fig.subplots_adjust(left=0.05, right=0.99, bottom=0.03, top=0.96, hspace=0.6, wspace=0.2)
    return fig
