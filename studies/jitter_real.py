"""The timing jitter (`st_jitter`) on a real campaign, in one process (issue 42 item 2): for a campaign the
pipeline refuses (BROAD's free motion), what the workflow's point estimate and diagnostics would say.

For each model (the baseline, plus `st_latency`, each with and without `st_jitter`): the REML noise scales
(the stated noise as the start and the prior's centre: config's ``noise``, ``--arw``), the residual RMS of
the first channel set against what the stated noise predicts (`diagnostics.noise_rms_arcsec`), the
innovations' whiteness (lag-1 z) and their rate growth (`rategrowth`), and the REML's restricted
log-likelihood at the fitted noise (its gain from the jitter is a likelihood ratio on one degree of freedom).
The campaign is read as `studies/real_residual_vs_rate.py` reads it (labelled, aligned, unscreened where
the checks refuse it).

    python studies/jitter_real.py CAMPAIGN [--config config/tstick.yaml] [--arw 0.31]
"""

import importlib.util
from pathlib import Path

import numpy as np

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit import classic, noisefit
from gyrocal.inference.fit.estimate import linearize_all, point_estimate
from gyrocal.inference.noise.covariance import ratios_of, stated_scales
from gyrocal.maneuvers import preprocess
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD

_spec = importlib.util.spec_from_file_location("jitter_axis", Path(__file__).with_name("jitter_axis.py"))
jitter_axis = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(jitter_axis)

MODELS = {"baseline": [], "jitter": ["st_jitter"], "latency": ["st_latency"], "latency_jitter": ["st_latency", "st_jitter"]}


def main(argv=None):
    args = jitter_axis.campaign_parser(__doc__.splitlines()[0]).parse_args(argv)
    maneuvers, note, stated = jitter_axis.stated_campaign(args)
    index = preprocess.noise_groups(maneuvers)[1]
    groups = index if np.max(index) > 0 else None
    predicted = diagnostics.noise_rms_arcsec(maneuvers, stated)
    print(f"campaign {args.campaign}: {note}; the stated noise predicts a residual RMS of {predicted:.0f} arcsec")
    print("| model | REML noise | residual RMS, arcsec | / stated prediction | whiteness z | rate growth log10 p "
          "| restricted log-lik |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, extra in MODELS.items():
        names = list(effects.BASELINE) + extra
        spec = ModelSpec.build(name, effects.resolve(name, names, {}), maneuvers[0].channels)
        est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
        lins, noises = linearize_all(maneuvers, est)
        white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
        negative = noisefit.profile_reml(noises, ratios_of(est.log_sigma), groups)[0]
        resid = np.concatenate([lin.body_error[:, 0, :] for lin in lins])
        rms = float(np.sqrt(np.mean(resid**2))) / ARCSEC_RAD
        scales = ", ".join(f"{k.split('_')[0] if k != 'st_jitter_ms' else 'jitter'} {v:.3g}"
                           for k, v in stated_scales(est.log_sigma).items())
        latency = f"; latency {1e3 * est.theta[spec.labels.index('st_latency.latency')]:.2f} ms" \
            if "st_latency.latency" in spec.labels else ""
        print(f"| {name} | {scales}{latency} | {rms:.0f} | {rms / predicted:.2f} | {white['z']:+.1f} | "
              f"{white['rate_growth']['log10_p']:.1f} | {-negative:.1f} |", flush=True)


if __name__ == "__main__":
    main()
