"""Correlated reference noise against the deterministic explanations ranked below it.

A deterministic effect the model lacks correlates the residual too, and a large one can out-score its
own score test (an independent review found a hidden gravity offset three times the study's largest,
a g-sensitivity three times and a bias drift ten times named as correlated noise, by a score that
summed the autocorrelations). The two are told apart by what each leaves: with the effect's columns
fitted too, the innovations of such a campaign are white again, while a Gauss-Markov error's
correlation survives any one effect (the reviewer's runs: given the true effect the noise's log10 p
went to 0.0 on 8 of 8 hidden-effect campaigns; on tau 30 s campaigns it stayed at -84 and -43
given the top deterministic candidates). The reference's timing jitter (`rategrowth`) is set below
them the same way: a latency left out also leaves innovations that grow with the rate (at 5 deg/s a
20 ms latency scored log10 p -689 as jitter against -517 for st_latency), and its columns take them.
"""

import numpy as np

from gyrocal.criticism import correlation, rategrowth
from gyrocal.inference import errormodel
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.inference.noise import covariance
from gyrocal.inference.noise.covariance import ratios_of
from gyrocal.inference.sampling.predictive import WhitenedManeuver
from gyrocal.maneuvers.preprocess import noise_groups

__all__ = ["LEFTOVER_LOG10_P", "NOISE_EFFECT", "RATE_EFFECT", "SCORES_GIVEN", "demote_explained", "innovation_sd",
           "noise_score_given", "rate_score_given"]

NOISE_EFFECT = "st_correlated_noise"
RATE_EFFECT = "st_jitter"

LEFTOVER_LOG10_P = -2.0
"""Given an effect's columns, a noise score above this log10 p is explained by the effect (the ranking's
leaders are the candidates below it)."""


def innovation_sd(estimate: PointEstimate, group: int) -> float:
    """The sd that standardises a maneuver's whitened innovations (`WhitenedManeuver` whitens at unit
    cross-boresight variance): the campaign's cross-boresight sd times the level of its noise group."""
    level = 1.0 if estimate.group_offsets is None else np.exp(2 * estimate.group_offsets[group])
    return float(np.sqrt(np.exp(2 * estimate.log_sigma[0]) * level))


def _whitened(maneuvers, estimate: PointEstimate, added):
    """Per maneuver: the whitened columns of the model's parameters and ``added``'s, and the whitened
    data, each with the maneuver's nuisance projected out and scaled to unit noise; the
    innovations' stride (values per sample); and the body rate at the reference samples."""
    spec = estimate.spec.augmented(added)
    theta = np.concatenate([estimate.theta, np.zeros(len(spec) - len(estimate.spec))])
    ratios = ratios_of(estimate.log_sigma)
    index = noise_groups(maneuvers)[1]
    for m, data in enumerate(maneuvers):
        lin = errormodel.linearize(data, spec, theta, estimate.biases[m])
        wm = WhitenedManeuver(covariance.build(lin, estimate.boresight, estimate.correlation_time_s,
                                                   estimate.spec.jitter_noise), ratios)
        q = np.linalg.qr(wm.wg)[0]
        unit = innovation_sd(estimate, index[m])
        x = (wm.wx - q @ (q.T @ wm.wx)) / unit
        d = (wm.wd - q @ (q.T @ wm.wd)) / unit
        yield x, d, lin.z.shape[1] * 3, lin.st_body_rate


def _innovations_given(maneuvers, estimate: PointEstimate, added) -> list:
    """Per maneuver, the innovations with the model's and ``added``'s parameters fitted jointly, their
    stride and the body rate at the reference samples."""
    parts = list(_whitened(maneuvers, estimate, added))
    x = np.vstack([p[0] for p in parts])
    coef = np.linalg.lstsq(x, np.concatenate([p[1] for p in parts]), rcond=1e-10)[0]
    return [(dm - xm @ coef, stride, rate) for xm, dm, stride, rate in parts]


def noise_score_given(maneuvers, estimate: PointEstimate, added) -> dict:
    """`correlation.score` of the innovations with the model's parameters and ``added``'s (effects or
    signatures) fitted jointly, each maneuver's nuisance profiled out."""
    return correlation.score([correlation.periodogram(w, stride) for w, stride, _ in
                              _innovations_given(maneuvers, estimate, added)])


def rate_score_given(maneuvers, estimate: PointEstimate, added) -> dict:
    """`rategrowth.score` of the innovations with the model's parameters and ``added``'s fitted jointly:
    a latency or a scale-factor error left out grows with the rate too, and its columns take it."""
    return rategrowth.score([rategrowth.per_sample(w, stride, rate) for w, stride, rate in
                             _innovations_given(maneuvers, estimate, added)])


SCORES_GIVEN = {NOISE_EFFECT: noise_score_given, RATE_EFFECT: rate_score_given}
"""Each noise-model effect's score given deterministic candidates' columns."""


def demote_explained(ranking: list, maneuvers, estimate: PointEstimate, candidates: dict, top: int,
                     noise_effect: str = NOISE_EFFECT, score_given=None) -> None:
    """Set the noise-model effect ``noise_effect`` (correlated noise, or the timing jitter), where it leads a
    deterministic candidate within the ``top`` of ``ranking`` (name -> effect in ``candidates``), below the
    last such candidate that leaves it unexplained (`LEFTOVER_LOG10_P`), in place; its entry gets
    ``leftover_log10_p``, the most significant of its scores given each (``score_given``'s: by default
    `SCORES_GIVEN`'s)."""
    score_given = score_given or SCORES_GIVEN[noise_effect]
    at = next((i for i, r in enumerate(ranking[:top]) if r["name"] == noise_effect), None)
    if at is None or ranking[at]["log10_p"] >= LEFTOVER_LOG10_P:
        return
    below = [i for i in range(at + 1, min(top, len(ranking)))
             if ranking[i]["name"] in candidates and ranking[i]["log10_p"] < LEFTOVER_LOG10_P]
    if not below:
        return
    left = {i: score_given(maneuvers, estimate, [candidates[ranking[i]["name"]]])["log10_p"] for i in below}
    entry = ranking[at]
    entry["leftover_log10_p"] = float(min(left.values()))
    explained = [i for i in below if left[i] >= LEFTOVER_LOG10_P]
    if explained:
        ranking.insert(explained[-1], ranking.pop(at))
