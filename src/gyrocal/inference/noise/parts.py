"""The star tracker's white and Gauss-Markov parts, and which of them a stated noise states.

With `st_correlated_noise` the sampled scales are the total sds (``sigma_cross``, ``sigma_about``) and the
Gauss-Markov share (`covariance.GM_FRACTION_SCALE`). A data sheet states the total; a recording at rest
states the white part (campaign.yaml's ``star_tracker: sigma_is: white``, as `gyrocal import` writes it):
then the prior (`gyrocal.inference.sampling.priors`), the refusal before sampling and the misfit check
take the white part, and the reports give both parts (`SPLIT_KEYS`)."""

import numpy as np

from gyrocal.inference.noise.covariance import GM_FRACTION_SCALE, position
from gyrocal.io.campaign_yaml import SIGMA_IS_KEY

__all__ = ["SPLIT_KEYS", "judged_log_sigma", "split_parts", "white_log_sigma", "white_stated"]

SPLIT_KEYS = {"sigma_cross_arcsec": ("st_white_cross_arcsec", "st_gm_cross_arcsec"),
              "sigma_about_arcsec": ("st_white_about_arcsec", "st_gm_about_arcsec")}
"""With correlated star-tracker noise, each total sd's white and Gauss-Markov parts (`split_parts`), as
``posterior_summary.csv`` and ``diagnostics.json`` report them beside the sampled scales."""


def white_stated(stated: dict) -> bool:
    """Whether the stated star-tracker noise (``sigma_cross``, ``sigma_about``) is its white part alone:
    campaign.yaml's ``star_tracker: sigma_is: white`` (`SIGMA_IS_KEY`), as `gyrocal import` writes it for
    a noise measured in a recording's rests, where the consecutive samples' differences show the white
    part (a Gauss-Markov part that forgets over seconds or a radian turned hardly moves between them).
    Then that part is judged, and the Gauss-Markov part's level is the model's to fit; by default the
    stated sd is the total, as a data sheet gives it (`covariance.GM_FRACTION_SCALE`)."""
    return stated.get(SIGMA_IS_KEY) == "white"


def white_log_sigma(log_sigma) -> np.ndarray:
    """``log_sigma`` (last axis, a layout with a Gauss-Markov share) with the star tracker's two scales as
    their white parts, ``log(sigma sqrt(1 - share))``: finite at any share (``logaddexp``)."""
    log_sigma = np.asarray(log_sigma, dtype=float)
    share = position(log_sigma, GM_FRACTION_SCALE)
    out = log_sigma.copy()
    out[..., :2] = log_sigma[..., :2] - 0.5 * np.logaddexp(0.0, log_sigma[..., share:share + 1])
    return out


def judged_log_sigma(log_sigma, stated: dict) -> np.ndarray:
    """``log_sigma`` (last axis) as the stated noise states them: where `white_stated` and the model has a
    Gauss-Markov share, the white parts (`white_log_sigma`); else as they are. Against the sampled
    coordinates the map is triangular with unit diagonal, so a prior put on these needs no Jacobian. The
    prior it leaves the Gauss-Markov part, ``log sigma_white + logit(share) / 2``, has its median at the
    white part and a log sd of ``hypot(noise_log_sd, 1)``."""
    log_sigma = np.asarray(log_sigma, dtype=float)
    if position(log_sigma, GM_FRACTION_SCALE) is None or not white_stated(stated):
        return log_sigma
    return white_log_sigma(log_sigma)


def split_parts(scales: dict) -> dict:
    """The star tracker's sds split into their white and Gauss-Markov parts (`SPLIT_KEYS`), draw by draw:
    ``scales`` maps the sampled keys to values (or arrays of draws) in the contract's units, with the
    Gauss-Markov share; empty where there is none."""
    if GM_FRACTION_SCALE.key not in scales:
        return {}
    share = np.asarray(scales[GM_FRACTION_SCALE.key], dtype=float)
    out = {}
    for total, (white, gm) in SPLIT_KEYS.items():
        out[white] = np.asarray(scales[total], dtype=float) * np.sqrt(1.0 - share)
        out[gm] = np.asarray(scales[total], dtype=float) * np.sqrt(share)
    return out
