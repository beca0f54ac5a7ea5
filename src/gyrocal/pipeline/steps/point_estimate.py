"""Rule ``point_estimate``: the full-trajectory WLS of one model."""

import logging

from gyrocal.inference import clock
from gyrocal.inference.fit import classic
from gyrocal.inference.fit.estimate import point_estimate
from gyrocal.inference.noise.covariance import noise_knowledge, stated_scales
from gyrocal.inference.sampling.refusals import check_variant_informed
from gyrocal.io.outputs import write_with
from gyrocal.model import effects
from gyrocal.model.spec import ModelSpec
from gyrocal.pipeline.settings import PointEstimateSettings
from gyrocal.pipeline.steps.common import load_maneuvers, read_json

__all__ = ["run"]

log = logging.getLogger("gyrocal")


def _informed(spec):
    """Each prior-only parameter in the log; the variant skipped where its additions are all prior-only
    (`check_variant_informed`), before its noise scales and WLS are fitted for nothing."""
    for p in spec.parameters:
        if p.prior_only:
            log.warning("%s is prior-only: %s", p.label, p.prior_only)
    check_variant_informed(spec)


def run(maneuver_files, input_json, out_npz, model: str, settings: PointEstimateSettings):
    """The full-trajectory WLS of one model, started from the classic estimate, with the default
    priors of the campaign's gyro sensor class (``campaign.yaml``'s ``gyro.sensor_class``); saved
    with the model's specification, the noise knowledge it used and its linearisation. The classic
    start is computed here, for the model's own specification (a tenth of a second). A variant whose
    added parameters are all prior-only is skipped (`check_variant_informed`) before its noise and WLS
    are fitted.
    ``maneuver_files``: the preprocessed ``.npz``, in the campaign's order; saved to ``out_npz``."""
    maneuvers = load_maneuvers(maneuver_files)
    fx = effects.resolve(model, settings.effects, effects.load_plugins(settings.plugins or []))
    info = read_json(input_json)
    model_spec = ModelSpec.build(model, fx, maneuvers[0].channels).with_sensor_class(info["gyro"].get("sensor_class"))
    stated = clock.with_clock(noise_knowledge(info, settings.noise), maneuvers)
    est = point_estimate(maneuvers, model_spec, stated, classic.classic_start(maneuvers, model_spec),
                         settings.noise["estimate_scales"], check=_informed)
    if model_spec.correlated_noise:
        per_rad = maneuvers[0].gm_clock_s_per_rad
        log.info("star-tracker noise correlation time: %.2f s%s", est.correlation_time_s,
                 f" of a clock that runs {per_rad:g} s a radian turned (a correlation angle of "
                 f"{est.correlation_time_s / per_rad:.3g} rad)" if per_rad > 0 else "")
    log.info("WLS: %s (%d evaluations); noise %s", est.message, est.nfev,
             stated_scales(est.log_sigma))
    write_with(est.save, out_npz)
