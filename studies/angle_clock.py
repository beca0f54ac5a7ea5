"""Does a real run's error decorrelate with time, or with the angle turned? (issue 42). Reads a finished
run (``results/<campaign>``) and one model's point estimate, and fits only noise: the REML of
`gyrocal.inference.fit.noisefit` at that estimate, for the white model, for the Gauss-Markov model of
``st_correlated_noise``, and for that model with its clock run on the angle turned as well as on time.

The Gauss-Markov part's factor between two reference samples is ``exp(-dt / tau)``. Here ``dt`` becomes
``dt + kappa * dtheta``, ``dtheta`` the net rotation of the in-loop gyros' attitude between the two samples, as a
campaign that states ``star_tracker: gm_clock_s_per_rad`` has it (`errormodel.gm_clock_steps`), and
``kappa`` (s/rad) tried on a grid: at ``kappa`` 0 it is the time clock; at
large ``kappa`` the error holds while the body rests and changes as it turns, with a correlation angle
``tau / kappa`` (rad). An error of the reference that depends on the pose (an optical tracker's fit of
its markers, seen from other cameras as the body turns) would decorrelate so, and so would one of the
gyro that follows the angle turned. The markov filter takes any steps; the gyro's walk keeps its own,
and the REML's search for tau (half the median step to ten times the longest maneuver) moves with the
clock, which the printout flags where tau ends on a bound. The best ``kappa`` of the grid is one more
fitted number, which the printout's last line says how to state; a campaign.yaml that states
``gm_clock_s_per_rad: auto`` has the preprocessing choose it by the same REML (`gyrocal.inference.clock`).

Prints, per ``kappa``, the negative REML log-likelihood (lower is better; differences are log-likelihood
ratios of models with the same number of scales), the scales (sigma_cross and sigma_about in arcsec, ARW
in deg/sqrt(h), the Gauss-Markov share, tau in effective seconds) and the correlation angle.

    python studies/angle_clock.py results/<campaign> [--model baseline] [--plugins FILE ...] [--kappa 0 1 10 30 100 300]
"""

import argparse
from pathlib import Path

import numpy as np

from gyrocal.inference.clock import angle_steps, correlated_fit, on_angle_clock
from gyrocal.inference.fit import noisefit
from gyrocal.inference.noise import covariance
from gyrocal.pipeline.readback import load_model_run


def tau_bounds_s(lins) -> tuple:
    """The tau the REML searches (`noisefit.estimate_correlated_noise`): half the median step to ten times
    the longest maneuver, in the clock's seconds."""
    step = noisefit.st_step(lins)
    return 0.5 * step, 10.0 * max(float(np.sum(lin.gm_steps)) for lin in lins)


def main():
    """Print the white model's REML, then the correlated model's at each ``kappa``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a run's results/<campaign> folder")
    parser.add_argument("--model", default="baseline")
    parser.add_argument("--plugins", nargs="*", default=[])
    parser.add_argument("--kappa", nargs="*", type=float, default=[0.0, 1.0, 10.0, 30.0, 100.0, 300.0])
    args = parser.parse_args()
    maneuvers, est = load_model_run(args.run, args.model, args.plugins)
    lins = [est.linearize(maneuvers, m) for m in range(len(maneuvers))]
    turned = angle_steps(maneuvers, est)
    log_sigma0 = covariance.log_sigma_of(est.stated_noise)
    white = [covariance.build(lin, est.boresight) for lin in lins]
    white_sigma = noisefit.estimate_noise(white, log_sigma0)[0]
    white_value = noisefit.profile_reml(white, covariance.ratios_of(white_sigma))[0]
    print(f"{args.run} ({args.model}, {sum(len(lin.st_dt) for lin in lins)} reference samples)")
    print(f"  white:            {white_value:10.1f}   scales {np.round(covariance.scales_in_units(white_sigma), 3)}")
    best = (np.inf, 0.0)
    for kappa in args.kappa:
        clocked = on_angle_clock(lins, turned, kappa)
        log_sigma, value = correlated_fit(clocked, est.boresight, log_sigma0)
        best = min(best, (value, kappa))
        scales = covariance.scales_in_units(log_sigma)
        angle = f"{scales[-1] / kappa:.3g} rad" if kappa > 0 else "-"
        low, high = tau_bounds_s(clocked)
        edge = "   (tau at the search's bound)" if not 1.5 * low < scales[-1] < high / 1.5 else ""
        print(f"  kappa {kappa:7.1f} s/rad: {value:10.1f}   scales {np.round(scales, 3)}   correlation angle {angle}{edge}")
    print(f"best of the grid: kappa {best[1]:g} s/rad; to fit it, campaign.yaml's star_tracker states it "
          f"(gm_clock_s_per_rad: {best[1]:g}) and a model adds st_correlated_noise")


if __name__ == "__main__":
    main()
