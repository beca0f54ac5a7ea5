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
"""

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from gyrocal.io.telemetry import NAME_PATTERN, Campaign, Maneuver, TelemetryError, default_name, write_campaign
from gyrocal.model.channels import Channel
from gyrocal.model.units import AXES

__all__ = [
    "ANGLE_UNITS", "ORDERS", "RATE_UNITS", "Imported", "build_campaign", "import_files", "maneuver_axis", "mapping_path",
    "read_file", "read_mapping", "reference_rows", "report"
]

ORDERS = {"xyzw": [0, 1, 2, 3], "wxyz": [1, 2, 3, 0]}
"""Where scalar-last ``q1..q4`` come from in each quaternion order a mapping may declare."""

RATE_UNITS = {"rad/s": 1.0, "deg/s": np.pi / 180.0}
ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}


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
    path = mapping_path(name_or_path)
    mapping = yaml.safe_load(path.read_text())
    required = {"format", "time", "reference", "gyro"}
    if not isinstance(mapping, dict) or required - set(mapping):
        raise TelemetryError(f"{path}: a mapping needs the sections {sorted(required)}")
    if mapping["reference"].get("order") not in ORDERS:
        raise TelemetryError(f"{path}: reference.order must be one of {sorted(ORDERS)}")
    gyro = mapping["gyro"]
    if gyro.get("quantity") not in ("rate", "increment"):
        raise TelemetryError(f"{path}: gyro.quantity must be rate or increment")
    units = RATE_UNITS if gyro["quantity"] == "rate" else ANGLE_UNITS
    if gyro.get("unit") not in units:
        raise TelemetryError(f"{path}: gyro.unit of a {gyro['quantity']} must be one of {sorted(units)}")
    _check_interval(mapping["reference"].get("sample_interval_s"), f"{path}: reference.sample_interval_s")
    for name, axis in gyro.get("axes", {}).items():
        if axis not in AXES:
            raise TelemetryError(f"{path}: gyro.axes.{name} must be one of {list(AXES)}")
    return mapping


def read_file(path, mapping) -> Imported:
    """One file through the mapping; columns are numbered from 1, as a spreadsheet shows them."""
    path = Path(path)
    fmt = mapping["format"]
    try:
        frame = pd.read_csv(path, sep=fmt.get("delimiter", ","), skiprows=int(fmt.get("header_rows", 1)),
                            header=None)
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
                                 f"{frame.iloc[bad[0], number - 1]!r}")
        return values

    time = column(mapping["time"]["column"], "time")
    ref = mapping["reference"]
    raw = np.column_stack([column(c, "reference quaternion") for c in ref["columns"]])
    quat = raw[:, ORDERS[ref["order"]]]
    valid = np.linalg.norm(quat, axis=1) > 0
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
    return Imported(path.stem, time, quat, valid, increments, extras, rate)


def maneuver_axis(imported: Imported, axes: list) -> str:
    """The body axis a file rotates about most (the largest total gyro rotation); ``axes`` are the
    gyro columns' axes, in their order."""
    turned = np.abs(imported.increments).sum(axis=0)
    return axes[int(np.argmax(turned))]


def _check_interval(interval_s, where: str):
    """A reference sample interval is ``None`` or a number of seconds >= 0 (0: every row)."""
    if interval_s is not None and not (isinstance(interval_s, (int, float)) and interval_s >= 0):
        raise TelemetryError(f"{where} must be a number of seconds >= 0 (0: every row), got {interval_s!r}")


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
    """The campaign of ``files`` (one maneuver each, end to end) and what was counted per file."""
    gyro = mapping["gyro"]
    names = list(gyro["columns"])
    axes = [gyro["axes"][n] for n in names]
    channels = tuple(Channel(n, None, a) for n, a in zip(names, axes))
    gap = mapping.get("gap_s")
    direction = (mapping.get("maneuver") or {}).get("direction", "both")
    interval = mapping["reference"].get("sample_interval_s") if reference_interval_s is None else reference_interval_s
    _check_interval(interval, "the reference sample interval")
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
        maneuvers.append(Maneuver(imp.stem, maneuver_axis(imp, axes), direction, float(time[0]), float(time[-1])))
        counts[imp.stem] = {"rows": len(time), "reference_dropouts": int((~imp.valid[keep]).sum()),
                            "reference_kept": int(keep.sum()), "reference_interval_s": float(interval or 0.0),
                            "time_shift_s": float(shift)}
        offset = time[-1] + (float(np.median(np.diff(time))) if gap is None else float(gap))
    time = np.concatenate([t for t, _, _ in parts])
    st_time = np.concatenate([t[keep] for t, _, keep in parts])
    quat = np.concatenate([imp.quat[keep] for _, imp, keep in parts])
    valid = np.concatenate([imp.valid[keep] for _, imp, keep in parts]).astype(int)
    increments = np.concatenate([imp.increments for _, imp, _ in parts])
    columns = {n: increments[:, i] for i, n in enumerate(names)}
    for key in parts[0][1].extras:
        columns[key] = np.concatenate([imp.extras[key] for _, imp, _ in parts])
    campaign = Campaign(name=name, channels=channels, star_tracker=dict(mapping.get("star_tracker") or {}),
                        gyro=dict(mapping.get("gyro_noise") or {}), maneuvers=tuple(maneuvers), st_time=st_time,
                        st_quat=quat, st_valid=valid, gyro_time=time, gyro_columns=columns)
    return campaign, counts


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
    return "\n".join(lines)
