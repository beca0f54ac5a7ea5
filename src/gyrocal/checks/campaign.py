"""Physical consistency of a campaign, before any fit: do the gyros see what the star tracker sees?

Format checks (`gyrocal.io.telemetry`) cannot tell increments in degrees from increments in radians,
or a scalar-first quaternion from a scalar-last one. Here each maneuver's gyro rotation,
summed between star-tracker samples, is compared with the star tracker's own rotation
over the same interval (`physics`), the sampling and clocks are checked (`sampling`), and
star-tracker outliers are screened (`outliers`). Each finding says what was found and its
likely cause. The thresholds come from the physical bounds of the campaign's sensor class
(`gyrocal.model.sensorclass`, a DTG's where it declares none) and from the
noise measured in the data themselves, not from one file."""


from gyrocal.checks.conventions import convention_findings
from gyrocal.checks.mounting import align
from gyrocal.checks.outliers import EXCURSION_MAX_S, outlier_distances, screen, trend_distances
from gyrocal.checks.physics import rotation_findings
from gyrocal.checks.sampling import clock_findings, extreme_findings, gap_findings, interval_findings
from gyrocal.checks.saturation import gyro_range_rad_s, saturation_findings
from gyrocal.checks.sensing import physical_limits, sense
from gyrocal.checks.stuck import stuck_findings
from gyrocal.finding import Findings
from gyrocal.inference.fit import classic
from gyrocal.inference.sampling.refusals import EstimateError, check_blocks
from gyrocal.io.telemetry import UNIT_NORM_TOL, Campaign, TelemetryError, read_campaign
from gyrocal.io.telemetry import summary as format_summary
from gyrocal.maneuvers import preprocess

__all__ = ["check", "read_checked", "summary"]


def check(campaign: Campaign, block_s: float | None = None) -> Findings:
    """Every physical check of a campaign. Outliers are screened with a threshold that keeps
    the expected false alarms per campaign at `OUTLIER_FALSE_ALARMS`; they are listed here
    and left out by `preprocess`. With ``block_s`` (the sampler's leave-one-block-out block), a
    maneuver too short for it is refused here, as the posterior step would refuse it later."""
    findings = Findings()
    if extreme_findings(campaign, findings) or interval_findings(campaign, findings):
        return findings
    gap_findings(campaign, findings)
    limits = physical_limits(campaign.channels, campaign.gyro.get("sensor_class"))  # the class's, not a DTG's
    if convention_findings(campaign, limits, findings) or stuck_findings(campaign, limits, findings):
        return findings  # the physics per maneuver would only restate them, once per maneuver
    range_rad_s = gyro_range_rad_s(campaign)
    screened, sliced = [], []
    for m in campaign.maneuvers:
        try:
            data = preprocess.slice_maneuver(campaign, m.id)
        except TelemetryError as exc:
            findings.refuse("slice", str(exc))
            continue
        sliced.append(data)
        every_set = [sense(data, s) for s in range(len(data.sets))]  # redundant channels too
        clipped = any(saturation_findings(sensed, limits[0], findings, range_rad_s) for sensed in every_set)  # once
        if clipped or not all([rotation_findings(campaign, sensed, limits, findings) for sensed in every_set]):
            continue
        sensed = every_set[0]
        clock_findings(sensed, findings)
        missing = classic.missing_holds(data)
        if data.free:
            findings.warn("holds", f"maneuver {m.id}: free motion: the paper's classic method does not apply "
                                     "to it (the full-trajectory fit does)")
        elif data.direction == "both":
            findings.warn("holds", f"maneuver {m.id}: turns both ways: the paper's classic method does not apply "
                                     "to it (the full-trajectory fit does)")
        elif missing:
            findings.warn("holds", f"maneuver {m.id}: no inertial hold {' or '.join(missing)} the rotation: "
                                     "the paper's classic method does not apply to it (the full-trajectory "
                                     "fit does)")
        screened.append((data, *outlier_distances(sensed), *trend_distances(sensed)))
    screen(campaign, screened, findings)
    if block_s and sliced:
        try:
            check_blocks(sliced, block_s)
        except EstimateError as short:
            findings.refuse("blocks", str(short))
    return findings




def read_checked(directory, campaign=None, block_s: float | None = None):
    """Read a campaign (format, `telemetry.read_campaign`; or take ``campaign``, the directory's
    as that read it), turn its reference into body axes (`align`) and check its physics (`check`,
    with the sampler's ``block_s`` where given); every error found is raised at once in one
    `TelemetryError`. Returns the aligned campaign and its `Findings`."""
    campaign, mounting, refused = align(read_campaign(directory) if campaign is None else campaign)
    findings = check(campaign, block_s) if refused is None else Findings([refused])  # the rest would check a wrong frame
    findings.mounting = mounting
    if findings.errors:
        listed = "\n".join(f"  - {e}" for e in findings.errors)
        raise TelemetryError(f"{directory}: the data are not physically consistent "
                             f"({len(findings.errors)} finding(s)):\n{listed}")
    return campaign, findings


def summary(campaign: Campaign, findings: Findings) -> str:
    """What ``gyrocal validate`` prints: the campaign, then the warnings and outliers."""
    lines = [format_summary(campaign)]
    if findings.mounting:
        lines.append(f"  reference  mounting {findings.mounting['source']}: {findings.mounting['angle_deg']:.3f} deg "
                     f"from body axes"
                     + ("; sd about " + ", ".join(f"{a} {v:.3g}" for a, v in findings.mounting["sd_deg"].items())
                        + " deg" if "sd_deg" in findings.mounting else ""))
    if campaign.st_renormalised:
        lines.append(f"  renormalised {campaign.st_renormalised} star-tracker quaternions (norm off 1 by more "
                     f"than {UNIT_NORM_TOL:g}, as rounding leaves them)")
    for w in findings.warnings:
        lines.append(f"  warning: {w}")
    if findings.outliers:
        away = sum(o.kind == "excursion" for o in findings.outliers)
        lines.append(f"  star-tracker outliers, left out of the fit: {len(findings.outliers)}"
                     + (f", {away} of them in excursions (off the error's trend and back within "
                        f"{EXCURSION_MAX_S:g} s)" if away else "")
                     + (" (the 20 largest; all in input.json)" if len(findings.outliers) > 20 else ""))
        for o in sorted(findings.outliers, key=lambda o: -o.mahalanobis)[:20]:
            lines.append(f"    {o.maneuver:<12} line {o.line:>7}  t = {o.time_s:.2f} s  {o.size_arcsec:8.1f} arcsec "
                         f"({o.mahalanobis:.1f} sd)" + ("  excursion" if o.kind == "excursion" else ""))
    return "\n".join(lines)
