"""Does the reference's rate-dependent error lie along the rotation axis (a timing jitter) or in every
direction (a marker blur)? (issue 42 item 2: whether `st_jitter` needs an isotropic partner)

A timing jitter ``sigma_t`` leaves the reference at sample j off by ``R_j omega_j dt``: a covariance
``sigma_t^2 a_j a_j^T`` with ``a_j = R_j omega_j`` (inertial, rank one). A blur that grows with the
speed leaves ``sigma_b^2 |omega_j|^2 I``, the same in every direction. Their traces are alike, so the
binned variance of `real_residual_vs_rate` cannot tell them apart; the direction can.

On a campaign directory: the baseline's point estimate (with ``--effects``' beside it) and its inertial residual at the reference
samples (as `real_residual_vs_rate`), the increments ``d_j = r_j - r_(j-1)``, of which every second
one (j even) is kept: under white reference noise those are independent, so their Gaussian likelihood
is exact. Each is modelled as

    d_j ~ N(0, C_m + ARW^2 dt_j I + sigma_t^2 (a_j a_j^T + a_(j-1) a_(j-1)^T)
                  + sigma_b^2 (|omega_j|^2 + |omega_(j-1)|^2) I)

with ``C_m`` a free 3x3 covariance per trial (the reference's own noise, anisotropic as it likes, and
constant in time), ARW the stated one. Maximum likelihood with ``sigma_t``, ``sigma_b``, both or
neither; each term's likelihood ratio given the other (chi-square on one dof, halved: the boundary),
and the odd increments as a second, independent look.

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
from real_residual_vs_rate import labelled, load, residuals, smoothed_rate  # noqa: E402

from gyrocal.inference.fit import classic  # noqa: E402
from gyrocal.inference.fit.estimate import point_estimate  # noqa: E402
from gyrocal.inference.noise.covariance import noise_knowledge  # noqa: E402
from gyrocal.io.telemetry import read_campaign  # noqa: E402
from gyrocal.model import effects  # noqa: E402
from gyrocal.model.spec import ModelSpec  # noqa: E402
from gyrocal.model.units import ARCSEC_RAD, DEG_SQRT_H_RAD_SQRT_S  # noqa: E402

TERMS = ("jitter", "blur")


def increments(maneuvers, est, arw_rad_sqrt_s: float, smooth_s: float, parity: int) -> list:
    """Per trial: the kept increments (n, 3, rad), their walk covariance (n, rad^2), the axial shapes
    ``a_j a_j^T + a_(j-1) a_(j-1)^T`` (n, 3, 3, rad^2/s^2) and the isotropic ``|omega_j|^2 + |omega_(j-1)|^2``."""
    out = []
    for data, (r, R, walk) in zip(maneuvers, residuals(maneuvers, est)):
        w, _ = smoothed_rate(data, smooth_s)
        a = np.einsum("jab,jb->ja", R, w)
        keep = np.arange(1, len(r))
        keep = keep[keep % 2 == parity]
        d = r[keep] - r[keep - 1]
        axial = np.einsum("ja,jb->jab", a[keep], a[keep]) + np.einsum("ja,jb->jab", a[keep - 1], a[keep - 1])
        iso = np.sum(w[keep] ** 2, axis=1) + np.sum(w[keep - 1] ** 2, axis=1)
        out.append((d, arw_rad_sqrt_s ** 2 * np.asarray(walk)[keep], axial, iso))
    return out


def _base(params6):
    """A covariance from its Cholesky factor's 6 entries (log diagonal)."""
    L = np.zeros((3, 3))
    L[np.tril_indices(3)] = params6
    L[np.diag_indices(3)] = np.exp(L[np.diag_indices(3)])
    return L @ L.T


def negloglik(x, parts, terms):
    """Negative log-likelihood; ``x``: 6 Cholesky entries per trial (radians scaled by 1 arcsec), then the
    log variances of ``terms`` (s^2 for the jitter, (rad/(rad/s))^2 = s^2 too for the blur)."""
    n_tr = len(parts)
    extra = dict(zip(terms, np.exp(x[6 * n_tr:])))
    total = 0.0
    for m, (d, walk, axial, iso) in enumerate(parts):
        S = _base(x[6 * m:6 * m + 6]) * ARCSEC_RAD ** 2 + walk[:, None, None] * np.eye(3)
        S = S + extra.get("jitter", 0.0) * axial + extra.get("blur", 0.0) * iso[:, None, None] * np.eye(3)
        sign, logdet = np.linalg.slogdet(S)
        quad = np.einsum("ja,ja->j", d, np.linalg.solve(S, d[..., None])[..., 0])
        total += 0.5 * float(np.sum(logdet + quad))
    return total


def fit(parts, terms):
    """Maximum likelihood with the given rate terms; returns (neg log-lik, their sd in ms)."""
    x0 = []
    for d, *_ in parts:
        c = np.cov(d.T) / ARCSEC_RAD ** 2
        L = np.linalg.cholesky(c + 1e-6 * np.eye(3))
        L[np.diag_indices(3)] = np.log(np.diag(L))
        x0.extend(L[np.tril_indices(3)])
    best = None
    for start in (np.log(1e-3 ** 2), np.log(1e-2 ** 2)):
        x = np.concatenate([x0, np.full(len(terms), start)])
        res = minimize(negloglik, x, args=(parts, terms), method="L-BFGS-B")
        if best is None or res.fun < best.fun:
            best = res
    sd_ms = {t: 1e3 * float(np.exp(0.5 * v)) for t, v in zip(terms, best.x[6 * len(parts):])}
    return float(best.fun), sd_ms


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
    print("| increments | n | none | jitter | blur | both | jitter given blur: LR, log10 p | "
          "blur given jitter: LR, log10 p |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for parity, name in ((0, "even"), (1, "odd")):
        parts = increments(maneuvers, est, stated["arw_deg_sqrt_h"] * DEG_SQRT_H_RAD_SQRT_S, smooth_s, parity)
        fits = {k: fit(parts, t) for k, t in (("none", ()), ("jitter", ("jitter",)), ("blur", ("blur",)),
                                                ("both", TERMS))}
        lr_j = 2 * (fits["blur"][0] - fits["both"][0])
        lr_b = 2 * (fits["jitter"][0] - fits["both"][0])
        n = sum(len(p[0]) for p in parts)
        cell = {k: ", ".join(f"sigma_{t[0]} {v:.2f} ms" for t, v in f[1].items()) or f"-" for k, f in fits.items()}
        gain = {k: 2 * (fits["none"][0] - f[0]) for k, f in fits.items()}
        print(f"| {name} | {n} | 0 | {cell['jitter']} (LR {gain['jitter']:.1f}) | {cell['blur']} (LR {gain['blur']:.1f}) "
              f"| {cell['both']} (LR {gain['both']:.1f}) | {lr_j:.1f}, {half_chi2_log10p(lr_j):.2f} | "
              f"{lr_b:.1f}, {half_chi2_log10p(lr_b):.2f} |")
        rows.append(dict(parity=name, n=n, lr_jitter_given_blur=lr_j, lr_blur_given_jitter=lr_b, **gain))
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
