"""Recordings into a campaign directory (docs/interface.md section 3), driven by a mapping
(`gyrocal.io.mapping`; each file read by `gyrocal.io.recording`).

Each file becomes one maneuver named after its stem, or, with ``maneuver.split: rests``, one per
stretch between the rests its gyro shows (`gyrocal.io.rests`; ``<stem>_1``, ``<stem>_2``, ...);
each file is one noise group. The files' times are shifted so they follow each other, one
sample step apart (or ``gap_s``). A maneuver is labelled with the axis it turns most about and
the mapping's direction, or, with ``maneuver.free: true``, written with neither: free motion.

A reference faster than its noise is white (a motion-capture system filters its attitude over
several of its samples) can be kept only every ``reference.sample_interval_s`` seconds, as a
star tracker at a few Hz would give it, while the gyro keeps every row: the rows in between
are left out of ``star_tracker.csv`` and counted in the import report, never dropped silently.

A maneuver starts where the reference is (`referenced`): its first attitude is interpolated between
the valid reference samples around its start. A stretch whose reference is missing at its start
(motion capture that sees the markers only seconds into the recording) starts at its first valid
sample instead, and the report says so; a stretch with fewer than `MIN_REFERENCE_SAMPLES` is left
out, and the report names it and why.

A mapping may declare the gyro's range (``gyro.range``, in the mapping's gyro unit, per second
for increments): the report counts the samples within `RANGE_BAND` of it, where the gyro clips
(`gyrocal.checks.saturation` refuses such a maneuver).
"""

import numpy as np

from gyrocal.io import rests
from gyrocal.io.campaign_yaml import SIGMA_IS_KEY
from gyrocal.io.mapping import (
    ANGLE_UNITS,
    ORDERS,
    RATE_UNITS,
    check_interval,
    declared_range_rad_s,
    mapping_path,
    read_mapping,
)
from gyrocal.io.readers import BINARY_WORDS, printed_quantum
from gyrocal.io.recording import MOST_REFUSED, PRECISION_MARGIN, Imported, maneuver_axis, read_file
from gyrocal.io.telemetry import (
    MIN_REFERENCE_SAMPLES,
    NAME_PATTERN,
    UNIT_NORM_TOL,
    Campaign,
    Maneuver,
    TelemetryError,
    default_name,
    write_campaign,
)
from gyrocal.model.channels import Channel
from gyrocal.model.units import rad_to_arcsec

__all__ = [
    "ANGLE_UNITS", "MOST_REFUSED", "ORDERS", "PRECISION_MARGIN", "RANGE_BAND", "RATE_AGREE", "RATE_UNITS", "Imported",
    "build_campaign", "declared_range_rad_s", "import_files", "maneuver_axis", "mapping_path", "printed_quantum",
    "read_file", "read_mapping", "reference_rows", "referenced", "report", "rows_per_reference", "split_file"
]

RANGE_BAND = 0.01
"""Samples within this share of a declared gyro range are counted as at the range (as
`gyrocal.checks.saturation.FLAT_BAND`)."""


def rows_per_reference(time, interval_s) -> int:
    """How many rows one reference interval spans: ``round(interval_s / median step)``, at least one;
    one where the reference is kept every row (``0`` or ``None``)."""
    return max(1, round(interval_s / float(np.median(np.diff(time))))) if interval_s else 1


def reference_rows(time, interval_s) -> np.ndarray:
    """Which rows of one file keep their reference sample when it is wanted only every
    ``interval_s`` seconds: the first row, then every `rows_per_reference` rows after it, and the
    last row (so the reference spans the whole maneuver). ``0`` or ``None``: every row."""
    keep = np.ones(len(time), dtype=bool)
    if not interval_s:
        return keep
    keep[:] = False
    keep[::rows_per_reference(time, interval_s)] = True
    keep[-1] = True
    return keep


def referenced(first: int, stop: int, kept_valid: np.ndarray, reach: int):
    """Rows ``first .. stop - 1`` of a file as a maneuver's ``(first, stop)``: its start moved to its first
    row with a kept, valid reference sample (``kept_valid``) unless one lies at most ``reach`` rows (one
    reference interval) before it and another at most ``reach`` after, where the start's attitude
    interpolates between them as usual; None where fewer than `MIN_REFERENCE_SAMPLES` such rows lie after
    its start (the start's sample anchors its attitude; `gyrocal.maneuvers.preprocess.slice_maneuver`
    counts those after it)."""
    rows = np.flatnonzero(kept_valid[first:stop])
    if not len(rows):
        return None
    near = kept_valid[max(0, first - reach):first + 1].any() and kept_valid[first:first + reach + 1].any()
    start = first if near else first + int(rows[0])
    if np.count_nonzero(kept_valid[start + 1:stop]) < MIN_REFERENCE_SAMPLES:
        return None
    return start, stop


def split_file(imp: Imported, options: dict) -> tuple:
    """A file's maneuvers ``[(first row, row after the last)]`` and its `rests.Rests` (None when the
    mapping keeps each file whole: ``maneuver.split: file``, the default); with ``maneuver.window_s``,
    each of those cut into windows of about that length (`rests.windows`)."""
    step = float(np.median(np.diff(imp.time)))
    if options.get("split", "file") != "rests":
        return rests.windows([(0, len(imp.time))], step, options.get("window_s")), None
    rate = imp.rate if imp.rate is not None else np.vstack([imp.increments[1:2] * 0, imp.increments[1:]
                                                            / np.diff(imp.time)[:, None]])
    found = rests.find_rests(rate, step, float(options.get("min_rest_s", rests.MIN_REST_S)))
    return rests.windows(rests.pieces(len(imp.time), found.runs), step, options.get("window_s")), found


def build_campaign(files, mapping, name: str, reference_interval_s=None) -> tuple:
    """The campaign of ``files`` (end to end; each file one noise group, and one maneuver or, with
    ``maneuver.split: rests``, one per stretch between its rests) and what was counted per file.
    A maneuver is labelled (its axis, the one the gyro turns most about, and the mapping's
    direction, ``both`` by default) unless the mapping says ``maneuver.free: true``: then it has
    neither axis nor direction, free motion."""
    gyro = mapping["gyro"]
    names = list(gyro["columns"])
    axes = [gyro["axes"][n] for n in names]
    channels = tuple(Channel(n, None, a) for n, a in zip(names, axes))
    gap = mapping.get("gap_s")
    options = mapping.get("maneuver") or {}
    direction = None if options.get("free") else options.get("direction", "both")
    interval = mapping["reference"].get("sample_interval_s") if reference_interval_s is None else reference_interval_s
    check_interval(interval, "the reference sample interval")
    range_rad_s = declared_range_rad_s(mapping)
    boresight = (mapping.get("star_tracker") or {}).get("boresight_body", REST_BORESIGHT_BODY)
    parts, maneuvers, counts, rates, walks, still = [], [], {}, [], [], []
    offset = 0.0
    for f in files:
        imp = read_file(f, mapping)
        if not NAME_PATTERN.match(imp.stem):
            raise TelemetryError.at(f, "the file's stem names its maneuvers and noise group, so it may hold only "
                                       "letters, digits and '_'", todo="rename the file")
        shift = offset - imp.time[0]
        time = imp.time + shift
        keep = reference_rows(time, interval)
        parts.append((time, imp, keep))
        spans, found = split_file(imp, options)
        reach = rows_per_reference(time, interval)
        ids, trimmed, left_out = [], {}, []
        for i, (a, b) in enumerate(spans):
            mid = imp.stem if len(spans) == 1 else f"{imp.stem}_{i + 1}"
            span = referenced(a, b, keep & imp.valid, reach)
            if span is None:
                left_out.append((mid, float(time[a]), float(time[b - 1])))
                continue
            if span[0] != a:
                trimmed[mid] = float(time[a])
            a, b = span
            axis = None if direction is None else maneuver_axis(imp.increments[a:b], axes)
            maneuvers.append(Maneuver(mid, axis, direction, float(time[a]), float(time[b - 1]),
                                      noise_group=imp.stem))  # one noise level per recording
            ids.append(mid)
        if not ids:
            usable = int((keep & imp.valid).sum())
            raise TelemetryError.at(f, f"no stretch of it has {MIN_REFERENCE_SAMPLES} valid reference samples kept ({usable} in "
                                       f"all, of {int(keep.sum())} kept)", todo="check the reference columns and the mapping, "
                                       "or keep the reference more often (gyrocal import --reference-interval)")
        step = float(np.median(np.diff(time)))
        rates.append(imp.rate_hz)
        if found is not None and found.arw_rad_sqrt_s is not None:
            walks.append(found.arw_rad_sqrt_s)
        at_rest = None if found is None else rests.reference_noise_at_rest(imp.quat, keep & imp.valid, found.runs, boresight)
        still.append(at_rest)
        counts[imp.stem] = {"rows": len(time), "maneuvers": ids, "trimmed": trimmed, "left_out": left_out,
                            "reference_dropouts": int((~imp.valid[keep] & ~imp.refused[keep] & ~imp.missing[keep]).sum()),
                            "reference_missing": int((keep & imp.missing).sum()),
                            "reference_kept": int(keep.sum()), "reference_interval_s": float(interval or 0.0),
                            "time_shift_s": float(shift), "rate_hz": imp.rate_hz or 1.0 / step,
                            **_rest_counts(found, spans, time, at_rest),
                            **_norm_counts(imp, keep, mapping["reference"]["columns"]),
                            **_range_counts(imp, names, range_rad_s)}
        offset = time[-1] + (step if gap is None else float(gap))
    time = np.concatenate([t for t, _, _ in parts])
    st_time = np.concatenate([t[keep] for t, _, keep in parts])
    quat = np.concatenate([imp.quat[keep] for _, imp, keep in parts])
    valid = np.concatenate([imp.valid[keep] for _, imp, keep in parts]).astype(int)
    increments = np.concatenate([imp.increments for _, imp, _ in parts])
    columns = {n: increments[:, i] for i, n in enumerate(names)}
    for key in parts[0][1].extras:
        columns[key] = np.concatenate([imp.extras[key] for _, imp, _ in parts])
    campaign = Campaign(name=name, channels=channels, star_tracker=_reference_knowledge(mapping, still, boresight),
                        gyro=_gyro_knowledge(mapping, range_rad_s, rates, walks), maneuvers=tuple(maneuvers), st_time=st_time,
                        st_quat=quat, st_valid=valid, gyro_time=time, gyro_columns=columns)
    return campaign, counts


RATE_AGREE = 1e-3
"""Files whose sampling rates differ by less than this share are at one rate (``gyro.rate_hz``)."""


def _gyro_knowledge(mapping, range_rad_s, rates, walks=()) -> dict:
    """``campaign.yaml``'s ``gyro:`` from the mapping: its noise (``gyro_noise``; where it states no ARW,
    the largest the files' rests show, `rests.arw_at_rest`), its sensor class, its range, and its sampling
    rate (the mapping's ``rate_hz``, or the files' one rate where the mapping reads the time off a rate)."""
    known = dict(mapping.get("gyro_noise") or {})
    if "arw_deg_sqrt_h" not in known and walks:
        known["arw_deg_sqrt_h"] = float(np.rad2deg(max(walks)) * 60.0)
    if mapping.get("sensor_class"):
        known["sensor_class"] = mapping["sensor_class"]
    if range_rad_s is not None:
        known["range_deg_s"] = float(np.rad2deg(range_rad_s))  # validate's saturation check reads it
    if mapping.get("rate_hz") is not None:
        known["rate_hz"] = float(mapping["rate_hz"])
    elif None not in rates and np.ptp(rates) <= RATE_AGREE * min(rates):
        known["rate_hz"] = float(rates[0])
    return known


REST_BORESIGHT_BODY = (0.0, 0.0, 1.0)
"""The axis the reference's noise at rest is split about (across it and about it) where the mapping states
no ``star_tracker: boresight_body``; campaign.yaml states it beside the noise, so the split is the one
the fit reads."""


def _reference_knowledge(mapping, still, boresight) -> dict:
    """``campaign.yaml``'s ``star_tracker:`` from the mapping; where it states no noise, the one the files'
    rests show together (`rests.pooled_reference_noise` of ``still``, per file a `rests.ReferenceAtRest`),
    with the boresight it is split about and ``sigma_is: white`` (what a recording at rest shows), as
    `_gyro_knowledge` takes the gyro's ARW from the same rests."""
    known = dict(mapping.get("star_tracker") or {})
    pooled = rests.pooled_reference_noise(still)
    if pooled is not None and "sigma_cross_arcsec" not in known and "sigma_about_arcsec" not in known:
        known["sigma_cross_arcsec"], known["sigma_about_arcsec"] = (float(rad_to_arcsec(v)) for v in pooled)
        known["boresight_body"] = [float(v) for v in boresight]
        known[SIGMA_IS_KEY] = "white"
    return known


def _rest_counts(found, spans, time, at_rest=None) -> dict:
    """The rests a file was cut at and the reference's noise in them (``at_rest``, a `rests.ReferenceAtRest`;
    None where too few pairs), for the report (none unless the mapping splits at rests)."""
    if found is None:
        return {}
    noise = {} if at_rest is None else {
        "reference_rest_sigma_arcsec": [float(rad_to_arcsec(v)) for v in (at_rest.cross_rad, at_rest.about_rad)],
        "reference_rest_pairs": at_rest.pairs, "reference_rest_lag1": at_rest.lag1, "reference_rest_white": at_rest.white}
    return {**noise, "rests_s": [(float(time[a]), float(time[b - 1])) for a, b in found.runs],
            "rest_threshold_rad_s": found.threshold, "rest_sigma_rad_s": found.sigma.tolist(),
            "rest_bias_rad_s": found.bias.tolist(), "rest_smooth": found.smooth,
            "maneuver_spans_s": [(float(time[a]), float(time[b - 1])) for a, b in spans]}


def _norm_counts(imp: Imported, keep, columns) -> dict:
    """What the import did to the reference quaternions it keeps: renormalised (norm off 1 by more
    than `UNIT_NORM_TOL`, within what the printed digits explain) and refused beyond it; norm
    errors also as multiples of what rounding to the printed digits can do."""
    used = keep & imp.valid
    error = np.abs(imp.norm_error)
    times = np.divide(error, imp.norm_rounding, out=np.zeros_like(error), where=imp.norm_rounding > 0)
    refused = np.flatnonzero(keep & imp.refused)
    first = None
    if refused.size:
        row = int(refused[0])
        first = {"line": int(imp.lines[row]), "columns": columns, "norm": float(1.0 + imp.norm_error[row]),
                 "times_rounding": float(times[row])}
    return {"reference_precision": imp.precision,
            "reference_renormalised": int((used & (error > UNIT_NORM_TOL)).sum()),
            "reference_norm_error_max": float(error[used].max()) if used.any() else 0.0,
            "reference_times_rounding_max": float(times[used].max()) if used.any() else 0.0,
            "reference_refused": int(refused.size), "reference_refused_first": first}


def _range_counts(imp: Imported, names, range_rad_s) -> dict:
    """Samples of each gyro channel within `RANGE_BAND` of a declared range (none if none is declared)."""
    if range_rad_s is None:
        return {}
    rate = imp.rate if imp.rate is not None else imp.increments[1:] / np.diff(imp.time)[:, None]
    at = np.abs(rate) >= (1 - RANGE_BAND) * range_rad_s
    return {"gyro_range_rad_s": range_rad_s, "at_range": {n: int(at[:, i].sum()) for i, n in enumerate(names)}}


def import_files(mapping_name, outdir, files, reference_interval_s=None) -> tuple:
    """``gyrocal import``: read ``files`` through a mapping and write the campaign to ``outdir``;
    ``reference_interval_s`` overrides the mapping's ``reference.sample_interval_s`` (0: every row)."""
    mapping = read_mapping(mapping_name)
    name = default_name(outdir)
    campaign, counts = build_campaign(files, mapping, name, reference_interval_s)
    write_campaign(campaign, outdir)
    return campaign, counts


def report(campaign, counts, outdir) -> str:
    """What ``gyrocal import`` prints: the campaign written and what was counted per file."""
    lines = [f"wrote {outdir}: {len(campaign.maneuvers)} maneuvers, channels {', '.join(campaign.channel_names)}, "
             f"extras {', '.join(campaign.extras()) or 'none'}"
             + (f", sensor class {campaign.gyro['sensor_class']}" if "sensor_class" in campaign.gyro else "")]
    for stem, c in counts.items():
        kept = ""
        if c["reference_kept"] < c["rows"]:
            kept = (f", reference kept every {c['reference_interval_s']:g} s: {c['reference_kept']} samples, "
                    f"{c['rows'] - c['reference_kept']} left out between them (the gyro keeps every row)")
        lines.append(f"  {stem:<24} {c['rows']} rows at {c['rate_hz']:.6g} Hz{kept}, {c['reference_dropouts']} "
                     f"reference dropouts (all-zero quaternions, flagged invalid), {c['reference_missing']} reference "
                     f"rows missing (NaN or empty: no attitude, flagged invalid), times shifted by "
                     f"{c['time_shift_s']:+.2f} s")
        turns = []
        for mid in c["maneuvers"]:
            m = campaign.maneuver(mid)
            turn = "free motion" if m.axis is None else m.turn
            was = c.get("trimmed", {}).get(mid)
            trim = f"; from its first valid reference sample, not {was:.2f} s" if was is not None else ""
            turns.append(f"{m.id} ({turn}, {m.t_start:.2f} to {m.t_end:.2f} s{trim})")
        lines.append("    maneuvers: " + ", ".join(turns))
        for mid, t0, t1 in c.get("left_out", []):
            lines.append(f"    left out: {mid} ({t0:.2f} to {t1:.2f} s): fewer than {MIN_REFERENCE_SAMPLES} valid reference "
                         "samples in it")
        if "rests_s" in c:
            found = ", ".join(f"{a:.2f} to {b:.2f} s" for a, b in c["rests_s"]) or "none"
            lines.append(f"    rests (gyro rate within {np.rad2deg(c['rest_threshold_rad_s']):.2g} deg/s of its rest "
                         f"value over {c['rest_smooth']} samples: {rests.REST_SIGMAS:g} sd of its noise at rest, "
                         f"{', '.join(f'{np.rad2deg(v):.2g}' for v in c['rest_sigma_rad_s'])} deg/s a sample): {found}; "
                         "cut in the middle of each inner one")
            if "reference_rest_sigma_arcsec" in c:
                cross, about = c["reference_rest_sigma_arcsec"]
                shown = (f"{cross:.3g} arcsec about each axis across the boresight, {about:.3g} about it, from "
                         f"{c['reference_rest_pairs']} pairs of consecutive kept samples in the rests")
                lines.append(f"    reference at rest: {shown} (campaign.yaml states the files' together as sigma_is: white, "
                             "unless the mapping states a noise)" if c["reference_rest_white"] else
                             f"    reference at rest: {shown}, but its differences correlate {c['reference_rest_lag1']:+.2f} "
                             f"with the next (white samples give -0.5): its error is correlated over the interval kept, "
                             "so they state no noise (keep the reference less often: --reference-interval)")
        lines.append("    " + _norm_report(c))
        if "at_range" in c:
            at = ", ".join(f"{n} {k}" for n, k in c["at_range"].items() if k) or "none"
            lines.append(f"    gyro samples within {RANGE_BAND:.0%} of the declared range "
                         f"{np.rad2deg(c['gyro_range_rad_s']):.4g} deg/s: {at}"
                         + (" (the gyro clips there: validate refuses a maneuver that sits at it)" if at != "none" else ""))
    return "\n".join(lines)


def _norm_report(c: dict) -> str:
    """The import report's line on the reference quaternions of one file."""
    first = c["reference_refused_first"]
    if c["reference_precision"] == BINARY_WORDS:  # not printed: off 1 by more than UNIT_NORM_TOL is not rounding
        text = (f"reference quaternions stored as {BINARY_WORDS}: {c['reference_renormalised']} renormalised "
                f"(norm off 1 by up to {c['reference_norm_error_max']:.2g}), ")
        if first is None:
            return text + f"none off by more than {UNIT_NORM_TOL:g}"
        return text + (f"{c['reference_refused']} off by more than {UNIT_NORM_TOL:g} refused and flagged invalid; the "
                       f"first at row {first['line']}, columns {', '.join(str(k) for k in first['columns'])}: norm "
                       f"{first['norm']:.6f}")
    text = (f"reference quaternions printed to {c['reference_precision']}: {c['reference_renormalised']} renormalised "
            f"(norm off 1 by up to {c['reference_norm_error_max']:.2g}, at most {c['reference_times_rounding_max']:.2g} "
            f"times what rounding to those digits can do)")
    if first is None:
        return text + f", none off by more than {PRECISION_MARGIN:g} times"
    columns = ", ".join(str(k) for k in first["columns"])
    return (text + f", {c['reference_refused']} off by more than {PRECISION_MARGIN:g} times refused and flagged "
            f"invalid (not rounding: the source's own values, e.g. interpolated across a gap); the first at line "
            f"{first['line']}, columns {columns}: norm {first['norm']:.6f}, {first['times_rounding']:.2g} times")
