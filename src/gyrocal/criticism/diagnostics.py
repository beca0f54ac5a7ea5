"""Model criticism: is the fit consistent with the noise model, and if not, what is missing?

Three checks of the residuals against the noise model (their level, their whiteness,
their structure) and a ranking of what could explain a misfit: each library effect the
model lacks and each residual signature (docs/interface.md section 5), scored by a
Lagrange-multiplier (score) test at the fitted model, which needs no refit: the drop in
the weighted residual sum of squares that adding its columns would buy, with the
model's own parameters and the nuisance re-fitted. Its ``score`` is one minus the
test's p-value: near 1 for structure the noise cannot explain.
"""

import numpy as np
import pandas as pd
from scipy.special import chdtr, chdtrc, gammaln

from gyrocal.criticism import correlation, noiseranking, rategrowth
from gyrocal.criticism.bands import band_findings
from gyrocal.criticism.increments import smoothness_finding
from gyrocal.finding import Finding
from gyrocal.inference import clock, errormodel
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.fit.likelihood import campaign_stats, maneuver_stats, total
from gyrocal.inference.noise import covariance, parts, smoothness
from gyrocal.inference.noise.covariance import NOISE_SCALES, noise_scales, ratios_of, variances
from gyrocal.inference.sampling.predictive import WhitenedManeuver
from gyrocal.inference.sampling.refusals import noise_beyond
from gyrocal.maneuvers.preprocess import noise_groups
from gyrocal.model import effects
from gyrocal.model.units import ARCSEC_RAD, AXES, rad_to_arcsec

__all__ = [
    "COLLINEAR_FRACTION",
    "ENCOMPASS_TOP",
    "Signature",
    "chi2_log_sf",
    "conditional_drop",
    "diagnose",
    "judged_key",
    "linearized",
    "misfit_checks",
    "misfit_findings",
    "motion_part_arcsec",
    "noise_rms_arcsec",
    "rank",
    "signature_effects",
    "whiteness"
]


class Signature(effects.Effect):
    """A residual signature as a per-channel regressor of the channel increments."""

    def __init__(self, name, regressor, description, columns=("k",)):
        self.name = name
        self.description = description
        self.parameters = tuple(effects.Parameter(c, "-", 1.0, 1.0) for c in columns)
        self._regressor = regressor

    def gyro(self, m):
        return self._regressor(m)


def _own(m, values):
    """(K, n_channels) of a body-axis quantity on each channel's own axis."""
    return values[:, [c.axis_index for c in m.channels]]


def signature_effects(extra_columns) -> list:
    """The signatures of docs/interface.md section 5, plus one per extra ``gyro.csv`` column.

    ``time`` and ``rate_squared`` are the columns of the library's ``bias_drift`` and
    ``sf_nonlinearity``: they are ranked once, under the effect (see `rank`).
    """
    def cross(m):
        rate = m.body_rate
        own = _own(m, rate)
        return {"k": own * (rate.sum(axis=1, keepdims=True) - own) * m.dt[:, None]}

    out = [
        Signature("rate", lambda m: {"k": m.increments}, "an error proportional to the rate"),
        Signature("rate_sign", lambda m: {"k": np.sign(m.rate) * m.moving * m.dt[:, None]},
                  "a bias that flips with the direction of rotation"),
        Signature("cross_rate", cross, "own rate times the other axes' rates (anisoinertia)"),
        Signature("acceleration", lambda m: {"k": _own(m, m.acceleration) * m.dt[:, None]},
                  "the angular acceleration: a timing offset between gyros and star tracker"),
    ]
    for column in extra_columns:
        def regress(m, column=column):
            x = m.extras[column] - np.mean(m.extras[column])
            return {"scale": x[:, None] * m.increments, "bias": m.bias_regressor(x)}
        out.append(Signature(column, regress, f"a scale factor or bias that follows {column}", ("scale", "bias")))
    return out


def _applies(effect, data) -> bool:
    """Whether an effect can be evaluated on this campaign (a plugin may need columns it lacks)."""
    try:
        errormodel.effect_derivatives(effect, errormodel.view(data))
        return True
    except ValueError:
        return False


def _augmented(maneuvers, estimate: PointEstimate, candidates, var):
    """Sufficient statistics of the fitted model's parameters followed by the candidate
    effects' columns, all global, with each maneuver's nuisance integrated out."""
    spec = estimate.spec.augmented(candidates)
    theta = np.concatenate([estimate.theta, np.zeros(len(spec) - len(estimate.spec))])
    noises = (covariance.build(errormodel.linearize(data, spec, theta, estimate.biases[m]), estimate.boresight,
                          estimate.correlation_time_s, estimate.spec.jitter_noise) for m, data in enumerate(maneuvers))
    if estimate.group_offsets is None:
        return spec, campaign_stats(noises, var)  # one maneuver's noise at a time: summed, then freed
    index = noise_groups(maneuvers)[1]
    return spec, total([maneuver_stats(nz, estimate.maneuver_variances(m, index[m])) for m, nz in enumerate(noises)])


COLLINEAR_FRACTION = 1e-3
"""A candidate direction whose weighted variance is more than 99.9 % explained by the
model's own columns is not tested: there the statistic would measure second-order model
error amplified a thousandfold, not structure."""


def conditional_drop(stats, base, cand) -> float:
    """Drop in the weighted residual sum of squares from adding columns ``cand`` to the
    columns ``base`` (Schur complement), in directions ``base`` does not already span."""
    base, cand = np.asarray(base, dtype=int), np.asarray(cand, dtype=int)
    A_mm = stats.A[np.ix_(base, base)]
    A_cm = stats.A[np.ix_(cand, base)]
    solve = np.linalg.lstsq(A_mm, np.column_stack([A_cm.T, stats.b[base]]), rcond=1e-12)[0]
    S = stats.A[np.ix_(cand, cand)] - A_cm @ solve[:, :-1]
    r = stats.b[cand] - A_cm @ solve[:, -1]
    scale = np.sqrt(np.maximum(np.diag(stats.A)[cand], 1e-300))
    values, vectors = np.linalg.eigh(S / np.outer(scale, scale))
    keep = values > COLLINEAR_FRACTION
    projected = vectors[:, keep].T @ (r / scale)
    return float(np.sum(projected**2 / values[keep]))


def _chi2_drop(stats, n_model, idx) -> float:
    """Score statistic of candidate columns ``idx`` given the model's own parameters."""
    return conditional_drop(stats, np.arange(n_model), n_model + np.asarray(idx))


ENCOMPASS_TOP = 5


def _encompass(ranking, groups, stats, n_model):
    """Reorder the leading significant candidates by what each leaves unexplained.

    Two candidates can both explain much of a misfit (a rate-squared scale factor and a
    bias that flips with the rotation). The better explanation is the one after whose
    addition the others explain least: for each leader, the most significant of the
    other leaders given it (``leftover_log10_p``), highest first. Leaders that each leave nothing
    significant (leftover above `noiseranking.LEFTOVER_LOG10_P`) explain each other equally well
    and keep their own order, the most significant first: a 50 ms latency and the acceleration
    signature, both explaining it, differ in leftover only by noise (-0.13 against -0.12), and the
    latency, one parameter, is the more significant (log10 p -1049 against -1040 on six).
    """
    columns = {effect.name: idx for _, effect, idx in groups}
    leaders = [r for r in ranking[:ENCOMPASS_TOP] if r["log10_p"] < -2 and r["name"] in columns]
    if len(leaders) < 2:
        return
    for r in leaders:
        base = list(range(n_model)) + [n_model + i for i in columns[r["name"]]]
        worst = 0.0
        for other in leaders:
            if other is r:
                continue
            drop = conditional_drop(stats, base, [n_model + i for i in columns[other["name"]]])
            worst = min(worst, chi2_log_sf(drop, len(columns[other["name"]])) / np.log(10))
        r["leftover_log10_p"] = round(worst, 2)
    positions = sorted(ranking.index(r) for r in leaders)
    def left_unexplained(r):
        """The leftover's significance beyond the threshold; nothing significant left counts alike (zero)."""
        return min(0.0, r["leftover_log10_p"] - noiseranking.LEFTOVER_LOG10_P)

    for position, r in zip(positions, sorted(leaders, key=lambda r: (-left_unexplained(r), r["log10_p"]))):
        ranking[position] = r


def chi2_log_sf(x: float, df: int) -> float:
    """``log P(chi2_df > x)``, finite however large x: scipy's where it does not underflow
    (x up to about 1400), else the asymptotic series of the upper incomplete gamma function,
    ``Q(a, z) ~ z^(a-1) e^-z / Gamma(a) (1 + (a-1)/z + (a-1)(a-2)/z^2 + ...)``, a = df/2, z = x/2.
    scipy's part is `scipy.stats.chi2.logsf` from `scipy.special` (through ``log1p(-cdf)`` where
    the tail is above one half), without importing scipy.stats: 0.5 s of the diagnostics step's
    start-up."""
    if x <= 0:
        return 0.0
    sf = chdtrc(df, x)
    with np.errstate(divide="ignore"):
        value = float(np.log1p(-chdtr(df, x)) if sf > 0.5 else np.log(sf))
    if np.isfinite(value):
        return value
    a, z = df / 2.0, x / 2.0
    terms = np.cumprod([(a - k) / z for k in range(1, 6)])
    return float((a - 1) * np.log(z) - z - gammaln(a) + np.log1p(terms.sum()))


def _entry(name, kind, drop, df, description, signature=""):
    log_p = chi2_log_sf(drop, df)
    entry = {"name": name, "kind": kind, "score": round(-float(np.expm1(log_p)), 4), "chi2_drop": round(drop, 2),
             "df": df, "log10_p": round(log_p / np.log(10), 2), "description": description}
    return {**entry, "signature": signature} if signature else entry


def rank(maneuvers, estimate: PointEstimate, extra_columns, plugin_effects=(), white=None):
    """Score every library effect the model lacks and every residual signature.

    A library effect whose columns are a signature's (``bias_drift`` and ``time``) is
    scored once, under its name, with the signature beside it. A noise-model effect
    (correlated star-tracker noise) is scored from ``white`` by the likelihood ratio of white plus
    Gauss-Markov noise over white (`correlation.score`, on two degrees of freedom), and set below a
    deterministic candidate that leaves it unexplained (`noiseranking.demote_explained`).
    Returns a list of dicts (best first) and, per candidate with per-channel columns,
    its statistic channel by channel.
    """
    var = variances(estimate.log_sigma)
    present = set(estimate.spec.effect_names)
    library = [e for e in list(effects.LIBRARY.values()) + list(plugin_effects)
               if e.name not in present and not e.core and not e.noise and _applies(e, maneuvers[0])]
    candidates = [("effect", e) for e in library] + [("signature", e) for e in signature_effects(extra_columns)]
    spec, stats = _augmented(maneuvers, estimate, [e for _, e in candidates], var)
    n_model = len(estimate.spec)
    extras = spec.parameters[n_model:]
    groups = [(kind, e, [i for i, p in enumerate(extras) if p.effect == e.name]) for kind, e in candidates]
    ranking, detail = [], {}
    for kind, effect, idx in groups:
        drop = _chi2_drop(stats, n_model, idx)
        ranking.append(_entry(effect.name, kind, drop, len(idx), effect.description, effect.signature))
        per_channel = [i for i in idx if extras[i].channel is not None]
        if per_channel:
            detail[effect.name] = {extras[i].label: round(_chi2_drop(stats, n_model, [i]), 2)
                                                       for i in per_channel}
    on_clock = maneuvers[0].gm_clock_s_per_rad > 0
    if white is not None and not estimate.spec.correlated_noise:
        fitted = clock.likelihood_ratio(maneuvers, estimate) if on_clock else white["gauss_markov"]
        said = (f" (on the campaign's clock of {fitted['clock_s_per_rad']:g} s a radian turned: the REML's "
                f"likelihood ratio, share {fitted['share']:.2f}, tau {fitted['tau_s']:.3g} clock seconds)"
                if on_clock else correlation.caveat(fitted))
        for effect in (e for e in effects.LIBRARY.values() if e.noise and not e.rate_noise):
            ranking.append(_entry(effect.name, "effect", fitted["chi2"], correlation.GAUSS_MARKOV_DF,
                                  effect.description + said))
    if white is not None and white.get("rate_growth") and not estimate.spec.jitter_noise:
        jitter = effects.LIBRARY["st_jitter"]
        ranking.append(_entry(jitter.name, "effect", white["rate_growth"]["chi2"], rategrowth.RATE_DF,
                              jitter.description))
    ranking.sort(key=lambda r: (r["log10_p"], -r["chi2_drop"]))
    _encompass(ranking, groups, stats, n_model)
    deterministic = {e.name: e for _, e, _ in groups}
    for noise_effect in noiseranking.SCORES_GIVEN:  # on the clock, correlated noise given each: the REML's ratio
        given = _clock_score_given if on_clock and noise_effect == noiseranking.NOISE_EFFECT else None
        noiseranking.demote_explained(ranking, maneuvers, estimate, deterministic, ENCOMPASS_TOP, noise_effect, given)
    return ranking, detail


def _clock_score_given(maneuvers, estimate: PointEstimate, added) -> dict:
    """`clock.likelihood_ratio` given ``added``'s columns, as `noiseranking.demote_explained` reads a score."""
    fitted = clock.likelihood_ratio(maneuvers, estimate, added)
    return {**fitted, "log10_p": chi2_log_sf(fitted["chi2"], correlation.GAUSS_MARKOV_DF) / np.log(10)}


def linearized(maneuvers, estimate: PointEstimate):
    """Each maneuver's linearisation and noise structure about the estimate, one maneuver at a
    time (`linearize_all` holds every maneuver's: over 1 GB at 10x the default campaign)."""
    for m in range(len(maneuvers)):
        lin = estimate.linearize(maneuvers, m)
        yield lin, covariance.build(lin, estimate.boresight, estimate.correlation_time_s, estimate.spec.jitter_noise)


def _measuring(walk_variances, pairs, measured: list):
    """``pairs`` passed on, each linearisation's increment growth (`smoothness.of_maneuver`, at its fitted
    walk) appended to ``measured`` on the way."""
    for walk, (lin, nz) in zip(walk_variances, pairs):
        measured.append(smoothness.of_maneuver(lin, walk))
        yield lin, nz


def whiteness(maneuvers, pairs, estimate: PointEstimate):
    """Lag-1 autocorrelation of the standardised innovations at the fitted model, per
    maneuver and overall, with its z-score (``rho sqrt(n)``, n the star-tracker samples), and the
    Whittle likelihood ratio of white plus Gauss-Markov noise over white on the first channel set's
    innovations (`correlation.score`, ``gauss_markov``) that ranks correlated reference noise, and the
    likelihood ratio of their variance growing with the squared rate (`rategrowth.score`, ``rate_growth``)
    that ranks the reference's timing jitter.
    ``pairs``: each maneuver's linearisation and noise structure, e.g. `linearized`'s."""
    ratios = ratios_of(estimate.log_sigma)
    index = noise_groups(maneuvers)[1]
    per, spectra, pooled_num, pooled_den, rated = {}, [], 0.0, 0.0, []
    for m, (data, (lin, nz)) in enumerate(zip(maneuvers, pairs)):
        wm = WhitenedManeuver(nz, ratios)
        zero = np.zeros((1, nz.n_params))
        beta = wm.nuisance(zero)
        w = (wm.wd - wm.wg @ beta[0]) / noiseranking.innovation_sd(estimate, index[m])
        lag = lin.z.shape[1] * 3
        num, den = float(w[lag:] @ w[:-lag]), float(w @ w)
        per[data.id] = {"lag1": round(num / den, 4), "z": round(num / den * np.sqrt(len(w) / lag), 2),
                        "variance": round(den / len(w), 4)}
        pooled_num += num
        pooled_den += den
        spectra.append(correlation.periodogram(w, lag))
        if lin.st_body_rate is not None:
            rated.append(rategrowth.per_sample(w, lag, lin.st_body_rate))
    n = sum(len(d.st_time) for d in maneuvers)
    rho = pooled_num / pooled_den
    return {"lag1": round(rho, 4), "z": round(rho * np.sqrt(n), 2), "per_maneuver": per,
            "gauss_markov": correlation.score(spectra), "rate_growth": rategrowth.score(rated) if rated else None}


def noise_rms_arcsec(maneuvers, stated_noise, motion_arcsec=None) -> float:
    """What the stated noise predicts for the residual RMS per axis: the star tracker's variance averaged
    over the axes, plus the walk left after the initial attitude and bias are fitted (detrended Brownian
    motion: q T / 15). ``motion_arcsec``: where the stated noise is the reference's white part alone
    (`parts.white_stated`), the fitted Gauss-Markov part's sds (cross, about), its stationary
    variance added: the error that the recording's rests do not show (on a clock of the angle turned, the
    error the motion sets). The check cannot then fail on that part's level: the white part judged
    against the rests, the innovations' whiteness and the ranking judge it."""
    cross, about, arw = covariance.stated_si(stated_noise)
    st_var = (2 * cross**2 + about**2) / 3
    if motion_arcsec is not None:
        gm_cross, gm_about = np.asarray(motion_arcsec, dtype=float) * ARCSEC_RAD
        st_var += (2 * gm_cross**2 + gm_about**2) / 3
    durations = np.array([d.st_time[-1] - d.gyro_time[0] for d in maneuvers])
    return float(rad_to_arcsec(np.sqrt(st_var + arw**2 * np.mean(durations) / 15)))


def judged_key(key: str, noise_posterior: dict, stated_noise: dict) -> str:
    """The posterior's key that the stated ``key`` judges: the star tracker's white part
    (`parts.SPLIT_KEYS`) where the stated noise is that part alone (`parts.white_stated`) and
    the model sampled a Gauss-Markov part; else ``key`` itself."""
    white = parts.SPLIT_KEYS.get(key, (None,))[0]
    return white if parts.white_stated(stated_noise) and white in noise_posterior else key


def motion_part_arcsec(noise_posterior: dict, stated_noise: dict):
    """The fitted Gauss-Markov part's sds (cross, about; arcsec) where the stated noise is the white part
    alone (`judged_key`), for `noise_rms_arcsec`; None otherwise."""
    gm = [parts.SPLIT_KEYS[k][1] for k in ("sigma_cross_arcsec", "sigma_about_arcsec")]
    if not parts.white_stated(stated_noise) or not all(k in noise_posterior for k in gm):
        return None
    return [noise_posterior[k] for k in gm]


def _nearest_to_band(low, high) -> float:
    """A noise scale's figure against the band, either way: the end of its 95 % interval nearest the
    stated value (1 where the interval holds it), as a factor of at least 1."""
    if low <= 1.0 <= high:
        return 1.0
    near = low if low > 1.0 else high
    return near if near >= 1 else 1 / near if near > 0 else np.inf


def misfit_findings(residual_rms, noise_rms, white, ranking, noise_posterior, stated_noise, cfg,
                    noise_interval=None) -> list:
    """Each misfit check as a `Finding`: its figure against the threshold of the config's ``diagnostics``.
    ``noise_interval``: each noise scale's 95 % posterior interval (low, high) by key; a scale
    without one is judged on its point, ``noise_posterior``, alone (`refusals.noise_beyond`)."""
    findings = []
    ratio = residual_rms / noise_rms
    findings.append(Finding.judged(
        "level", bool(ratio <= cfg["rms_ratio_max"]),
        f"residual RMS {residual_rms:.2f} arcsec is {ratio:.2f} times what the stated noise "
        + ("and the fitted Gauss-Markov part (the reference's error that its rests do not show) predict"
           if motion_part_arcsec(noise_posterior, stated_noise) is not None else "predicts")
        + f" ({noise_rms:.2f}); limit {cfg['rms_ratio_max']}",
        figure=float(ratio), threshold=float(cfg["rms_ratio_max"]), unit="x predicted"))
    band = cfg["noise_ratio_max"]
    for name in (s.key for s in NOISE_SCALES):
        judged = judged_key(name, noise_posterior, stated_noise)
        fitted, stated = noise_posterior[judged], stated_noise[name]
        r = fitted / stated
        low, high = (np.asarray((noise_interval or {}).get(judged, (fitted, fitted)), dtype=float) / stated)
        off = bool(noise_beyond(low, high, band))
        part = "" if judged == name else (f"'s white part ({judged}; campaign.yaml states what the reference shows "
                                          "at rest, sigma_is: white)")
        findings.append(Finding.judged(
            f"noise:{name}", not off,
            f"the data ask for {name}{part} = {fitted:.4g}, {r:.2f} times the stated {stated:.4g} "
            f"(95 % interval {low:.2f} to {high:.2f}); off only where the interval lies outside "
            f"{1 / band:.2f} to {band:.2f}",
            figure=float(_nearest_to_band(low, high)), threshold=float(band), unit="x stated, either way"))
    findings.append(Finding.judged(
        "whiteness", bool(abs(white["z"]) <= cfg["whiteness_z_max"]),
        f"lag-1 autocorrelation of the standardised innovations {white['lag1']:+.3f} "
        f"(z = {white['z']:+.1f}; limit |z| <= {cfg['whiteness_z_max']})",
        figure=float(abs(white["z"])), threshold=float(cfg["whiteness_z_max"]), unit="sd"))
    worst = ranking[0]
    findings.append(Finding.judged(
        "structure", bool(worst["log10_p"] >= cfg["structure_log10_p_min"]),
        f"{worst['kind']} {worst['name']} would explain chi2 {worst['chi2_drop']:.1f} on "
        f"{worst['df']} degrees of freedom (log10 p = {worst['log10_p']:.1f}; "
        f"limit {cfg['structure_log10_p_min']})",
        figure=float(worst["log10_p"]), threshold=float(cfg["structure_log10_p_min"]), unit="log10 p",
        where=f"{worst['kind']} {worst['name']}"))
    return findings


def misfit_checks(residual_rms, noise_rms, white, ranking, noise_posterior, stated_noise, cfg,
                  noise_interval=None) -> list:
    """Each check as ``diagnostics.json`` records it: name, passed, and a sentence a reviewer can act on."""
    return [f.as_check() for f in misfit_findings(residual_rms, noise_rms, white, ranking, noise_posterior,
                                                  stated_noise, cfg, noise_interval)]


def diagnose(maneuvers, estimate: PointEstimate, fit: pd.DataFrame, summary: pd.DataFrame, thresholds: dict,
             plugin_effects=()) -> dict:
    """``diagnostics.json`` (docs/interface.md section 5): the misfit checks of the fitted
    model, the ranking of what could explain a misfit, and what they rest on.

    ``fit`` is the posterior step's per-sample fit table, ``summary`` its posterior
    summary indexed by label; ``thresholds`` the config's ``diagnostics`` section.
    """
    residuals = fit[[f"residual_{a}" for a in AXES]].to_numpy()
    residual_rms = float(np.sqrt(np.mean(residuals**2)))
    measured = []
    walks = smoothness.fitted_walk_variances(maneuvers, estimate)
    white = whiteness(maneuvers, _measuring(walks, linearized(maneuvers, estimate), measured), estimate)
    ranking, detail = rank(maneuvers, estimate, list(maneuvers[0].extras), plugin_effects, white)
    keys = [s.key for s in NOISE_SCALES]
    sampled = [s.key for s in noise_scales(True, True)] + [k for parts in parts.SPLIT_KEYS.values() for k in parts]
    noise_post = {k: float(summary.loc[f"noise.{k}", "mean"]) for k in sampled if f"noise.{k}" in summary.index}
    noise_ci = {k: [float(summary.loc[f"noise.{k}", c]) for c in ("ci95_low", "ci95_high")]
                for k in sampled if f"noise.{k}" in summary.index and "ci95_low" in summary.columns}
    noise_rms = noise_rms_arcsec(maneuvers, estimate.stated_noise, motion_part_arcsec(noise_post, estimate.stated_noise))
    checks = misfit_checks(residual_rms, noise_rms, white, ranking, noise_post, estimate.stated_noise, thresholds,
                           noise_ci)
    groups = {d.id: d.noise_group for d in maneuvers}
    checks += [f.as_check() for f in band_findings(fit, groups, thresholds["band_outside_max"])]
    checks.append(smoothness_finding(measured).as_check())
    per_maneuver = {}
    for (m, s), group in fit.groupby(["maneuver", "set"], sort=False):
        per_maneuver.setdefault(m, {})[f"set{s}"] = {
            a: round(float(np.sqrt(np.mean(group[f"residual_{a}"] ** 2))), 3) for a in AXES}
    judged = {k: judged_key(k, noise_post, estimate.stated_noise) for k in keys}
    out = {
        "model": estimate.spec.model,
        "effects": list(estimate.spec.effect_names),
        "residual_rms_arcsec": round(residual_rms, 4),
        "noise_rms_arcsec": round(noise_rms, 4),
        "misfit": not all(c["passed"] for c in checks),
        "ranking": ranking,
        "checks": checks,
        "whiteness": white,
        "noise_posterior": noise_post,
        "noise_posterior_ci95": noise_ci,
        "noise_stated": {k: estimate.stated_noise[k] for k in keys},
        "st_correlation_time_s": estimate.correlation_time_s,
        "residual_rms_per_maneuver_arcsec": per_maneuver,
        "signature_detail_chi2": detail,
        "unexplained_fraction": round(float(fit[[f"outside_{a}" for a in AXES]].to_numpy().mean()), 4),
    }
    if any(k != v for k, v in judged.items()):  # the stated noise is the white part: what each judges
        out["noise_judged"] = judged
    return out
