"""Does the reference error that grows with the rate lie along the rotation axis (a timing jitter,
`st_jitter`) or in every direction (marker blur, ``sigma_b^2 |omega|^2 I``)? (issue 42 item 2)

On a campaign: the baseline's residual increments at the reference samples (as
`studies/real_residual_vs_rate.py` takes them: the point estimate, the first channel set, differences of
consecutive residuals), each split along the rotation axis ``u`` (the body rate's direction at the two
samples, averaged, in the reference frame) and across it. A timing jitter ``sigma_t`` adds
``sigma_t^2 q`` along ``u`` only (``q`` the mean squared rate at the two samples, one error per sample); a
blur of ``sigma_b`` per rad/s adds ``sigma_b^2 q`` in each of the three directions. So

    along  = a + (sigma_t^2 + sigma_b^2) q,    across (per direction) = a' + sigma_b^2 q

fitted by least squares on the increments of samples turning faster than ``--min-rate-deg-s`` (the axis
is noise at rest), with standard errors from the residuals' spread. The blur is needed where
``sigma_b^2`` is significantly above 0.

``--latency``: the residuals of the baseline plus `st_latency` (a latency left out errs by ``tau omega``,
along the axis too, and grows with the rate).

    python studies/jitter_axis.py CAMPAIGN [--config config/tstick.yaml] [--arw 0.31] [--latency]
"""

import argparse
import importlib.util
from pathlib import Path

import numpy as np
import yaml

from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.io.telemetry import read_campaign
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD

_spec = importlib.util.spec_from_file_location("rate_study", Path(__file__).with_name("real_residual_vs_rate.py"))
rate_study = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(rate_study)


def split(maneuvers, est, smooth_s: float):
    """Per increment: the squared component along the rotation axis, the mean squared component across
    it (per direction), the mean squared rate ``q`` (rad^2/s^2) and the trial's index."""
    rows = []
    for m, (data, (r, R, _)) in enumerate(zip(maneuvers, rate_study.residuals(maneuvers, est))):
        w, _ = rate_study.smoothed_rate(data, smooth_s)
        d = np.diff(r, axis=0)
        axis = np.einsum("jab,jb->ja", R, w)
        u = 0.5 * (axis[1:] + axis[:-1])
        u = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)
        along = np.einsum("ja,ja->j", d, u) ** 2
        across = 0.5 * (np.sum(d**2, axis=1) - along)
        w2 = np.sum(w**2, axis=1)
        rows.append(np.column_stack([along, across, 0.5 * (w2[1:] + w2[:-1]), np.full(len(d), m)]))
    return np.vstack(rows)


def fit(y, q, trial):
    """Least squares of ``y = a_trial + s q``; ``s`` and its standard error (from the residuals' spread)."""
    n_trials = int(trial.max()) + 1
    x = np.column_stack([(trial == k).astype(float) for k in range(n_trials)] + [q])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    resid = y - x @ coef
    cov = np.linalg.inv(x.T @ x) * np.sum(resid**2) / (len(y) - x.shape[1])
    return coef[-1], float(np.sqrt(cov[-1, -1]))


def campaign_parser(description: str) -> argparse.ArgumentParser:
    """The arguments both jitter studies take: the campaign, the config whose ``noise`` is stated, an ARW."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("campaign", type=Path)
    parser.add_argument("--config", type=Path, default=Path("config/tstick.yaml"))
    parser.add_argument("--arw", type=float, default=None)
    return parser


def stated_campaign(args) -> tuple:
    """The campaign's maneuvers (`real_residual_vs_rate.load`), how they were read, and the stated noise."""
    defaults = yaml.safe_load(args.config.read_text())["noise"]
    if args.arw is not None:
        defaults["arw_deg_sqrt_h"] = args.arw
    maneuvers, note = rate_study.load(args.campaign)
    info = read_campaign(rate_study.labelled(args.campaign))
    return maneuvers, note, noise_knowledge({"star_tracker": info.star_tracker, "gyro": info.gyro}, defaults)


def main(argv=None):
    parser = campaign_parser(__doc__.splitlines()[0])
    parser.add_argument("--smooth-s", type=float, default=0.05)
    parser.add_argument("--min-rate-deg-s", type=float, default=5.0)
    parser.add_argument("--latency", action="store_true", help="fit st_latency with the baseline")
    args = parser.parse_args(argv)
    maneuvers, note, stated = stated_campaign(args)
    names = list(effects.BASELINE) + (["st_latency"] if args.latency else [])
    spec = ModelSpec.build("model", effects.resolve("model", names, {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    rows = split(maneuvers, est, args.smooth_s)
    fast = rows[:, 2] > np.deg2rad(args.min_rate_deg_s) ** 2
    rows = rows[fast]
    s_along, se_along = fit(rows[:, 0], rows[:, 2], rows[:, 3])
    s_across, se_across = fit(rows[:, 1], rows[:, 2], rows[:, 3])
    if args.latency:
        print(f"latency fitted: {est.theta[spec.labels.index('st_latency.latency')] * 1e3:.2f} ms")
    print(f"campaign {args.campaign}: {note}; {fast.sum()} increments turning faster than {args.min_rate_deg_s} deg/s")
    print(f"mean squared increment: along the axis {np.sqrt(rows[:, 0].mean()) / ARCSEC_RAD:.0f} arcsec, across it "
          f"{np.sqrt(rows[:, 1].mean()) / ARCSEC_RAD:.0f} arcsec per direction")
    print(f"slope along (sigma_t^2 + sigma_b^2): {s_along:.3e} +- {se_along:.1e} s^2 (z {s_along / se_along:+.1f})")
    print(f"slope across (sigma_b^2):           {s_across:.3e} +- {se_across:.1e} s^2 (z {s_across / se_across:+.1f})")
    jitter = max(s_along - s_across, 0.0)
    print(f"sigma_t = {1e3 * np.sqrt(jitter):.2f} ms; sigma_b = {1e3 * np.sqrt(max(s_across, 0.0)):.2f} ms (arcsec per "
          f"arcsec/s x 1000); along - across: {s_along - s_across:.3e} +- {np.hypot(se_along, se_across):.1e}")


if __name__ == "__main__":
    main()
