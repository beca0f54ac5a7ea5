"""One recording read through a mapping (`gyrocal.io.mapping`), in SI, before it joins a campaign.

Rates become increments by the trapezoidal rule, ``(w[k-1] + w[k]) / 2 * dt``: a sampled
rate is an instantaneous value, and the trapezoid integrates a rate that varies linearly
between samples with no lag; ``w[k] * dt`` would lag half a sample, 5 ms at 100 Hz, which is
1 400 arcsec at 80 deg/s.

Reference quaternions are written unit. A source prints them to a few digits, so their norm is
off 1 by what rounding those digits can do: the importer reads how many digits each quaternion
column prints (`gyrocal.io.readers.printed_quantum`; a binary file's floats, their spacing) and
renormalises every quaternion whose norm error is within `PRECISION_MARGIN` times what that
rounding explains (and never less than `UNIT_NORM_TOL`). One further off is not a rounded unit
quaternion: it is refused as a sample (flagged invalid, as a dropout is) and named with its
file, line and columns; a file where most are refused is refused whole (the columns hold no
quaternion). A reference row with a missing value (NaN, an empty cell: a motion-capture system
that lost its markers) has no quaternion: it is flagged invalid too, and counted apart.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gyrocal.io import readers
from gyrocal.io.mapping import ANGLE_UNITS, ORDERS, RATE_UNITS, extra, variable, variables
from gyrocal.io.telemetry import UNIT_NORM_TOL, TelemetryError

__all__ = ["MOST_REFUSED", "PRECISION_MARGIN", "Imported", "file_time", "maneuver_axis", "read_file"]

PRECISION_MARGIN = 2.0
"""A quaternion is renormalised when its norm is off 1 by at most this many times what rounding
its printed digits can do (the norm of half a unit in the last place of each component), and
never less than `UNIT_NORM_TOL`. Twice, since a source may have rounded more than once; the
RepoIMU trials that turn slowly sit up to 1.7 times the rounding bound (their norms dip a little
below 1, as an interpolation between samples makes them); the fast one, 133 times."""
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
    missing: np.ndarray | None = None
    """(N,) reference rows with a missing value (NaN, an empty cell: occluded markers): invalid."""
    rate_hz: float | None = None
    """The sampling rate the rows are counted at, where the mapping reads the time off a rate."""


def file_time(table: readers.Table, time: dict) -> tuple:
    """Each row's time in seconds, and the sampling rate it was counted at (or None): a column, or
    the rows counted at a rate (``rate_hz``, or a variable of the file holding it, ``rate_variable``)."""
    if "rate_hz" in time or "rate_variable" in time:
        rate = float(time["rate_hz"]) if "rate_hz" in time else table.scalar(time["rate_variable"], "sampling rate")
        return np.arange(table.rows) / rate, rate
    values = table.column(variable(time), int(time.get("column", 1)), "time")
    step = np.diff(values)
    if (step <= 0).any():
        row = int(np.flatnonzero(step <= 0)[0]) + 1
        raise TelemetryError.at(table.path, f"the time {values[row]:.9g} s does not increase (the row before holds "
                                            f"{values[row - 1]:.9g} s)", table.where(variable(time), row,
                                                                                      int(time.get("column", 1)), "time"),
                                "sort the rows by time and drop repeated ones")
    return values, None


def read_file(path, mapping) -> Imported:
    """One file through the mapping (`gyrocal.io.readers`: CSV, MAT or HDF5); columns are numbered
    from 1, as a spreadsheet shows them. A reference row with a missing value (NaN, an empty
    cell) has no quaternion: it is flagged invalid and counted, not refused."""
    path = Path(path)
    table = readers.read_table(path, mapping["format"], variables(mapping))
    if table.kind != "csv":
        table.sampled_as(variable(mapping["gyro"]), "gyro")
    time, rate_hz = file_time(table, mapping["time"])
    ref = mapping["reference"]
    where = variable(ref)
    raw = np.column_stack([table.column(where, c, "reference quaternion", missing_ok=True) for c in ref["columns"]])
    lines = table.lines()
    quat, valid, checked = _unit_quaternions(path, raw, [table.printed(where, c) for c in ref["columns"]], ref, lines)
    quat = quat[:, ORDERS[ref["order"]]]
    gyro = mapping["gyro"]
    names = list(gyro["columns"])
    values = np.column_stack([table.column(variable(gyro), gyro["columns"][n], f"gyro {n}") for n in names])
    rate = None
    if gyro["quantity"] == "rate":
        rate = values * RATE_UNITS[gyro["unit"]]
        increments = np.zeros_like(rate)
        increments[1:] = 0.5 * (rate[1:] + rate[:-1]) * np.diff(time)[:, None]
    else:
        increments = values * ANGLE_UNITS[gyro["unit"]]
    extras = {name: table.column(*extra(spec), f"extra {name}") for name, spec in (mapping.get("extras") or {}).items()}
    return Imported(path.stem, time, quat, valid, increments, extras, rate, lines, **checked, rate_hz=rate_hz)


def _unit_quaternions(path, raw, text, ref, lines) -> tuple:
    """The reference quaternions (in the file's order) renormalised where their printed digits
    explain their norm error (a binary file's, its floats' spacing), which rows are valid (no
    missing value, not all zero, not refused), and what was found (`Imported`'s norm fields); a
    file where most are off unit beyond their precision is refused."""
    missing = np.isnan(raw).any(axis=1)
    raw = np.where(missing[:, None], 0.0, raw)
    quanta, words = [], []
    for i, t in enumerate(text):
        quantum = np.zeros(len(raw))
        quantum[~missing], word = readers.printed_quantum(None if t is None else t[~missing], raw[~missing, i])
        quanta.append(quantum)
        words.append(word)
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
        place = f"line {lines[row]}" if variable(ref) is None else f"variable {variable(ref)}, row {lines[row]}"
        raise TelemetryError.at(
            path, f"the reference quaternion's norm is {norm[row]:.6g}, off 1 by {abs(error[row]):.2g}, more than "
                  f"the {precision} printed explain ({tolerance[row]:.2g}), as are {int(refused.sum())} of the "
                  f"file's {int(present.sum())} quaternions",
            f"{place}, columns {columns} (reference quaternion)",
            "check the mapping's reference.columns: they should hold a unit quaternion")
    quat = raw.copy()
    keep = present & ~refused
    quat[keep] /= norm[keep, None]
    return quat, keep, {"norm_error": error, "norm_rounding": rounding, "refused": refused, "precision": precision,
                        "missing": missing}


def maneuver_axis(increments: np.ndarray, axes: list) -> str:
    """The body axis a stretch of gyro increments rotates about most: the largest excursion of its
    cumulative rotation (peak to peak), the measure `gyrocal validate` holds a label against, so that a
    trial which turns whole turns about one axis while it shakes about another is labelled by the turns;
    ``axes`` are the gyro columns' axes, in their order."""
    excursion = np.ptp(np.cumsum(np.asarray(increments, dtype=float), axis=0), axis=0)
    return axes[int(np.argmax(excursion))]
