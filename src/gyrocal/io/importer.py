"""Tabular telemetry into a campaign directory (docs/interface.md section 3), driven by a mapping.

A mapping file (YAML) says where each quantity sits in a user's files and in which units:
the time column, the attitude reference's quaternion columns and their order, the gyro
columns and whether they hold rates or increments, and any extra columns to keep as
candidate regressors. Each file becomes one maneuver named after its stem; the files'
times are shifted so the maneuvers follow each other, one sample step apart (or ``gap_s``). A new format needs a mapping, not
code. gyrocal ships the mappings in ``gyrocal/io/mappings/`` (``repoimu``: the RepoIMU
T-stick recordings).

A reference faster than its noise is white (a motion-capture system filters its attitude over
several of its samples) can be kept only every ``reference.sample_interval_s`` seconds, as a
star tracker at a few Hz would give it, while the gyro keeps every row: the rows in between
are left out of ``star_tracker.csv`` and counted in the import report, never dropped silently.

Rates become increments by the trapezoidal rule, ``(w[k-1] + w[k]) / 2 * dt``: a sampled
rate is an instantaneous value, and the trapezoid integrates a rate that varies linearly
between samples with no lag; ``w[k] * dt`` would lag half a sample, 5 ms at 100 Hz, which is
1 400 arcsec at 80 deg/s.

Reference quaternions are written unit. A source prints them to a few digits, so their norm is
off 1 by what rounding those digits can do: the importer reads how many digits each quaternion
column prints (`printed_quantum`) and renormalises every quaternion whose norm error is within
`PRECISION_MARGIN` times what that rounding explains. One further off is not a rounded unit
quaternion: it is refused as a sample (flagged invalid, as a dropout is) and named with its
file, line and columns; a file where most are refused is refused whole (the columns hold no
quaternion). The import report counts both, per file.

A mapping may declare the gyro's range (``gyro.range``, in the mapping's gyro unit, per second
for increments): the report counts the samples within `RANGE_BAND` of it, where the gyro clips
(`gyrocal.checks.saturation` refuses such a maneuver).
"""

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from gyrocal.errors import excerpt
from gyrocal.io.telemetry import (
    NAME_PATTERN,
    UNIT_NORM_TOL,
    Campaign,
    Maneuver,
    TelemetryError,
    default_name,
    write_campaign,
)
from gyrocal.io.yamlfile import check_schema, read_yaml
from gyrocal.model.channels import Channel

__all__ = [
    "ANGLE_UNITS", "MOST_REFUSED", "ORDERS", "PRECISION_MARGIN", "RANGE_BAND", "RATE_UNITS", "Imported", "build_campaign",
    "declared_range_rad_s", "import_files", "maneuver_axis", "mapping_path", "printed_quantum", "read_file",
    "read_mapping", "reference_rows", "report"
]

ORDERS = {"xyzw": [0, 1, 2, 3], "wxyz": [1, 2, 3, 0]}
"""Where scalar-last ``q1..q4`` come from in each quaternion order a mapping may declare."""

RATE_UNITS = {"rad/s": 1.0, "deg/s": np.pi / 180.0}
ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}

PRECISION_MARGIN = 2.0
"""A quaternion is renormalised when its norm is off 1 by at most this many times what rounding
its printed digits can do (the norm of half a unit in the last place of each component), and
never less than `UNIT_NORM_TOL`. Twice, since a source may have rounded more than once; the
RepoIMU trials that turn slowly sit up to 1.7 times the rounding bound (their norms dip a little
below 1, as an interpolation between samples makes them); the fast one, 133 times."""
RANGE_BAND = 0.01
"""Samples within this share of a declared gyro range are counted as at the range (as
`gyrocal.checks.saturation.FLAT_BAND`)."""
MOST_REFUSED = 0.5
"""A file where more than this share of the quaternions are off unit beyond their precision is
refused whole: its reference columns hold no quaternion."""


@dataclass
class Imported:
    """One file read through a mapping, in SI, before the maneuvers are put end to end."""

    stem: str
    time: np.ndarray
    quat: np.ndarray
    """(N, 4) scalar last; rows where the reference has no value are zero."""
    valid: np.ndarray
    increments: np.ndarray
    """(N, n_channels) rad over the interval ending at each row; the first row is the start."""
    extras: dict
    rate: np.ndarray | None = None
    """(N, n_channels) rad/s as sampled, for a gyro logged as rates (None for increments). The
    Allan deviation needs the samples: the trapezoid averages neighbours, which hides half the
    white noise at a cluster of one sample."""
    lines: np.ndarray | None = None
    """(N,) each row's line in the file (the first line is 1)."""
    norm_error: np.ndarray | None = None
    """(N,) each reference quaternion's norm less 1, as read (0 where all components are zero)."""
    norm_rounding: np.ndarray | None = None
    """(N,) the largest norm error rounding to its printed digits can make (`printed_quantum`)."""
    refused: np.ndarray | None = None
    """(N,) quaternions off unit beyond that: flagged invalid, not renormalised."""
    precision: str = ""
    """How the reference quaternion columns are printed, in words ("5 significant digits")."""


def mapping_path(name_or_path) -> Path:
    """A shipped mapping by name (``repoimu``) or a user's mapping file."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        return path
    shipped = resources.files("gyrocal.io") / "mappings" / f"{name_or_path}.yaml"
    if not shipped.is_file():
        names = sorted(p.name.removesuffix(".yaml") for p in (resources.files("gyrocal.io") / "mappings").iterdir()
                       if p.name.endswith(".yaml"))
        raise TelemetryError(f"no mapping {name_or_path!r}: gyrocal ships {names}; or give a mapping file (.yaml)")
    return Path(str(shipped))


def read_mapping(name_or_path) -> dict:
    """A mapping, read by `gyrocal.io.yamlfile` and checked against its schema
    (``gyrocal/io/schemas/mapping.schema.json``: the sections, the orders, quantities, units and
    axes), then for what the schema does not say."""
    path = mapping_path(name_or_path)
    document = read_yaml(path)
    check_schema(document, "mapping")
    mapping = document.data
    gyro = mapping["gyro"]
    units = RATE_UNITS if gyro["quantity"] == "rate" else ANGLE_UNITS
    if gyro["unit"] not in units:
        raise TelemetryError(f"{path}: gyro.unit of a {gyro['quantity']} must be one of {sorted(units)}")
    _check_interval(mapping["reference"].get("sample_interval_s"), f"{path}: reference.sample_interval_s")
    unpaired = sorted(set(gyro["columns"]) ^ set(gyro["axes"]))
    if unpaired:
        raise TelemetryError.at(path, f"gyro.columns and gyro.axes must name the same channels; {unpaired} is in "
                                      "only one", f"gyro (line {document.line(['gyro'])})")
    return mapping


def read_file(path, mapping) -> Imported:
    """One file through the mapping; columns are numbered from 1, as a spreadsheet shows them."""
    path = Path(path)
    fmt = mapping["format"]
    try:
        frame = pd.read_csv(path, sep=fmt.get("delimiter", ","), skiprows=int(fmt.get("header_rows", 1)),
                            header=None, dtype=str)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise TelemetryError(f"{path}: cannot be read with this mapping: {exc}") from exc

    def column(number, what):
        if not 1 <= number <= frame.shape[1]:
            raise TelemetryError(f"{path}: the mapping's {what} is column {number}, but the file has "
                                 f"{frame.shape[1]} columns")
        values = pd.to_numeric(frame.iloc[:, number - 1], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            line = int(bad[0]) + int(fmt.get("header_rows", 1)) + 1
            raise TelemetryError(f"{path}: line {line}, column {number} ({what}): not a number: "
                                 f"{excerpt(frame.iloc[bad[0], number - 1])}")
        return values

    time = column(mapping["time"]["column"], "time")
    ref = mapping["reference"]
    raw = np.column_stack([column(c, "reference quaternion") for c in ref["columns"]])
    lines = np.arange(len(frame)) + int(fmt.get("header_rows", 1)) + 1
    quat, valid, checked = _unit_quaternions(path, raw, [frame.iloc[:, c - 1] for c in ref["columns"]], ref, lines)
    quat = quat[:, ORDERS[ref["order"]]]
    gyro = mapping["gyro"]
    names = list(gyro["columns"])
    values = np.column_stack([column(gyro["columns"][n], f"gyro {n}") for n in names])
    rate = None
    if gyro["quantity"] == "rate":
        rate = values * RATE_UNITS[gyro["unit"]]
        increments = np.zeros_like(rate)
        increments[1:] = 0.5 * (rate[1:] + rate[:-1]) * np.diff(time)[:, None]
    else:
        increments = values * ANGLE_UNITS[gyro["unit"]]
    extras = {name: column(number, f"extra {name}") for name, number in (mapping.get("extras") or {}).items()}
    return Imported(path.stem, time, quat, valid, increments, extras, rate, lines, **checked)


_NUMBER = r"^\s*[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?\s*$"
"""A number as a file prints it: whole part, decimals, exponent."""


def printed_quantum(text, values) -> tuple:
    """The unit in the last place of each value of one column as the file prints it, and the
    column's precision in words. A column printed to a fixed number of decimals (``%.4f``) has
    one unit, 10^-decimals; one printed to significant digits (``%.5g``: 0.98275, 2.4976e-006)
    has a unit that scales with each value, 10^(exponent - digits + 1). Which one is read off the
    column: the most decimals and the most significant digits any value shows; each value's unit
    is the larger of the two readings, which is the right one in either case (a value printed as
    ``1`` among 5-digit ones stands for 1.0000). In words, a column whose values all show as many
    decimals is printed to decimals, any other to significant digits."""
    parts = pd.Series(text, dtype=object).astype(str).str.extract(_NUMBER)
    whole, frac = parts[0].fillna(""), parts[1].fillna("")
    exponent = pd.to_numeric(parts[2], errors="coerce").fillna(0).to_numpy(dtype=float)
    shown = frac.str.len().to_numpy(dtype=float) - exponent
    decimals = float(shown.max())
    digits = float(max(1, (whole + frac).str.lstrip("0").str.len().max()))
    values = np.asarray(values, dtype=float)
    with np.errstate(divide="ignore"):
        by_digits = 10.0 ** (np.floor(np.log10(np.abs(values))) - digits + 1)
    if shown.min() < decimals:
        words = f"{digits:.0f} significant digit{'s' if digits != 1 else ''}"
    else:
        words = f"{decimals:.0f} decimal{'s' if decimals != 1 else ''}"
    return np.maximum(by_digits, 10.0 ** -decimals), words


def _unit_quaternions(path, raw, text, ref, lines) -> tuple:
    """The reference quaternions (in the file's order) renormalised where their printed digits
    explain their norm error, which rows are valid (not all zero, not refused), and what was
    found (`Imported`'s norm fields); a file where most are off unit beyond their precision is
    refused."""
    quanta, words = zip(*(printed_quantum(t, raw[:, i]) for i, t in enumerate(text)))
    norm = np.linalg.norm(raw, axis=1)
    present = norm > 0
    error = np.where(present, norm - 1.0, 0.0)
    rounding = np.linalg.norm(0.5 * np.column_stack(quanta), axis=1)
    tolerance = np.maximum(PRECISION_MARGIN * rounding, UNIT_NORM_TOL)
    refused = present & (np.abs(error) > tolerance)
    precision = ", ".join(dict.fromkeys(words))
    columns = ", ".join(str(c) for c in ref["columns"])
    if refused.sum() > MOST_REFUSED * max(present.sum(), 1):
        row = int(np.argmax(refused))
        raise TelemetryError.at(
            path, f"the reference quaternion's norm is {norm[row]:.6g}, off 1 by {abs(error[row]):.2g}, more than "
                  f"the {precision} printed explain ({tolerance[row]:.2g}), as are {int(refused.sum())} of the "
                  f"file's {int(present.sum())} quaternions",
            f"line {lines[row]}, columns {columns} (reference quaternion)",
            "check the mapping's reference.columns: they should hold a unit quaternion")
    quat = raw.copy()
    keep = present & ~refused
    quat[keep] /= norm[keep, None]
    return quat, keep, {"norm_error": error, "norm_rounding": rounding, "refused": refused, "precision": precision}


def declared_range_rad_s(mapping) -> float | None:
    """The gyro's range a mapping declares (``gyro.range``, in its gyro unit: a rate unit, or an
    angle unit per second for increments), in rad/s; None if it declares none."""
    gyro = mapping["gyro"]
    value = gyro.get("range")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise TelemetryError(f"the mapping's gyro.range must be a positive number (in {gyro['unit']}"
                             f"{'' if gyro['quantity'] == 'rate' else ' per second'}), got {excerpt(value)}")
    units = RATE_UNITS if gyro["quantity"] == "rate" else ANGLE_UNITS
    return float(value) * units[gyro["unit"]]


def maneuver_axis(imported: Imported, axes: list) -> str:
    """The body axis a file rotates about most (the largest total gyro rotation); ``axes`` are the
    gyro columns' axes, in their order."""
    turned = np.abs(imported.increments).sum(axis=0)
    return axes[int(np.argmax(turned))]


def _check_interval(interval_s, where: str):
    """A reference sample interval is ``None`` or a number of seconds >= 0 (0: every row)."""
    if interval_s is not None and not (isinstance(interval_s, (int, float)) and interval_s >= 0):
        raise TelemetryError(f"{where} must be a number of seconds >= 0 (0: every row), got {excerpt(interval_s)}")


def reference_rows(time, interval_s) -> np.ndarray:
    """Which rows of one file keep their reference sample when it is wanted only every
    ``interval_s`` seconds: the first row, then every row ``round(interval_s / median step)``
    after it, and the last row (so the reference spans the whole maneuver). ``0`` or ``None``:
    every row."""
    keep = np.ones(len(time), dtype=bool)
    if not interval_s:
        return keep
    every = max(1, round(interval_s / float(np.median(np.diff(time)))))
    keep[:] = False
    keep[::every] = True
    keep[-1] = True
    return keep


def build_campaign(files, mapping, name: str, reference_interval_s=None) -> tuple:
    """The campaign of ``files`` (one maneuver and one noise group each, end to end) and what was
    counted per file."""
    gyro = mapping["gyro"]
    names = list(gyro["columns"])
    axes = [gyro["axes"][n] for n in names]
    channels = tuple(Channel(n, None, a) for n, a in zip(names, axes))
    gap = mapping.get("gap_s")
    direction = (mapping.get("maneuver") or {}).get("direction", "both")
    interval = mapping["reference"].get("sample_interval_s") if reference_interval_s is None else reference_interval_s
    _check_interval(interval, "the reference sample interval")
    range_rad_s = declared_range_rad_s(mapping)
    parts, maneuvers, counts = [], [], {}
    offset = 0.0
    for f in files:
        imp = read_file(f, mapping)
        if not NAME_PATTERN.match(imp.stem):
            raise TelemetryError(f"{f}: the file's stem names its maneuver, so it may hold only letters, digits "
                                 f"and '_'")
        shift = offset - imp.time[0]
        time = imp.time + shift
        keep = reference_rows(time, interval)
        parts.append((time, imp, keep))
        maneuvers.append(Maneuver(imp.stem, maneuver_axis(imp, axes), direction, float(time[0]), float(time[-1]),
                                  noise_group=imp.stem))  # one noise level per recording
        counts[imp.stem] = {"rows": len(time), "reference_dropouts": int((~imp.valid[keep] & ~imp.refused[keep]).sum()),
                            "reference_kept": int(keep.sum()), "reference_interval_s": float(interval or 0.0),
                            "time_shift_s": float(shift), **_norm_counts(imp, keep, mapping["reference"]["columns"]),
                            **_range_counts(imp, names, range_rad_s)}
        offset = time[-1] + (float(np.median(np.diff(time))) if gap is None else float(gap))
    time = np.concatenate([t for t, _, _ in parts])
    st_time = np.concatenate([t[keep] for t, _, keep in parts])
    quat = np.concatenate([imp.quat[keep] for _, imp, keep in parts])
    valid = np.concatenate([imp.valid[keep] for _, imp, keep in parts]).astype(int)
    increments = np.concatenate([imp.increments for _, imp, _ in parts])
    columns = {n: increments[:, i] for i, n in enumerate(names)}
    for key in parts[0][1].extras:
        columns[key] = np.concatenate([imp.extras[key] for _, imp, _ in parts])
    gyro_known = dict(mapping.get("gyro_noise") or {})
    if range_rad_s is not None:
        gyro_known["range_deg_s"] = float(np.rad2deg(range_rad_s))  # validate's saturation check reads it
    campaign = Campaign(name=name, channels=channels, star_tracker=dict(mapping.get("star_tracker") or {}),
                        gyro=gyro_known, maneuvers=tuple(maneuvers), st_time=st_time,
                        st_quat=quat, st_valid=valid, gyro_time=time, gyro_columns=columns)
    return campaign, counts


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
             f"extras {', '.join(campaign.extras()) or 'none'}"]
    for m in campaign.maneuvers:
        c = counts[m.id]
        kept = ""
        if c["reference_kept"] < c["rows"]:
            kept = (f", reference kept every {c['reference_interval_s']:g} s: {c['reference_kept']} samples, "
                    f"{c['rows'] - c['reference_kept']} left out between them (the gyro keeps every row)")
        lines.append(f"  {m.id:<24} {m.direction} {m.axis:<6} {c['rows']} rows{kept}, {c['reference_dropouts']} "
                     f"reference dropouts (all-zero quaternions, flagged invalid), times shifted by "
                     f"{c['time_shift_s']:+.2f} s")
        lines.append("    " + _norm_report(c))
        if "at_range" in c:
            at = ", ".join(f"{n} {k}" for n, k in c["at_range"].items() if k) or "none"
            lines.append(f"    gyro samples within {RANGE_BAND:.0%} of the declared range "
                         f"{np.rad2deg(c['gyro_range_rad_s']):.4g} deg/s: {at}"
                         + (" (the gyro clips there: validate refuses a maneuver that sits at it)" if at != "none" else ""))
    return "\n".join(lines)


def _norm_report(c: dict) -> str:
    """The import report's line on the reference quaternions of one file."""
    text = (f"reference quaternions printed to {c['reference_precision']}: {c['reference_renormalised']} renormalised "
            f"(norm off 1 by up to {c['reference_norm_error_max']:.2g}, at most {c['reference_times_rounding_max']:.2g} "
            f"times what rounding to those digits can do)")
    first = c["reference_refused_first"]
    if first is None:
        return text + f", none off by more than {PRECISION_MARGIN:g} times"
    columns = ", ".join(str(k) for k in first["columns"])
    return (text + f", {c['reference_refused']} off by more than {PRECISION_MARGIN:g} times refused and flagged "
            f"invalid (not rounding: the source's own values, e.g. interpolated across a gap); the first at line "
            f"{first['line']}, columns {columns}: norm {first['norm']:.6f}, {first['times_rounding']:.2g} times")
