"""The posterior's priors: each parameter's, normal or Student-t at the scale its `gyrocal.model.spec`
declares (or the config, or an earlier campaign's calibration, overrides), and the noise scales'
log-normal ones about the stated noise."""

from dataclasses import dataclass

import numpy as np
import pandas as pd

from gyrocal.inference.noise.covariance import log_sigma_of, noise_scales
from gyrocal.inference.noise.parts import judged_log_sigma
from gyrocal.io.calibration import parameter_rows
from gyrocal.model import priorfamily

__all__ = ["GROUP_SD_PRIOR_LOG_SD", "GROUP_SD_PRIOR_MEDIAN", "Priors", "model_priors", "posterior_spec"]


@dataclass
class Priors:
    """The parameters' priors, normal or Student-t (``dof``, `gyrocal.model.priorfamily`; ``sd`` their
    scale), with bounds that say what is physical (SI), and log-normal noise priors."""

    mean: np.ndarray
    sd: np.ndarray
    bound: np.ndarray
    log_sigma_center: np.ndarray
    log_sigma_sd: np.ndarray
    dof: np.ndarray | None = None
    """Each parameter's prior degrees of freedom; None or ``inf``: normal."""
    stated_noise: dict | None = None
    """The noise knowledge the noise priors are centred on: where it states the star tracker's white part
    alone (`parts.white_stated`), their log-normal holds that part (`noise_log_density`)."""

    def noise_log_density(self, log_sigma) -> np.ndarray:
        """The noise scales' log prior (W,) at ``log_sigma`` (W, k), up to a constant: log-normal about the
        stated noise, on the scales as it states them (`parts.judged_log_sigma`)."""
        judged = judged_log_sigma(log_sigma, self.stated_noise or {})
        return -0.5 * np.sum(((judged - self.log_sigma_center) / self.log_sigma_sd) ** 2, axis=1)

    @property
    def heavy(self) -> bool:
        """Whether any parameter's prior is Student-t."""
        return self.dof is not None and bool(priorfamily.heavy(self.dof).any())

    def log_density(self, theta) -> np.ndarray:
        """The parameters' log prior (W,) at ``theta`` (W, P), up to a constant."""
        if not self.heavy:
            return -0.5 * np.sum(((theta - self.mean) / self.sd) ** 2, axis=1)
        return priorfamily.log_density((theta - self.mean) / self.sd, self.dof)

    def gaussian_sd(self, theta_hat) -> np.ndarray:
        """The sd of the normal prior that stands in for each where a Gaussian one is needed, about the
        data's estimate ``theta_hat`` (`priorfamily.proposal_sd`): ``sd`` itself where all are normal."""
        if not self.heavy:
            return self.sd
        return priorfamily.proposal_sd(self.sd, (np.asarray(theta_hat) - self.mean) / self.sd, self.dof)

    @classmethod
    def from_spec(cls, spec, stated_noise: dict, noise_log_sd: float) -> "Priors":
        """The spec's priors (as declared, or overridden by `ModelSpec.with_priors`); the noise
        scales' (`covariance.noise_scales`) are centred on the stated noise (`covariance.log_sigma_of`:
        the three white scales, and the timing jitter where campaign.yaml states it, as
        `covariance.noise_knowledge` passes it on), else on their own median, with their own sd or else
        the config's ``noise_log_sd``: with correlated noise, the star tracker's Gauss-Markov share
        logit-normal about one half and its correlation time log-normal about 30 s (plus a radian's
        seconds where campaign.yaml runs its clock on the angle turned: `covariance.gm_tau_prior_s`), as
        `covariance.GM_FRACTION_SCALE` and `covariance.GM_TAU_SCALE` declare them (no campaign states
        either); the timing jitter log-normal (`covariance.JITTER_SCALE`). Where campaign.yaml states the star
        tracker's white part (`parts.white_stated`), its prior holds that part."""
        scales = noise_scales(spec.correlated_noise, spec.jitter_noise)
        center = log_sigma_of(stated_noise, spec.jitter_noise, spec.correlated_noise)
        sd = np.array([float(noise_log_sd) if s.prior_log_sd is None else s.prior_log_sd for s in scales])
        return cls(spec.prior_mean_si, spec.prior_sd_si, spec.bound_si, center, sd, spec.prior_dof, dict(stated_noise))

    @property
    def log_ratio_sd(self) -> float:
        """The prior sd of a white noise scale's log ratio to ``sigma_cross`` (two log scales'
        difference): where the data do not tell a ratio, its spread is this."""
        return np.sqrt(2.0) * self.log_sigma_sd[0]

    def ratio_sd(self, scales) -> np.ndarray:
        """Each noise ratio's prior sd (`covariance.ratios_of`, of the model's ``scales``), where the data
        do not tell it: a ratio of two scales under the config's ``noise_log_sd`` `log_ratio_sd`, one of a
        scale with its own prior to ``sigma_cross`` the two in quadrature, a share or tau its own."""
        sd = self.log_sigma_sd
        return np.array([self.log_ratio_sd if s.prior_log_sd is None else np.hypot(sd[0], sd[i]) if s.relative
                         else sd[i] for i, s in enumerate(scales) if i])


def posterior_spec(spec, priors_cfg: dict, prior_from=None):
    """A point estimate's specification with the priors its posterior samples under: the declared
    ones, overridden by the config and by an earlier campaign's ``calibration.csv``
    (``prior_from``): its parameters' rows, never its derived combinations (a combination is no
    parameter's prior: ``sf_mean`` is correlated with both scale factors)."""
    earlier = parameter_rows(pd.read_csv(prior_from)) if prior_from else None
    return spec.with_priors(priors_cfg, earlier, str(prior_from))


def model_priors(estimate, priors_cfg: dict, prior_from=None) -> Priors:
    """The priors of a point estimate's posterior (`posterior_spec`), its noise scales' centred on
    its stated noise with the config's ``noise_log_sd``."""
    spec = posterior_spec(estimate.spec, priors_cfg, prior_from)
    return Priors.from_spec(spec, estimate.stated_noise, priors_cfg["noise_log_sd"])


GROUP_SD_PRIOR_MEDIAN = 0.5
"""Noise groups: the prior's median of the sd of the groups' log levels about the campaign's..."""

GROUP_SD_PRIOR_LOG_SD = 1.0
"""... and its log-normal sd (a spread of a factor 1.07 to 3.6 in noise within two sd)."""
