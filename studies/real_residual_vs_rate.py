"""Does the reference's error grow with the angular rate? (issue 42, the investigation step)

On a campaign directory: the baseline's point estimate (as `gyrocal.study.baseline` fits it: REML noise
scales about the classic start, then WLS), its residual at the reference samples, and their increments
(differences of consecutive residuals: the gyro's random walk becomes white, the reference's white noise
an MA(1)). The increments' variance per axis is binned by the body rate at the reference samples (the
gyro's rate, smoothed over +-``--smooth-s``, at each sample of the pair: rms of the two) and by the
angular acceleration, against the noise model's prediction: ``2 (2 sigma_cross^2 + sigma_about^2) / 3 +
ARW^2 dt`` per axis, with the stated noise and with the REML noise the fit used. A timing jitter of sd
``sigma_t`` (or a marker blur growing with speed) adds ``sigma_t^2 |omega|^2 / 3`` per axis and sample, so

    E |d_j|^2 / 3 = ARW^2 dt_j + 2 sigma0^2 + sigma_t^2 (|omega_j|^2 + |omega_(j-1)|^2) / 3

which a weighted least squares on the binned variances fits (ARW held at the stated value: at a fixed
reference interval its walk and sigma0 cannot be told apart). Then two cheap rivals on the same
residuals: a latency per trial (the increment regressed on ``R omega`` differenced, the error a latency
``tau`` leaves), and a g-sensitivity (the increment regressed on the accelerometer's integral over the
interval, 9 coefficients per trial, where the campaign has ``acc_x, acc_y, acc_z``).

    python studies/real_residual_vs_rate.py CAMPAIGN FIGURE.png [--config config/tstick.yaml] [--arw 0.31]

A campaign the checks refuse (BROAD's free motion, until the pipeline takes it) is read, aligned to body
axes by the estimated mounting, and used without the outlier screen; the script says so.
"""

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np
import yaml

from gyrocal import checks
from gyrocal.checks.mounting import align
from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge, variances
from gyrocal.io.telemetry import TelemetryError, read_campaign
from gyrocal.maneuvers import preprocess
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD

AS2 = ARCSEC_RAD ** 2


def labelled(directory: Path) -> Path:
    """The campaign, or where its maneuvers have no axis labels (free motion, `gyrocal import broad`), a copy
    in a temporary folder labelled ``axis: roll, direction: both`` (the CSVs linked): the labels steer the
    checks and the classic start, not the WLS, and the schema still asks for them."""
    import tempfile
    meta = yaml.safe_load((directory / "campaign.yaml").read_text())
    if all("axis" in m and "direction" in m for m in meta["maneuvers"]):
        return directory
    out = Path(tempfile.mkdtemp()) / directory.name
    out.mkdir()
    for m in meta["maneuvers"]:
        m.setdefault("axis", "roll")
        m.setdefault("direction", "both")
    (out / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    for f in directory.iterdir():
        if f.name != "campaign.yaml":
            (out / f.name).symlink_to(f.resolve())
    print(f"{directory}: maneuvers without axis labels, read from a labelled copy {out}")
    return out


def load(directory: Path):
    """Maneuvers of the campaign, outliers left out where the checks pass; else aligned and unscreened."""
    directory = labelled(directory)
    try:
        campaign, findings = checks.read_checked(directory)
        out = [o.time_s for o in findings.outliers]
        note = f"checked; {len(out)} reference outliers left out"
    except TelemetryError as refused:
        campaign, _, _ = align(read_campaign(directory))
        out = []
        first = str(refused).splitlines()[1].strip()[:160] if "\n" in str(refused) else str(refused)[:160]
        note = f"refused by the checks ({first} ...): aligned by the estimated mounting, no outlier screen"
    return [preprocess.slice_maneuver(campaign, m.id, out) for m in campaign.maneuvers], note


def smoothed_rate(data, half_window_s: float) -> tuple:
    """Body rate (rad/s, the raw gyro) and angular acceleration (rad/s^2) at the reference times: the
    rate averaged over +-half_window_s; the acceleration, the slope of that average."""
    t_mid = 0.5 * (data.gyro_time[1:] + data.gyro_time[:-1])
    rate = data.increments[:, :3] / data.dt[:, None]
    c = np.vstack([np.zeros(3), np.cumsum(rate * data.dt[:, None], axis=0)])  # angle, at gyro_time

    def mean_rate(t0, t1):
        a0 = np.column_stack([np.interp(t0, data.gyro_time, c[:, i]) for i in range(3)])
        a1 = np.column_stack([np.interp(t1, data.gyro_time, c[:, i]) for i in range(3)])
        return (a1 - a0) / (t1 - t0)[:, None]

    t = data.st_time
    lo, hi = np.maximum(t - half_window_s, t_mid[0]), np.minimum(t + half_window_s, t_mid[-1])
    w = mean_rate(lo, hi)
    h = half_window_s
    before = mean_rate(np.maximum(t - 2 * h, t_mid[0]), t)
    after = mean_rate(t, np.minimum(t + 2 * h, t_mid[-1]))
    return w, (after - before) / h


def residuals(maneuvers, est):
    """Per maneuver: inertial residual (M, 3) of the first channel set, the body-to-inertial matrices,
    and each step's walk variance per unit ARW^2."""
    out = []
    for m in range(len(maneuvers)):
        lin = est.linearize(maneuvers, m)
        r = lin.z[:, 0, :] - est.chi0[m]
        walk = lin.st_dt if lin.walk_var is None else lin.walk_var
        out.append((r, lin.st_matrix, walk))
    return out


def per_axis_model(var: dict, walk):
    """Predicted per-axis variance of each increment under the white noise ``var`` (rad^2)."""
    st = 2.0 * (2.0 * var["cross"] + var["about"]) / 3.0
    return st + var["walk"] * walk


def binned(x, y, pred, edges):
    rows = []
    for lo, hi in itertools.pairwise(edges):
        sel = (x >= lo) & (x < hi)
        n = int(sel.sum())
        if n < 5:
            continue
        v = y[sel].mean()
        rows.append(dict(lo=lo, hi=hi, n=n, x=float(np.sqrt(np.mean(x[sel] ** 2))), var=v,
                         se=y[sel].std(ddof=1) / np.sqrt(n), pred=pred[sel].mean()))
    return rows


def fit_jitter(rows, walk_term):
    """WLS of the binned per-axis variance on [1, x^2/3... ]: returns sigma0, sigma_t and their se."""
    y = np.array([r["var"] for r in rows]) - np.array([r["walk"] for r in rows])
    se = np.array([r["se"] for r in rows])
    x2 = np.array([r["x2"] for r in rows])
    A = np.column_stack([2.0 * np.ones_like(x2), x2])
    W = 1.0 / se ** 2
    cov = np.linalg.inv(A.T @ (A * W[:, None]))
    beta = cov @ (A.T @ (W * y))
    chi2 = float(np.sum(W * (y - A @ beta) ** 2))
    return beta, cov, chi2, len(y) - 2


def sd_of(value, var):
    """sqrt of a fitted variance and its se by the delta method (negative: reported as -sqrt(-v))."""
    s = np.sign(value) * np.sqrt(abs(value))
    return s, np.sqrt(var) / (2 * max(abs(s), 1e-30))


def latency(r, R, w):
    """Latency tau (s) by least squares: increment of the residual on the increment of R omega."""
    x = np.einsum("jab,jb->ja", R, w)
    dx, dr = np.diff(x, axis=0).ravel(), np.diff(r, axis=0).ravel()
    tau = dx @ dr / (dx @ dx)
    res = dr - tau * dx
    se = np.sqrt(res @ res / (len(dr) - 1) / (dx @ dx))
    return tau, se, 1.0 - (res @ res) / (dr @ dr)


def g_sensitivity(data, d, R):
    """Increment of the residual on R (integral of acc over the interval) K: share of the increments'
    variance the 9 coefficients explain, and its F statistic's p-value under no effect."""
    from scipy import stats
    if not all(k in data.extras for k in ("acc_x", "acc_y", "acc_z")):
        return None
    acc = np.column_stack([data.extras[k] for k in ("acc_x", "acc_y", "acc_z")])
    c = np.vstack([np.zeros(3), np.cumsum(acc * data.dt[:, None], axis=0)])
    A = np.column_stack([np.interp(data.st_time, data.gyro_time, c[:, i]) for i in range(3)])
    dA = np.diff(A, axis=0)                        # body, m/s
    Rm = R[1:]
    # d_j (inertial, 3) = Rm_j K dA_j: linear in K's 9 entries
    X = np.einsum("jab,jc->jabc", Rm, dA).reshape(len(dA), 3, 9).reshape(-1, 9)
    d = d.ravel()
    k, *_ = np.linalg.lstsq(X, d, rcond=None)
    res = d - X @ k
    share = 1.0 - (res @ res) / (d @ d)
    dof = len(d) - 9
    f = (share / 9) / ((1 - share) / dof)
    return share, float(stats.f.sf(f, 9, dof)), np.abs(k).max() / ARCSEC_RAD


def analyse(directory: Path, figure: Path, config: Path, smooth_s: float, nbins: int, arw=None):
    noise_defaults = yaml.safe_load(config.read_text())["noise"]
    if arw is not None:
        noise_defaults["arw_deg_sqrt_h"] = arw
    maneuvers, note = load(directory)
    print(f"campaign {directory}: {len(maneuvers)} maneuvers; {note}")
    info = read_campaign(labelled(directory))
    stated = noise_knowledge({"star_tracker": info.star_tracker, "gyro": info.gyro}, noise_defaults)
    spec = ModelSpec.build("baseline", effects.resolve("baseline", list(effects.BASELINE), {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    names, index = preprocess.noise_groups(maneuvers)
    print(f"baseline WLS: {est.nfev} evaluations, {est.message}; REML noise "
          + ", ".join(f"{v:.4g}" for v in np.exp(est.log_sigma) / [ARCSEC_RAD, ARCSEC_RAD, np.pi / 180 / 60])
          + " (arcsec, arcsec, deg/sqrt(h))" + ("" if est.group_offsets is None else
                                                f", group factors {np.round(np.exp(est.group_offsets), 3).tolist()}"))
    stated_var = variances(np.log([stated["sigma_cross_arcsec"] * ARCSEC_RAD, stated["sigma_about_arcsec"] * ARCSEC_RAD,
                                   stated["arw_deg_sqrt_h"] * np.pi / 180 / 60]))
    print(f"stated noise: sigma_cross {stated['sigma_cross_arcsec']:.0f}, sigma_about {stated['sigma_about_arcsec']:.0f} "
          f"arcsec, ARW {stated['arw_deg_sqrt_h']:.2f} deg/sqrt(h)")
    cols = {k: [] for k in ("y", "y_lat", "pred", "fit", "w2", "acc", "walk", "trial")}
    print("\nper trial: rms increment per axis (arcsec), against the stated and REML noise models; latency; g-sensitivity")
    print("| trial | n | rms incr | stated model | ratio | REML model | ratio | latency ms (se) | share "
          "| g-sens share, p; less latency |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for m, (data, (r, R, walk)) in enumerate(zip(maneuvers, residuals(maneuvers, est))):
        w, acc = smoothed_rate(data, smooth_s)
        d = np.diff(r, axis=0)
        y = np.sum(d ** 2, axis=1) / 3.0
        w2 = np.sum(w ** 2, axis=1)
        fitted = est.maneuver_variances(m, index[m] if len(names) > 1 else 0)
        pred, fit = per_axis_model(stated_var, walk[1:]), per_axis_model(fitted, walk[1:])
        tau, tau_se, tau_share = latency(r, R, w)
        d_lat = d - tau * np.diff(np.einsum("jab,jb->ja", R, w), axis=0)
        g, g_lat = g_sensitivity(data, d, R), g_sensitivity(data, d_lat, R)
        gtxt = "n/a" if g is None else f"{g[0]:.3f}, {g[1]:.2g}; {g_lat[0]:.3f}, {g_lat[1]:.2g}"
        print(f"| {data.id} | {len(y)} | {np.sqrt(y.mean()) / ARCSEC_RAD:.0f} | {np.sqrt(pred.mean()) / ARCSEC_RAD:.0f} | "
              f"{np.sqrt(y.mean() / pred.mean()):.2f} | {np.sqrt(fit.mean()) / ARCSEC_RAD:.0f} | "
              f"{np.sqrt(y.mean() / fit.mean()):.2f} | {1e3 * tau:+.1f} ({1e3 * tau_se:.1f}) | {tau_share:.3f} | {gtxt} |")
        for k, v in (("y", y), ("y_lat", np.sum(d_lat ** 2, axis=1) / 3.0), ("pred", pred), ("fit", fit),
                     ("w2", 0.5 * (w2[1:] + w2[:-1])),
                     ("acc", np.sqrt(0.5 * (np.sum(acc[1:] ** 2, 1) + np.sum(acc[:-1] ** 2, 1)))),
                     ("walk", stated_var["walk"] * walk[1:]), ("trial", np.full(len(y), m))):
            cols[k].append(v)
    c = {k: np.concatenate(v) for k, v in cols.items()}
    tables, beta = report(c, len(maneuvers), nbins, "the baseline's residual increments")
    lat_tables, lat_beta = report(dict(c, y=c["y_lat"]), len(maneuvers), nbins,
                                  "the same increments less each trial's latency (tau above) times the change of R omega")
    plot(tables, beta, lat_tables, figure, directory.name)
    return tables, beta, lat_tables, lat_beta


def report(c, n_trials, nbins, label):
    """The binned tables and the WLS fits of one set of increments, ``c["y"]``."""
    print(f"\n=== {label} ===")
    tables = {}
    for name, x, unit, scale in (("rate", np.sqrt(c["w2"]), "deg/s", 180 / np.pi),
                                 ("acceleration", c["acc"], "deg/s^2", 180 / np.pi)):
        pos = x[x > 0]
        edges = np.quantile(pos, np.linspace(0, 1, nbins + 1))
        edges[-1] *= 1.0001
        rows = binned(x, c["y"], c["pred"], edges)
        for r_ in rows:
            sel = (x >= r_["lo"]) & (x < r_["hi"])
            r_["fit"], r_["walk"], r_["x2"] = c["fit"][sel].mean(), c["walk"][sel].mean(), (2 * c["w2"][sel] / 3).mean()
        tables[name] = (rows, unit, scale)
        print(f"\nincrement variance per axis binned by {name} (rms over the pair, {unit}); arcsec^2")
        print(f"| {name} bin, {unit} | n | observed var | se | stated model | obs/stated | REML model | obs/REML |")
        print("|---|---|---|---|---|---|---|---|")
        for r_ in rows:
            print(f"| {r_['lo'] * scale:.3g}-{r_['hi'] * scale:.3g} | {r_['n']} | {r_['var'] / AS2:.4g} | "
                  f"{r_['se'] / AS2:.2g} | {r_['pred'] / AS2:.4g} | {r_['var'] / r_['pred']:.1f} | {r_['fit'] / AS2:.4g} | "
                  f"{r_['var'] / r_['fit']:.2f} |")
        rho = np.corrcoef(np.log([r_["x"] for r_ in rows]), np.log([r_["var"] for r_ in rows]))[0, 1]
        print(f"log-log correlation of binned variance with {name}: {rho:+.2f}")
    rows = tables["rate"][0]
    beta, cov, chi2, dof = fit_jitter(rows, None)
    s0, s0_se = sd_of(beta[0], cov[0, 0])
    st, st_se = sd_of(beta[1], cov[1, 1])
    print(f"\nWLS on the {len(rows)} rate bins, var = ARW^2 dt + 2 sigma0^2 + sigma_t^2 (|w_j|^2 + |w_j-1|^2)/3:")
    print(f"  sigma0 = {s0 / ARCSEC_RAD:.0f} +- {s0_se / ARCSEC_RAD:.0f} arcsec; sigma_t = {1e3 * st:.2f} +- "
          f"{1e3 * st_se:.2f} ms; "
          f"chi2 = {chi2:.1f} on {dof} dof; sigma_t^2 / se = {beta[1] / np.sqrt(cov[1, 1]):.2f}")
    excess = c["y"].sum() - c["pred"].sum()
    rate_part = beta[1] * (2 * c["w2"] / 3).sum()
    print(f"  the rate term holds {rate_part / c['y'].sum():.1%} of the observed increment variance, "
          f"{rate_part / excess:.1%} of its excess over the stated model; observed / stated = "
          f"{c['y'].sum() / c['pred'].sum():.2f} in variance ({np.sqrt(c['y'].sum() / c['pred'].sum()):.2f} in sd), "
          f"without the rate term {(c['y'].sum() - rate_part) / c['pred'].sum():.2f} "
          f"({np.sqrt(max(c['y'].sum() - rate_part, 0) / c['pred'].sum()):.2f} in sd)")
    per_trial_fit(c, n_trials, max(2, nbins // 2))
    return tables, beta



def per_trial_fit(c, n_trials, nbins):
    """The same WLS with a sigma0 per trial and one sigma_t: a rate that differs between trials
    whose levels differ cannot pass for a rate dependence."""
    y, se, rows_x2, trial = [], [], [], []
    for m in range(n_trials):
        sel = c["trial"] == m
        x = np.sqrt(c["w2"][sel])
        edges = np.quantile(x, np.linspace(0, 1, nbins + 1))
        edges[-1] *= 1.0001
        for lo, hi in itertools.pairwise(edges):
            b = (x >= lo) & (x < hi)
            if b.sum() < 5:
                continue
            v = c["y"][sel][b] - c["walk"][sel][b]
            y.append(v.mean())
            se.append(v.std(ddof=1) / np.sqrt(b.sum()))
            rows_x2.append((2 * c["w2"][sel][b] / 3).mean())
            trial.append(m)
    y, se, x2, trial = map(np.array, (y, se, rows_x2, trial))
    rows_x2 = x2
    A = np.column_stack([2.0 * (trial == m) for m in range(n_trials)] + [x2])
    W = 1.0 / se ** 2
    cov = np.linalg.inv(A.T @ (A * W[:, None]))
    beta = cov @ (A.T @ (W * y))
    chi2 = float(np.sum(W * (y - A @ beta) ** 2))
    st, st_se = sd_of(beta[-1], cov[-1, -1])
    s0 = ", ".join(f"{sd_of(b, v)[0] / ARCSEC_RAD:.0f} +- {sd_of(b, v)[1] / ARCSEC_RAD:.0f}"
                   for b, v in zip(beta[:-1], np.diag(cov)[:-1]))
    print(f"\nWLS with a sigma0 per trial ({nbins} rate bins each): sigma0 = {s0} arcsec; sigma_t = {1e3 * st:.2f} +- "
          f"{1e3 * st_se:.2f} ms; sigma_t^2 / se = {beta[-1] / np.sqrt(cov[-1, -1]):.2f}; chi2 = {chi2:.1f} on "
          f"{len(y) - len(beta)} dof")
    rate_part = beta[-1] * (2 * c["w2"] / 3).sum()
    print(f"  its rate term holds {rate_part / c['y'].sum():.1%} of the observed increment variance; observed / stated "
          f"{np.sqrt(c['y'].sum() / c['pred'].sum()):.2f} in sd, without the rate term "
          f"{np.sqrt(max(c['y'].sum() - rate_part, 0) / c['pred'].sum()):.2f}")
    slope = np.polyfit(np.log(np.sqrt(rows_x2 * 1.5)), np.log(np.maximum(y, 1e-30)), 1)[0]
    print(f"  log-log slope of the binned variance (less the walk) on the rate, all trials' bins: {slope:.2f} "
          f"(a timing jitter alone: 2 where it dominates)")
    return beta, cov


def plot(tables, beta, lat_tables, figure: Path, title: str):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, (name, (rows, unit, scale)) in zip(axes, tables.items()):
        x = np.array([r["x"] for r in rows]) * scale
        ax.errorbar(x, [r["var"] / AS2 for r in rows], yerr=[2 * r["se"] / AS2 for r in rows], fmt="o", label="observed")
        ax.plot(x, [r["pred"] / AS2 for r in rows], "s--", label="stated noise model")
        ax.plot(x, [r["fit"] / AS2 for r in rows], "^:", label="REML noise model")
        lat = lat_tables[name][0]
        ax.errorbar(np.array([r["x"] for r in lat]) * scale, [r["var"] / AS2 for r in lat],
                    yerr=[2 * r["se"] / AS2 for r in lat], fmt="x", label="observed, less each trial's latency")
        if name == "rate":
            ax.plot(x, [(r["walk"] + 2 * beta[0] + beta[1] * r["x2"]) / AS2 for r in rows], "-",
                    label="fit: sigma0 + sigma_t |omega|")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"{name} at the reference samples, {unit}")
        ax.set_ylabel("increment variance per axis, arcsec^2")
        ax.legend(fontsize=8)
    fig.suptitle(f"{title}: residual increments against rate and acceleration (bars: 2 se)")
    fig.tight_layout()
    figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(figure, dpi=110)
    print(f"figure: {figure}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("campaign", type=Path)
    p.add_argument("figure", type=Path)
    p.add_argument("--config", type=Path, default=Path(__file__).resolve().parents[1] / "config" / "tstick.yaml",
                   help="a config whose noise section states the noise where campaign.yaml does not")
    p.add_argument("--arw", type=float, help="the gyro's ARW, deg/sqrt(h), in place of the config's (BROAD: 0.31, "
                   "from the rest phases' 0.087 deg/s a sample at 285.7 Hz)")
    p.add_argument("--smooth-s", type=float, default=0.05, help="half window of the rate at a sample, s")
    p.add_argument("--bins", type=int, default=8)
    a = p.parse_args(argv)
    analyse(a.campaign, a.figure, a.config, a.smooth_s, a.bins, a.arw)
    return 0


if __name__ == "__main__":
    sys.exit(main())
