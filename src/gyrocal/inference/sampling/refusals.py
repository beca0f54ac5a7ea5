"""Refusals before a posterior is sampled: a point estimate whose noise no sensor can have, one
beyond the physical bounds, maneuvers too short for the leave-one-block-out predictive, a
parameter the data do not identify at the fitted noise, or a residual smoother than any noise model
here (`check_representable`); and a sampler stopped by its budget. Each
raises `EstimateError` with the parameter and the maneuver it concerns. A variant whose every added
parameter is prior-only is skipped (`VariantSkipped`): the data cannot tell it from the model
without them.

They are the sampler's preconditions, so they live beside it: the posterior step calls them before
`posterior.prepare` and between it and `posterior.run`, and nothing here calls back up."""

import logging

import numpy as np

from gyrocal.errors import InputError
from gyrocal.inference.fit import identification, noisefit
from gyrocal.inference.fit.estimate import PointEstimate, linearize_all
from gyrocal.inference.fit.likelihood import maneuver_stats
from gyrocal.inference.noise import covariance, parts, smoothness
from gyrocal.inference.noise.covariance import variances
from gyrocal.inference.sampling import predictive
from gyrocal.model import units
from gyrocal.model.kinematics import increment_quantum_rad

__all__ = ["NOISE_PLAUSIBLE", "NOISE_RATIOS", "SHARE_BOUND_MARGIN", "EstimateError", "VariantSkipped",
           "check_blocks", "check_identified", "check_noise", "check_physical", "check_representable",
           "check_variant_informed", "noise_beyond", "sampling_failed", "sampling_stopped", "share_at_bound",
           "taken_by_correlated_part"]

log = logging.getLogger("gyrocal")


class EstimateError(InputError):
    """The point estimate is not physical: the campaign is refused before sampling; the message names
    the parameter and the maneuver. ``advice``: a library effect the message advises adding to the
    model's ``effects`` (the loop fits it where every variant is refused: `gyrocal.pipeline.steps.extend`)."""

    def __init__(self, message: str, *, advice: str = "", effects=(), **where):
        super().__init__(message, **where)
        self.advice = advice
        self.effects = list(effects)


class VariantSkipped(EstimateError):
    """A model variant the data cannot inform beyond the channel model: skipped, not refused."""

    status = "skipped"
    """What the variant's refusal record says (`gyrocal.pipeline.steps.common.variant_step`)."""


def check_variant_informed(spec):
    """Skip a variant whose effects add parameters that are all prior-only (`identification`): its
    posterior would be the channel model's with those parameters' priors beside it, and its
    comparison would measure the priors' volume, not the data."""
    extras = spec.extras
    if not extras or not all(p.prior_only for p in extras):
        return
    listed = "; ".join(f"{p.label} ({p.prior_only})" for p in extras[:3])
    more = f"; and {len(extras) - 3} more" if len(extras) > 3 else ""
    added = sorted({p.effect for p in extras})
    raise VariantSkipped(
        f"model {spec.model} skipped: every parameter its {', '.join(added)} adds is prior-only, so the data "
        f"cannot tell it from the model without it: {listed}{more}. Fly maneuvers that inform it (gyrocal plan "
        f"predicts which), or leave {spec.model} out of run_models")


NOISE_PLAUSIBLE = 1e3
"""A fitted noise scale more than this factor away from the stated one (either way) is not a noise
the sensors can have: the residuals are structure the model lacks."""


def noise_beyond(low, high, band: float):
    """Where a fitted noise scale is a misfit, the one rule of `check_noise` and of the misfit check
    (`gyrocal.criticism.diagnostics.misfit_findings`): ``low`` and ``high`` bound its 95 % interval
    as ratios to the stated scale, and it is off only where that interval excludes the stated value
    (1) and lies wholly outside the tolerated band ``[1 / band, band]``, so that the data, not the
    estimate's noise, say it is off by more than tolerated. An ARW of 0.79 +- 0.08 of the stated
    (interval 0.63 to 0.95) against the band 0.80 to 1.25 is not off: it may be 0.9. Elementwise on arrays."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    excludes_stated = (low > 1.0) | (high < 1.0)
    return excludes_stated & ((low > band) | (high < 1.0 / band))


def check_noise(maneuvers, est: PointEstimate):
    """Stop before sampling when REML puts a noise scale `NOISE_PLAUSIBLE` times off the stated one, taken
    as the stated noise states it (`parts.judged_log_sigma`; `noise_beyond`, its interval the point:
    REML gives none before sampling, and a factor of a thousand is beyond any interval's width); the
    message gives each maneuver's residual RMS about roll, pitch and yaw."""
    judged = parts.judged_log_sigma(est.log_sigma, est.stated_noise)[:3]
    ratio = np.exp(judged - covariance.log_sigma_of(est.stated_noise))
    off = noise_beyond(ratio, ratio, NOISE_PLAUSIBLE)
    if taken_by_correlated_part(est.spec.correlated_noise, ratio, off):
        log.info("point estimate of model %s: REML puts %s far below the stated (ratio %s): beside a Gauss-Markov "
                 "part, whose variance the data do not tell from it, that is no misfit; its prior holds it in the "
                 "posterior", est.spec.model, ", ".join(k for k, bad in zip(covariance.stated_scales(judged), off) if bad),
                 ", ".join(f"{r:.2g}" for r in ratio[off]))
        return
    if off.any():
        _check_resolution(maneuvers, est, off)
        fitted = covariance.stated_scales(judged)
        stated = covariance.stated_scales(covariance.log_sigma_of(est.stated_noise))
        listed = "; ".join(f"{k} {fitted[k]:.3g} (stated {stated[k]:.3g})" for k, bad in zip(fitted, off) if bad)
        lins, _ = linearize_all(maneuvers, est)
        rms = [np.sqrt(np.mean((lin.body_error[:, 0] - lin.body_error[:, 0].mean(axis=0)) ** 2, axis=0))
               / units.ARCSEC_RAD for lin in lins]
        residuals = "; ".join(f"{d.id} {r[0]:.0f}, {r[1]:.0f}, {r[2]:.0f}" for d, r in zip(maneuvers, rms))
        if (ratio < 1.0).all():  # every scale below its stated one: the data are quiet, not misfit
            raise EstimateError(
                f"point estimate of model {est.spec.model}: the data are far quieter than campaign.yaml states: "
                f"{listed}. The residuals (RMS about roll, pitch, yaw, arcsec: {residuals}) are below any noise these "
                "sensors can have: state the noise the sensors have (campaign.yaml: star_tracker and gyro), and for "
                "data simulated without noise, the noise of the data themselves")
        advice, effect = _correlation_advice(maneuvers, lins, est)
        raise EstimateError(
            f"point estimate of model {est.spec.model}: the fitted noise is not a noise these sensors can have: "
            f"{listed}. The residuals hold structure far above the noise that the model lacks (RMS about roll, "
            f"pitch, yaw, arcsec: {residuals}){advice}; validate the campaign (gyrocal "
            "validate) and read its warnings, or add the effect they point to", advice=effect,
            effects=est.spec.effect_names)


def taken_by_correlated_part(correlated: bool, ratio, off) -> bool:
    """Whether the one noise scale REML puts `NOISE_PLAUSIBLE` times off the stated (``off``, the scales'
    ``ratio``s to it: cross, about, walk) is the gyro's walk, below it, in a model with a Gauss-Markov
    part: a walk beside a reference error that forgets slowly, over a radian turned, is one variance the
    data need not tell apart, and REML can give it all to the correlated part. No misfit then, and no
    sensor that cannot be: the walk's prior holds it in the posterior. Any other scale off, a white
    model's collapse (correlated residuals) and every scale below (a campaign stated far noisier than
    its data) still stop."""
    ratio, off = np.asarray(ratio, dtype=float), np.asarray(off, dtype=bool)
    return bool(correlated and off.tolist() == [False, False, True] and ratio[2] < 1.0)


def _check_resolution(maneuvers, est: PointEstimate, off):
    """Refuse naming the cause where a stated star-tracker noise lies below the gyros' own resolution: a
    pulse-counting gyro's rounding (`kinematics.increment_quantum_rad`) adds white error the fit then gives the
    reference, and every off scale is within `NOISE_PLAUSIBLE` of the stated noise and that rounding added."""
    quantum = max(increment_quantum_rad(d.increments) for d in maneuvers)
    rounding = quantum / np.sqrt(12.0)
    stated = np.exp(covariance.log_sigma_of(est.stated_noise))[:2]
    if rounding <= 0 or not off[:2].any() or off[2] or not (stated < rounding).any():
        return
    floor = np.hypot(stated, rounding)
    if np.all(np.exp(est.log_sigma[:2]) <= NOISE_PLAUSIBLE * floor):
        fitted = covariance.stated_scales(est.log_sigma[:3])
        raise EstimateError(
            f"point estimate of model {est.spec.model}: the star tracker's stated noise "
            f"({', '.join(f'{k} {v:.3g}' for k, v in est.stated_noise.items() if k.startswith('sigma_'))}) lies below the "
            f"gyros' own resolution: their increments in gyro.csv come in steps of {quantum / units.ARCSEC_RAD:.3g} arcsec, "
            f"whose rounding adds {rounding / units.ARCSEC_RAD:.3g} arcsec to every attitude error, and the fit gives the "
            f"reference {fitted['sigma_cross_arcsec']:.3g} (across) and {fitted['sigma_about_arcsec']:.3g} (about). State "
            f"the star tracker's noise in campaign.yaml at no less than {rounding / units.ARCSEC_RAD:.3g} arcsec "
            "(star_tracker: sigma_cross_arcsec, sigma_about_arcsec)")


def _correlation_advice(maneuvers, lins, est: PointEstimate) -> tuple:
    """Where the residuals' differences are correlated in time and the model's reference noise is
    white, say so: a reference sampled faster than its noise is white (a star tracker's slow
    errors, motion capture at 100 Hz) collapses a white-noise fit. Returns the words and the effect
    they advise adding (``st_correlated_noise``, or "")."""
    if est.spec.correlated_noise:
        return "", ""
    smooth = smoothness.describe(smoothness.of_estimate(maneuvers, est, lins))
    if smooth:
        return f". And {smooth}", ""
    tau = noisefit.correlation_time(lins)
    if tau <= 0:
        return "", ""
    return (f". They are correlated in time (correlation time about {tau:.3g} s from their differences): add "
            "st_correlated_noise to the model (white plus Gauss-Markov reference noise), or import the reference at "
            "an interval longer than that (gyrocal import --reference-interval)", "st_correlated_noise")


def check_representable(maneuvers, est: PointEstimate):
    """Stop before sampling where the Gauss-Markov share is fitted at its upper bound and the residual is
    smooth at the sampling interval (`smoothness`): no noise model here represents it, and the posterior
    lies beyond the share's bound, where the sampler's chains drift (RepoIMU at 100 Hz: stopped
    unconverged after 750-800 steps, a minute per model)."""
    share = covariance.position(est.log_sigma, covariance.GM_FRACTION_SCALE)
    if share is None or est.log_sigma[share] < noisefit.GM_LOGIT_BOUND - SHARE_BOUND_MARGIN:
        return
    measured = smoothness.of_estimate(maneuvers, est, [est.linearize(maneuvers, m) for m in range(len(maneuvers))])
    if smoothness.describe(measured):
        raise EstimateError(f"point estimate of model {est.spec.model}: {share_at_bound(est.log_sigma, measured)}. "
                            "Its posterior would lie beyond the share's bound, where the sampler cannot converge")


def check_physical(maneuvers, est: PointEstimate, bound_si):
    """Stop before sampling when the WLS puts a parameter beyond its physical bound by more than
    `identification.DETECTION_SD` of its own standard error: the data then say it is out (a
    unit slip, a gap, a wrong label), not the confounding of two parameters that only the prior
    holds apart. Names the parameter and the maneuver the model fits worst."""
    sd = np.sqrt(np.diag(est.cov))
    beyond = est.spec.free & (np.abs(est.theta) - bound_si > identification.DETECTION_SD * sd)
    if not beyond.any():
        return
    _, noises = linearize_all(maneuvers, est)
    stats = [maneuver_stats(nz, variances(est.log_sigma)) for nz in noises]
    misfit = np.array([s.c / s.n for s in stats])
    worst = int(np.argmax(misfit))
    spec = est.spec
    values = spec.to_unit(est.theta)
    listed = "; ".join(f"{spec.labels[i]} = {values[i]:.6g} {spec.units[i]} (bound {spec.to_unit(bound_si)[i]:g}, "
                       f"WLS sd {sd[i] / spec.si_per_unit[i]:.3g})" for i in np.flatnonzero(beyond))
    raise EstimateError(
        f"point estimate of model {spec.model}: beyond the physical bounds, so sampling would not start: {listed}. "
        f"The model fits maneuver {maneuvers[worst].id} worst (weighted residual {misfit[worst]:.3g} per sample, "
        f"1 expected): check its data and labels (gyrocal validate) and the noise knowledge")


def check_blocks(maneuvers, block_s: float):
    """Stop before sampling when a maneuver is too short for the leave-one-block-out predictive even
    with its blocks shortened (`predictive.maneuver_block_s`): each block is predicted from the rest of
    its maneuver alone, which must then keep `predictive.MIN_REST_SAMPLES` (a single block would leave
    nothing, and the factorisation would fail)."""
    short = [f"{d.id} spans {d.st_time[-1] - d.st_time[0]:.0f} s ({len(d.st_time)} samples)"
             for d in maneuvers if predictive.maneuver_block_s(d.st_time, block_s) is None]
    if short:
        raise EstimateError(
            f"too short for the leave-one-block-out predictive (blocks of sampler.block_s = {block_s:g} s, halved "
            f"down to two samples, each predicted from the rest of its maneuver, which needs at least "
            f"{predictive.MIN_REST_SAMPLES} star-tracker samples): {'; '.join(short)}. Lengthen the maneuver")


SHARE_BOUND_MARGIN = 0.05
"""A fitted ``logit st_gm_fraction`` this close to its bound is at it (`share_at_bound`)."""

NOISE_RATIOS = {"sigma_about_arcsec": "log(sigma_about / sigma_cross)", "arw_deg_sqrt_h": "log(arw / sigma_cross)",
                "st_gm_fraction": "logit st_gm_fraction", "st_gm_tau_s": "log st_gm_tau_s",
                "st_jitter_ms": "log(st_jitter / sigma_cross)"}
"""The noise ratios the posterior's grid spans (`noisegrid.RatioGrid`, `covariance.ratios_of`) in words,
by the key of their scale: two, two more with correlated star-tracker noise, one with the timing jitter."""


def check_identified(est: PointEstimate, priors, stats, ratio_sd) -> str:
    """Before sampling, at the fitted noise (``stats``: the data's information, the nuisance integrated
    out): refuse when a parameter the point estimate kept free carries less than
    `identification.INFORMATION_RATIO_MIN` of its prior's information, the others estimated with it
    (it was judged at the stated noise; a fitted noise far above it leaves less), naming it and what to
    fly. Otherwise return what is weakest, in words, for a sampler that does not converge: the least
    informed parameters, directions only the prior holds, noise ratios the data do not tell, a
    Gauss-Markov share at its bound (over a smooth residual `check_representable` refused it first). A
    noise ratio is not told where its sd (``ratio_sd``) is half its prior's (`Priors.ratio_sd`) or more."""
    spec, prior_sd = est.spec, priors.sd
    index = np.flatnonzero(spec.free)
    joint = identification.joint_information(stats.A[np.ix_(index, index)], np.asarray(prior_sd)[index])
    weak = joint < identification.INFORMATION_RATIO_MIN
    if weak.any():
        listed = "; ".join(f"{spec.labels[i]} ({r:.2g} of its prior's information: "
                           f"{identification.maneuver_to_fly(spec, i)})" for i, r in zip(index[weak], joint[weak]))
        raise EstimateError(
            f"point estimate of model {spec.model}: at the fitted noise ({_noise_words(est)}) the data do not "
            f"identify {listed}. Its posterior would be its prior, and the sampler would wander along it. "
            "Fly what is named, or state the noise as fitted (campaign.yaml) so that the point estimate marks "
            "it prior-only")
    order = [k for k in np.argsort(joint)[:3] if joint[k] < 1.0]
    notes = ["weakly informed (the data carry less than the prior): " + ", ".join(
        f"{spec.labels[index[k]]} ({joint[k]:.2g} of its prior's information; "
        f"{identification.maneuver_to_fly(spec, index[k])})" for k in order)] if order else []
    held = identification.prior_held_directions(stats.A[np.ix_(index, index)], np.asarray(prior_sd)[index],
                                                [spec.labels[i] for i in index])
    notes += [f"a direction only the prior holds ({value:.2g} of its information): "
              + " ".join(f"{w:+.2f} {label}" for label, w in loads) for value, loads in held]
    scales = covariance.scales_of(est.log_sigma)
    flat = [NOISE_RATIOS[scale.key] for scale, sd, prior in zip(scales[1:], ratio_sd, priors.ratio_sd(scales))
            if sd >= 0.5 * prior]
    if flat:
        notes.append(f"the data hardly tell the noise ratio(s) {', '.join(flat)} (their profile is as wide as "
                     "the prior): a longer maneuver, or holds, separate the gyro walk from the reference noise")
    notes += [note] if (note := share_at_bound(est.log_sigma)) else []
    return "; ".join(notes)


def share_at_bound(log_sigma, measured=()) -> str:
    """What a Gauss-Markov share fitted at its bound (`noisefit.GM_LOGIT_BOUND`) says of the reference's
    noise, in words; "" where it is inside, or the noise white. At the upper bound the posterior lies
    beyond the grid, where the sampler cannot follow it; where the residual is smooth (``measured``:
    `smoothness.of_maneuver` of each maneuver) that is why, and the reference interval to use follows."""
    k = covariance.position(log_sigma, covariance.GM_FRACTION_SCALE)
    if k is None or abs(log_sigma[k]) < noisefit.GM_LOGIT_BOUND - SHARE_BOUND_MARGIN:
        return ""
    stated = covariance.stated_scales(log_sigma)
    share = stated["st_gm_fraction"]
    if log_sigma[k] < 0:
        return (f"the reference's noise fits as white (Gauss-Markov share {share:.2g}, at its bound): the model "
                "without st_correlated_noise holds it")
    head = (f"the reference's noise fits as all Gauss-Markov (share {share:.4g}, at its bound, tau "
            f"{stated['st_gm_tau_s']:.3g} s): it has no white part at this sampling")
    if words := smoothness.describe(measured):
        return f"{head}, and {words}"
    return (f"{head}, and one Gauss-Markov part may be standing in for errors on two time scales; import the "
            "reference every few correlation times (gyrocal import --reference-interval; on a clock of the angle "
            "turned, tau is in that clock's seconds), where its fast error is white")


def sampling_stopped(stopped, est: PointEstimate, notes: str, labels) -> EstimateError:
    """The refusal of a sampler stopped by its budget (`budget.SamplingStopped`): its reason, the slowest
    parameters (``labels``: the sampled ones, in order) and what `check_identified` found weakest."""
    worst = np.nanmax(stopped.tau, axis=0)
    name = lambda k: labels[k] if k < len(labels) else f"noise hyperparameter {k - len(labels) + 1}"
    slow = ", ".join(f"{name(k)} ({worst[k]:.1f} steps)" for k in np.argsort(-np.nan_to_num(worst))[:3])
    return EstimateError(
        f"posterior of model {est.spec.model} stopped without converging: {stopped.reason}. Slowest: {slow}. "
        f"What the data leave weak: {notes or 'nothing stands out'}. Fly what is named, or leave this model out")


def sampling_failed(failed, maneuvers, est: PointEstimate) -> EstimateError:
    """The refusal of a posterior that cannot be sampled from its point estimate (`proposal.SamplingError`:
    no start point on the noise-ratio grid, or no node of it whose covariance can be factored), with the
    Gauss-Markov correlation time against the maneuvers' length where the model has one: far beyond
    them, its filtered covariance is not positive definite in floating point (`markov`)."""
    advice = "Leave this model out, or fly what makes its noise identifiable"
    if est.spec.correlated_noise:  # the maneuvers' length on the part's clock (time, or time and the angle turned)
        longest = max(float(np.sum(est.linearize(maneuvers, m).gm_steps[1:])) for m in range(len(maneuvers)))
        advice = (f"Its star-tracker Gauss-Markov correlation time is {est.correlation_time_s:.4g} s, "
                  f"{est.correlation_time_s / longest:.3g} times the longest maneuver ({longest:.4g} s): a part that "
                  "slow is an offset and a walk to these data, which the model's bias and the gyro's walk already "
                  "hold. Leave st_correlated_noise out of this model, or fly maneuvers several correlation times long")
    return EstimateError(f"posterior of model {est.spec.model} cannot be sampled: {failed}. {advice}")


def _noise_words(est: PointEstimate) -> str:
    fitted = covariance.stated_scales(est.log_sigma)
    return ", ".join(f"{k} {v:.3g}" for k, v in fitted.items())
