"""Step ``validate``, the first of the preprocess rule's job: read a campaign, check its format
and physics, record ``input.json``."""

import logging
from dataclasses import asdict

from gyrocal import __version__, checks
from gyrocal.io import telemetry
from gyrocal.io.outputs import write_json

__all__ = ["run"]

log = logging.getLogger("gyrocal")


def run(campaign_dir, input_json, campaign=None, block_s: float | None = None):
    """Read the campaign (unless given ``campaign``, as `telemetry.read_campaign` read it) and
    check its format and physics (`gyrocal.checks`; with the sampler's ``block_s``, also that every
    maneuver is long enough for the leave-one-block-out predictive); record what was read, the
    warnings, the star-tracker outliers to leave out, its noise knowledge and the files' checksums in
    ``input_json``."""
    campaign, findings = checks.read_checked(campaign_dir, campaign, block_s)
    log.info("%s", checks.summary(campaign, findings))
    write_json({
        "campaign": campaign.name,
        "gyrocal_version": __version__,
        "channels": campaign.channel_names,
        "extras": list(campaign.extras()),
        "maneuvers": [m.id for m in campaign.maneuvers],
        "noise_groups": {m.id: m.noise_group for m in campaign.maneuvers},
        "rows": {"gyro": len(campaign.gyro_time), "star_tracker": len(campaign.st_time),
                 "star_tracker_invalid": int((campaign.st_valid == 0).sum()),
                 "star_tracker_outliers": len(findings.outliers),
                 "star_tracker_renormalised": campaign.st_renormalised},
        "warnings": findings.warnings,
        "star_tracker_outliers": [asdict(o) for o in findings.outliers],
        "mounting": findings.mounting,
        "star_tracker": campaign.star_tracker,
        "gyro": campaign.gyro,
        "checksums_sha256": telemetry.checksums(campaign_dir),
    }, input_json)
