"""The white baseline fitted to a campaign and its diagnostics' ranking of explanations, in one
process: what the ranking study (`studies/explanation_ranking.py`) and its tests call, as the
point-estimate and diagnostics steps compute them, without the workflow."""

from gyrocal.criticism import diagnostics
from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import linearize_all, point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.maneuvers import preprocess
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec

__all__ = ["baseline_ranking"]


def baseline_ranking(campaign, noise_defaults: dict) -> tuple:
    """The campaign's maneuvers, the baseline's point estimate (its noise as campaign.yaml states it, else
    ``noise_defaults``), its whiteness statistics and its ranking (`diagnostics.rank`, best first)."""
    maneuvers = [preprocess.slice_maneuver(campaign, m.id) for m in campaign.maneuvers]
    stated = noise_knowledge({"star_tracker": campaign.star_tracker, "gyro": campaign.gyro}, noise_defaults)
    spec = ModelSpec.build("baseline", effects.resolve("baseline", list(effects.BASELINE), {}), maneuvers[0].channels)
    est = point_estimate(maneuvers, spec, stated, classic.classic_start(maneuvers, spec))
    lins, noises = linearize_all(maneuvers, est)
    white = diagnostics.whiteness(maneuvers, zip(lins, noises), est)
    ranking, _ = diagnostics.rank(maneuvers, est, list(maneuvers[0].extras), (), white)
    return maneuvers, est, white, ranking
