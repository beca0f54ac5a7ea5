"""Does the reference's rate-dependent error lie along the rotation axis (a timing jitter) or in every
direction (a marker blur)? (issue 42 item 2: whether `st_jitter` needs an isotropic partner)

A timing jitter ``sigma_t`` leaves the reference at sample j off by ``R_j omega_j dt``: a covariance
``sigma_t^2 a_j a_j^T`` with ``a_j = R_j omega_j`` (inertial, rank one). A blur that grows with the
speed leaves ``sigma_b^2 |omega_j|^2 I``, the same in every direction. Their traces are alike, so the
binned variance of `real_residual_vs_rate` cannot tell them apart; the direction can. A third form
is the gyro's: a white scale-factor noise of density ``k`` (ppm/sqrt(Hz)) adds ``k^2 int |omega|^2 dt I``
over the interval, an error that grows with the interval where the reference's two do not; fitting
all three at several reference intervals tells a per-sample reference error from an integrated one.

On a campaign directory: the baseline's point estimate (with ``--effects``' beside it) and its inertial residual at the reference
samples (as `real_residual_vs_rate`), the increments ``d_j = r_j - r_(j-1)``, of which every second
one (j even) is kept: under white reference noise those are independent, so their Gaussian likelihood
is exact. Each is modelled as

    d_j ~ N(0, C_m + ARW^2 dt_j I + sigma_t^2 (a_j a_j^T + a_(j-1) a_(j-1)^T)
                  + sigma_b^2 (|omega_j|^2 + |omega_(j-1)|^2) I + k^2 int_(t_(j-1))^(t_j) |omega|^2 dt I)

with ``C_m`` a free 3x3 covariance per trial (the reference's own noise, anisotropic as it likes, and
constant in time), ARW the stated one. Maximum likelihood with ``sigma_t``, ``sigma_b``, both or
with subsets of the three; each term's likelihood ratio given the two others (chi-square on one dof,
halved: the boundary), and the odd increments as a second, independent look.

    python studies/rate_noise_axis.py CAMPAIGN [--config config/tstick.yaml] [--arw 0.31] [--effects st_latency]
"""

import argparse
import sys
from pathlib import Path

import numpy as np
import yaml
from scipy.optimize import minimize
from scipy.special import log_ndtr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from real_residual_vs_rate import labelled, load, residuals, smoothed_rate

from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.io.telemetry import read_campaign
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S

TERMS = ("jitter", "blur", "gyro")
START = {"jitter": np.log(1e-3 ** 2), "blur": np.log(1e-3 ** 2), "gyro": np.log(1e-3 ** 2)}
"""Each term's starting log variance: 1 ms of jitter or blur, 1000 ppm/sqrt(Hz)."""
UNIT = {"jitter": ("sigma_t", "ms", 1e3), "blur": ("sigma_b", "ms", 1e3), "gyro": ("k", "ppm/sqrt(Hz)", 1e6)}


def increments(maneuvers, est, arw_rad_sqrt_s: float, smooth_s: float, parity: int) -> list:
    """Per trial: the kept increments (n, 3, rad), their walk covariance (n, rad^2), the axial shapes
    ``a_j a_j^T + a_(j-1) a_(j-1)^T`` (n, 3, 3, rad^2/s^2), the isotropic ``|omega_j|^2 + |omega_(j-1)|^2`` and
the gyro's ``int |omega|^2 dt`` over the interval (rad^2/s)."""
    out = []
    for data, (r, R, walk) in zip(maneuvers, residuals(maneuvers, est)):
        w, _ = smoothed_rate(data, smooth_s)
        a = np.einsum("jab,jb->ja", R, w)
        keep = np.arange(1, len(r))
        keep = keep[keep % 2 == parity]
        d = r[keep] - r[keep - 1]
        axial = np.einsum("ja,jb->jab", a[keep], a[keep]) + np.einsum("ja,jb->jab", a[keep - 1], a[keep - 1])
        iso = np.sum(w[keep] ** 2, axis=1) + np.sum(w[keep - 1] ** 2, axis=1)
        energy = np.concatenate([[0.0], np.cumsum(np.sum(data.increments[:, :3] ** 2, axis=1) / data.dt)])
        at_st = np.interp(data.st_time, data.gyro_time, energy)  # int |omega|^2 dt from the start, rad^2/s
        integrated = at_st[keep] - at_st[keep - 1]
        out.append((d, arw_rad_sqrt_s ** 2 * np.asarray(walk)[keep], axial, iso, integrated))
    return out


def _base(params6):
    """A covariance from its Cholesky factor's 6 entries (log diagonal)."""
    L = np.zeros((3, 3))
    L[np.tril_indices(3)] = params6
    L[np.diag_indices(3)] = np.exp(L[np.diag_indices(3)])
    return L @ L.T


def negloglik(x, parts, terms):
    """Negative log-likelihood; ``x``: 6 Cholesky entries per trial (radians scaled by 1 arcsec), then the
    log variances of ``terms`` (s^2 for the jitter, (rad/(rad/s))^2 = s^2 too for the blur, 1/Hz for the gyro's)."""
    n_tr = len(parts)
    extra = dict(zip(terms, np.exp(x[6 * n_tr:])))
    total = 0.0
    for m, (d, walk, axial, iso, integrated) in enumerate(parts):
        S = _base(x[6 * m:6 * m + 6]) * ARCSEC_RAD ** 2 + walk[:, None, None] * np.eye(3)
        S = S + extra.get("jitter", 0.0) * axial
        S = S + (extra.get("blur", 0.0) * iso + extra.get("gyro", 0.0) * integrated)[:, None, None] * np.eye(3)
        sign, logdet = np.linalg.slogdet(S)
        if np.any(sign <= 0) or not np.all(np.isfinite(logdet)):
            return np.inf  # a step out of the positive definite cone: the optimizer steps back
        quad = np.einsum("ja,ja->j", d, np.linalg.solve(S, d[..., None])[..., 0])
        total += 0.5 * float(np.sum(logdet + quad))
    return total


def fit(parts, terms, warm=()):
    """Maximum likelihood with the given rate terms, from two cold starts and from each ``warm`` fit's
    optimum (``(terms, x)`` of a nested model; a term it lacks starts at nothing, one it has beyond
    ``terms`` is dropped), so a larger model never ends below a smaller one; returns (neg log-lik,
    each term's sd in its `UNIT`, the optimum ``x``)."""
    x0 = []
    for d, *_ in parts:
        c = np.cov(d.T) / ARCSEC_RAD ** 2
        L = np.linalg.cholesky(c + 1e-6 * np.eye(3))
        L[np.diag_indices(3)] = np.log(np.diag(L))
        x0.extend(L[np.tril_indices(3)])
    starts = [np.concatenate([x0, [START[t] + shift for t in terms]]) for shift in (0.0, np.log(100.0))]
    n_base = 6 * len(parts)
    for other, x in warm:
        value = dict(zip(other, x[n_base:]))
        starts.append(np.concatenate([x[:n_base], [value.get(t, START[t] - 20.0) for t in terms]]))
    best = None
    for x in starts:
        res = minimize(negloglik, x, args=(parts, terms), method="L-BFGS-B")
        if best is None or res.fun < best.fun:
            best = res
    sd = {t: UNIT[t][2] * float(np.exp(0.5 * v)) for t, v in zip(terms, best.x[n_base:])}
    return float(best.fun), sd, best.x


def half_chi2_log10p(lr: float) -> float:
    """log10 of half the chi-square(1) tail of a likelihood ratio ``lr`` (twice the log-likelihood gain)."""
    return float(log_ndtr(-np.sqrt(max(lr, 0.0))) / np.log(10)) if lr > 0 else 0.0


def analyse(directory: Path, config: Path, arw, smooth_s: float, extra=()):
    noise_defaults = yaml.safe_load(config.read_text())["noise"]
    if arw is not None:
        noise_defaults["arw_deg_sqrt_h"] = arw
    maneuvers, note = load(directory)
    info = read_campaign(labelled(directory))
    stated = noise_knowledge({"star_tracker": info.star_tracker, "gyro": info.gyro}, noise_defaults)
    names = list(effects.BASELINE) + list(extra)
    spec = ModelSpec.build("model", effects.resolve("model", names, {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    print(f"campaign {directory}: {len(maneuvers)} maneuvers; {note}; ARW {stated['arw_deg_sqrt_h']:.3g} deg/sqrt(h); "
          f"residuals of {' + '.join(names)}")
    print("| increments | n | model | twice the log-likelihood gain over none | estimates |")
    print("|---|---|---|---|---|")
    rows = []
    subsets = [()] + [(t,) for t in TERMS] + [tuple(t for t in TERMS if t != u) for u in TERMS] + [TERMS]
    for parity, name in ((0, "even"), (1, "odd")):
        parts = increments(maneuvers, est, stated["arw_deg_sqrt_h"] * DEG_SQRT_H_RAD_SQRT_S, smooth_s, parity)
        fits = {}
        for t in subsets:  # smaller models first: each larger one starts from their optima too
            fits[t] = fit(parts, t, [(u, f[2]) for u, f in fits.items() if set(u) < set(t)])
        for t in subsets[::-1]:  # and each smaller one from the larger ones' optima, the extra terms dropped
            better = fit(parts, t, [(u, f[2]) for u, f in fits.items() if set(t) < set(u)])
            fits[t] = min(fits[t], better, key=lambda f: f[0])
        n = sum(len(p[0]) for p in parts)
        for t, (nll, sd, _) in fits.items():
            est_txt = ", ".join(f"{UNIT[k][0]} {v if v > 1e-3 else 0:.3g} {UNIT[k][1]}" for k, v in sd.items()) or "-"
            print(f"| {name} | {n} | {' + '.join(t) or 'none'} | {2 * (fits[()][0] - nll):.1f} | {est_txt} |")
        row = dict(increments=name, n=n)
        for u in TERMS:
            others = tuple(t for t in TERMS if t != u)
            lr = 2 * (fits[others][0] - fits[TERMS][0])
            row[f"lr_{u}_given_others"], row[f"log10p_{u}"] = round(lr, 1), round(half_chi2_log10p(lr), 2)
        rows.append(row)
    print("\neach term given the two others (likelihood ratio, log10 p halved for the boundary):")
    for row in rows:
        print("  " + ", ".join(f"{k} {v}" for k, v in row.items()))
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("campaign", type=Path)
    p.add_argument("--config", type=Path, default=Path(__file__).resolve().parents[1] / "config" / "tstick.yaml",
                   help="a config whose noise section states the noise where campaign.yaml does not")
    p.add_argument("--arw", type=float, help="the gyro's ARW, deg/sqrt(h), in place of the config's (BROAD: 0.31)")
    p.add_argument("--effects", nargs="*", default=[], help="library effects fitted beside the baseline "
                   "before the residuals are taken (e.g. st_latency: a latency's error lies along the change of R omega)")
    p.add_argument("--smooth-s", type=float, default=0.05, help="half window of the rate at a sample, s")
    a = p.parse_args(argv)
    analyse(a.campaign, a.config, a.arw, a.smooth_s, a.effects)
    return 0


if __name__ == "__main__":
    sys.exit(main())
