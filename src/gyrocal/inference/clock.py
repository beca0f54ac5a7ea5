"""The reference error's clock chosen from the data (campaign.yaml's ``star_tracker: gm_clock_s_per_rad:
auto``): on the pilot fit's residual, the REML of `st_correlated_noise` with its Gauss-Markov part on
each clock of a grid, time alone (0) and time plus K seconds a radian turned.

An error of the reference that follows its pose, as an optical tracker's fit of its markers does (seen by
other cameras as the body turns), forgets with the angle turned rather than with time; an error of the
tracker's electronics forgets with time. Which it is, and on what scale, is a property of the reference
that no at-rest recording shows (at rest the pose does not change), so the data choose: the clock is one
more fitted number, taken on the angle only where it gains `GAIN_MIN` log-likelihood units over the time
clock (a likelihood-ratio test of one degree of freedom at p = 0.001), and then the smallest K within
`TIE` unit of the grid's best (above a few thousand s/rad the likelihood is flat: the error's correlation
angle, tau / K, is what the data fix). The pilot (`gyrocal.inference.fit.pilot`) is the same for every
model variant of a run, so the variants are compared on one clock. Each maneuver's error is taken apart
from the others' here (no chaining across gaps), each noise group at its own level.
"""

from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import chi2

from gyrocal.inference import errormodel
from gyrocal.inference.fit import noisefit
from gyrocal.inference.fit.pilot import pilot
from gyrocal.inference.noise import covariance
from gyrocal.io.campaign_yaml import GM_CLOCK_AUTO, GM_CLOCK_KEY
from gyrocal.maneuvers.preprocess import noise_groups

__all__ = ["GAIN_MIN", "GRID_S_PER_RAD", "TIE", "ClockChoice", "angle_steps", "choose", "chosen",
           "correlated_fit", "fitted_grid", "likelihood_ratio", "on_angle_clock", "with_clock"]

GRID_S_PER_RAD = (0.0, 100.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0)
"""The clocks tried (s a radian turned, beside time): from a radian's turn worth 100 s (an error that
forgets over a minute at rest as much as over a radian turned) to one worth 8 hours."""

GAIN_MIN = float(chi2.isf(1e-3, 1) / 2)
"""The REML gain (log-likelihood units) an angle clock needs over the time clock to be taken: 5.4, a
likelihood-ratio test of one more number at p = 0.001."""

TIE = 1.0
"""Clocks within this many log-likelihood units of the grid's best are as good; the smallest is taken."""


@dataclass(frozen=True)
class ClockChoice:
    """The clock the data named, with the REML of every clock tried."""

    clock_s_per_rad: float
    """Seconds a radian turned (0: time alone)."""
    grid: list
    """Per clock tried: ``clock_s_per_rad``, ``neg_log_lik`` (the REML's, lower is better; None where its fit
    failed, with its ``error``), ``gain_over_time``, the Gauss-Markov part's ``tau_s`` (clock seconds),
    ``st_gm_fraction`` and ``correlation_angle_rad`` (tau / K; None on the time clock)."""
    failed: str = ""
    """Why no clock was tried (the pilot fit failed); empty where the grid was fitted."""

    @property
    def best(self) -> dict:
        return min((r for r in self.grid if r["neg_log_lik"] is not None), key=lambda row: row["neg_log_lik"])

    @property
    def reason(self) -> str:
        """The choice in words, for the log and the review. The clock is chosen on the baseline channel
        model's residual, so a deterministic effect that model lacks can move it too."""
        if self.failed:
            return f"the time clock: {self.failed}"
        if self.grid[0]["neg_log_lik"] is None:
            return f"the time clock: the correlated model's fit on it failed ({self.grid[0].get('error', '')})"
        best = self.best
        if not self.clock_s_per_rad:
            return (f"the time clock: no clock on the angle turned ({GRID_S_PER_RAD[1]:g} to {GRID_S_PER_RAD[-1]:g} s a "
                    f"radian) gains {GAIN_MIN:.1f} log-likelihood units over it on the pilot fit's residual (the best, "
                    f"{best['clock_s_per_rad']:g} s/rad, gains {best['gain_over_time']:.1f})")
        row = next(r for r in self.grid if r["clock_s_per_rad"] == self.clock_s_per_rad)
        return (f"{self.clock_s_per_rad:g} s a radian turned: on the pilot fit's residual (the baseline channel "
                f"model) the reference error's Gauss-Markov part fits the grid's best clock, "
                f"{best['clock_s_per_rad']:g} s/rad, {best['gain_over_time']:.1f} log-likelihood units better than time "
                f"(taken above {GAIN_MIN:.1f}); this one, the smallest within {TIE:g} unit of it, gains "
                f"{row['gain_over_time']:.1f}, with a correlation angle of {row['correlation_angle_rad']:.3g} rad")

    def record(self) -> dict:
        """``preprocess/gm_clock.json``."""
        return {"requested": GM_CLOCK_AUTO, "clock_s_per_rad": self.clock_s_per_rad, "reason": self.reason,
                "gain_min": GAIN_MIN, "grid": self.grid}


def _group_index(maneuvers):
    """Each maneuver's noise group (`noise_groups`), or None where the campaign has one: as the REML takes them."""
    names, index = noise_groups(maneuvers)
    return index if len(names) > 1 else None


def with_clock(stated_noise: dict, maneuvers) -> dict:
    """The noise knowledge with the clock the maneuvers carry (the one stated, or the one chosen where
    campaign.yaml asks for ``auto``), as the fits and the priors read it (`covariance.gm_tau_prior_s`)."""
    out = {k: v for k, v in stated_noise.items() if k != GM_CLOCK_KEY}
    clock = maneuvers[0].gm_clock_s_per_rad if maneuvers else 0.0
    return {**out, GM_CLOCK_KEY: clock} if clock > 0 else out


def angle_steps(maneuvers, est) -> list:
    """(M,) per maneuver the net angle the body turns between reference samples (rad): the linearisation's
    clock at 1 s/rad, less its time (`errormodel.gm_clock_steps`)."""
    once = [replace(d, gm_clock_s_per_rad=1.0) for d in maneuvers]
    return [lin.gm_dt - lin.st_dt for lin in (est.linearize(once, m) for m in range(len(once)))]


def on_angle_clock(lins, turned, clock_s_per_rad: float) -> list:
    """The linearisations with the Gauss-Markov part's clock steps ``dt + K dtheta``, as a campaign that
    states ``star_tracker: gm_clock_s_per_rad: K`` has them; the gyro's walk keeps its steps."""
    return [replace(lin, gm_dt=lin.st_dt + clock_s_per_rad * step if clock_s_per_rad > 0 else None)
            for lin, step in zip(lins, turned)]


def correlated_fit(lins, boresight, log_sigma0, groups=None) -> tuple:
    """`st_correlated_noise`'s REML scales at the linearisations, each maneuver apart, and its negative
    log-likelihood there (``groups``: each maneuver's noise group, None for one; with the timing jitter
    where ``log_sigma0`` holds its scale)."""
    jitter = covariance.position(log_sigma0, covariance.JITTER_SCALE) is not None
    log_sigma = noisefit.estimate_correlated_noise(lins, boresight, log_sigma0, noisefit.tau_start_s(lins), groups)[0]
    ratios = covariance.ratios_of(log_sigma)
    noises = [covariance.build(lin, boresight, covariance.correlation_time_of(ratios), jitter) for lin in lins]
    return log_sigma, float(noisefit.profile_reml(noises, ratios, groups)[0])


def fitted_grid(lins, turned, boresight, log_sigma0, grid=GRID_S_PER_RAD, groups=None) -> list:
    """`ClockChoice.grid`: the correlated REML on each clock of ``grid`` (its first the time clock, 0); a
    clock whose fit fails or is not finite has ``neg_log_lik`` None and its ``error``."""
    rows = []
    for clock in grid:
        try:
            log_sigma, value = correlated_fit(on_angle_clock(lins, turned, clock), boresight, log_sigma0, groups)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
            rows.append({"clock_s_per_rad": float(clock), "neg_log_lik": None, "error": str(exc)})
            continue
        scales = covariance.stated_scales(log_sigma)
        tau = scales[covariance.GM_TAU_SCALE.key]
        finite = bool(np.isfinite(value))
        rows.append({"clock_s_per_rad": float(clock), "neg_log_lik": value if finite else None,
                     "gain_over_time": None, "tau_s": tau, "st_gm_fraction": scales[covariance.GM_FRACTION_SCALE.key],
                     "correlation_angle_rad": tau / clock if clock > 0 else None,
                     **({} if finite else {"error": "the REML is not finite"})})
    time = rows[0]["neg_log_lik"]
    for row in rows:
        if row["neg_log_lik"] is not None and time is not None:
            row["gain_over_time"] = time - row["neg_log_lik"]
    return rows


def likelihood_ratio(maneuvers, estimate, added=()) -> dict:
    """How strongly a white model's residual calls for `st_correlated_noise` on the clock its maneuvers carry
    (K > 0): twice the REML gain of the correlated model on that clock over the white one, both fitted at the
    model's linearisation (its channel parameters, ``added`` effects' columns and the nuisance integrated
    out; its timing jitter in both where it has one), each maneuver apart. The ranking's spectral test
    (`gyrocal.criticism.correlation`) presumes a noise model on time; this one is on the clock, and given a
    deterministic candidate's columns (``added``) it says whether that candidate explains the correlation.
    ``chi2`` (on the share and tau), the share, tau (clock seconds) and the clock."""
    spec = estimate.spec.augmented(list(added)) if added else estimate.spec
    theta = np.concatenate([estimate.theta, np.zeros(len(spec) - len(estimate.spec))])
    lins = [errormodel.linearize(d, spec, theta, estimate.biases[m]) if added else estimate.linearize(maneuvers, m)
            for m, d in enumerate(maneuvers)]
    groups = _group_index(maneuvers)
    jitter = estimate.spec.jitter_noise
    start = covariance.log_sigma_of(estimate.stated_noise, jitter)
    white = [covariance.build(lin, estimate.boresight, 0.0, jitter) for lin in lins]
    white_sigma = noisefit.estimate_noise(white, start, groups)[0]
    white_value = float(noisefit.profile_reml(white, covariance.ratios_of(white_sigma), groups)[0])
    log_sigma, value = correlated_fit(lins, estimate.boresight, start, groups)
    scales = covariance.stated_scales(log_sigma)
    chi2 = 2.0 * (white_value - value)
    return {"chi2": max(chi2, 0.0) if np.isfinite(chi2) else 0.0, "share": scales[covariance.GM_FRACTION_SCALE.key],
            "tau_s": scales[covariance.GM_TAU_SCALE.key], "clock_s_per_rad": maneuvers[0].gm_clock_s_per_rad}


def chosen(grid) -> float:
    """The clock the rule above takes from `fitted_grid`'s rows: time where the time clock's fit or every
    angle clock's failed."""
    fitted = [row for row in grid if row["neg_log_lik"] is not None]
    if grid[0]["neg_log_lik"] is None or len(fitted) < 2:
        return 0.0
    best = min(row["neg_log_lik"] for row in fitted)
    if grid[0]["neg_log_lik"] - best < GAIN_MIN:
        return 0.0
    return min(row["clock_s_per_rad"] for row in fitted[1:] if row["neg_log_lik"] - best <= TIE)


def choose(maneuvers, stated_noise: dict, sensor_class=None, grid=GRID_S_PER_RAD) -> ClockChoice:
    """The clock of the reference error's Gauss-Markov part the data prefer (`chosen`), on the pilot fit; the
    time clock, with why, where the pilot cannot be fitted."""
    try:
        est, lins = pilot(maneuvers, stated_noise, sensor_class)
    except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
        return ClockChoice(0.0, [], failed=f"the pilot fit failed ({exc})")
    rows = fitted_grid(lins, angle_steps(maneuvers, est), est.boresight, covariance.log_sigma_of(stated_noise), grid,
                       _group_index(maneuvers))
    return ClockChoice(chosen(rows), rows)
