"""Campaign directories (docs/interface.md section 3): read, validate, write.

A campaign is ``campaign.yaml``, ``star_tracker.csv`` and ``gyro.csv``. Bad input is
refused with a `TelemetryError` that names the file, the row or column and what is
wrong; rows are counted as in a spreadsheet: the header is line 1.
"""

import hashlib
import io
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from gyrocal.errors import OutputError, excerpt
from gyrocal.io.campaign_yaml import (
    CHANNEL_PATTERN,
    DEFAULT_NOISE_GROUP,
    NAME_PATTERN,
    NORM_REFUSE_TOL,
    Maneuver,
    TelemetryError,
    default_name,
    fail,
    read_meta,
)

__all__ = ["MIN_REFERENCE_SAMPLES", "NAME_PATTERN", "QUAT_COLUMNS", "UNIT_NORM_TOL", "Campaign", "Maneuver",
           "TelemetryError", "checksums", "default_name", "read_campaign", "read_meta", "summary", "write_campaign"]

QUAT_COLUMNS = ["q1", "q2", "q3", "q4"]
UNIT_NORM_TOL = 1e-6
"""Quaternions whose norm is further than this from 1 are renormalised and counted."""
MIN_REFERENCE_SAMPLES = 10
"""Valid reference samples a maneuver needs: its initial attitude, its biases and something to compare."""


READ_CSV_EXACT = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
"""pandas 3 parses floats exactly by default; pandas 2 needs asking (and 3 deprecates asking)."""


@dataclass
class Campaign:
    name: str
    channels: tuple
    star_tracker: dict
    gyro: dict
    maneuvers: tuple
    st_time: np.ndarray
    st_quat: np.ndarray
    st_valid: np.ndarray
    gyro_time: np.ndarray
    gyro_columns: dict = field(default_factory=dict)
    """Every non-time column of ``gyro.csv``: the channels, then any extras."""
    source: Path = None
    lines: dict = field(default_factory=dict)
    """Per file name, the line of each data row (the header is line 1), for messages."""
    st_renormalised: int = 0
    """Valid star-tracker quaternions whose written norm was off 1 by more than `UNIT_NORM_TOL`."""

    @property
    def channel_names(self) -> list:
        return [c.name for c in self.channels]

    def increments(self, rows=slice(None)) -> np.ndarray:
        """(N, n_channels) raw incremental angles (rad) of ``rows``, in channel order."""
        return np.column_stack([self.gyro_columns[c.name][rows] for c in self.channels])

    def extras(self) -> dict:
        """Extra ``gyro.csv`` columns (e.g. temperatures): candidate regressors."""
        names = set(self.channel_names)
        return {k: v for k, v in self.gyro_columns.items() if k not in names}

    def maneuver(self, maneuver_id: str) -> Maneuver:
        for m in self.maneuvers:
            if m.id == maneuver_id:
                return m
        raise KeyError(f"campaign {self.name} has no maneuver {maneuver_id!r}")

    def to_yaml_dict(self) -> dict:
        return {
            "name": self.name,
            "channels": {c.name: {**({"dtg": c.dtg} if c.dtg is not None else {}), "axis": c.axis}
                         for c in self.channels},
            "star_tracker": dict(self.star_tracker),
            "gyro": dict(self.gyro),
            "maneuvers": [{"id": m.id, **({} if m.free else {"axis": m.axis, "direction": m.direction}),
                           "t_start": float(m.t_start), "t_end": float(m.t_end),
                           **({"in_loop": list(m.in_loop)} if m.in_loop else {}),
                           **({"noise_group": m.noise_group} if m.noise_group != DEFAULT_NOISE_GROUP else {})}
                          for m in self.maneuvers],
        }


def _read_csv(path, required, max_bytes=None) -> pd.DataFrame:
    """Read a CSV whose every cell is a number; ``frame.attrs["lines"]`` holds each row's line in
    the file (the header is line 1; blank lines, which pandas skips, still count)."""
    if not path.exists():
        fail(path, "file not found")
    if not path.is_file():
        fail(path, "is not a file (a directory?)", todo=f"put the {path.name} file itself at this path")
    if max_bytes is not None:
        _check_size(path, max_bytes)
    text = _decode(path, path.read_bytes())
    try:
        frame = pd.read_csv(io.StringIO(text), **READ_CSV_EXACT)
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        fail(path, f"cannot be read as CSV: {excerpt(str(exc), 200)}")
    header = text.splitlines()[0] if text.strip() else ""
    _check_delimiter(path, header)
    _check_header(path, header)
    kept = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()][1:]
    frame.attrs["lines"] = np.array([i for i, _ in kept])[:len(frame)]
    frame.attrs["fields"] = np.array([line.count(",") + 1 for _, line in kept])[:len(frame)]
    missing = [c for c in required if c not in frame.columns]
    if missing:
        fail(path, f"missing column(s) {missing}; found {list(frame.columns)}")
    if len(frame) < 2:
        fail(path, "needs at least two data rows")
    for column in frame.columns:
        if not pd.api.types.is_numeric_dtype(frame[column]):
            bad = pd.to_numeric(frame[column], errors="coerce").isna() & frame[column].notna()
            row = int(np.flatnonzero(bad.to_numpy())[0])
            line = frame.attrs["lines"][row]
            if kept[row][1].strip() == header.strip():
                fail(path, "repeats the header (two files joined?)", where=f"line {line}",
                     todo="keep one header line, on line 1")
            fail(path, f"line {line}, column '{column}': not a number: {excerpt(frame[column].iloc[row])}")
    return frame


BYTE_ORDER_MARKS = ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"),
                    (b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16"))
"""Wide encodings by their byte-order mark, UTF-32's first: its little-endian mark begins with UTF-16's."""


def _wide_encoding(raw: bytes) -> str:
    """The wide encoding a file's first bytes show ('' if none): by its byte-order mark, or by NUL
    bytes, which text in UTF-8 never holds (every other byte NUL in UTF-16, three of four in UTF-32)."""
    for mark, name in BYTE_ORDER_MARKS:
        if raw.startswith(mark):
            return f"{name} text (its byte-order mark)"
    head = raw[:4096]
    if b"\x00" not in head:
        return ""
    name = "UTF-32" if head.count(0) > len(head) // 2 else "UTF-16"
    return f"{name} text (NUL bytes at its start)"


def _decode(path, raw: bytes) -> str:
    """The file's text: UTF-8 (a leading byte-order mark is dropped); UTF-16, UTF-32 or other bytes
    are refused with what to do."""
    wide = _wide_encoding(raw)
    if wide:
        fail(path, f"is {wide}, not UTF-8",
             where="line 1", todo="save it as UTF-8 (in a spreadsheet: CSV UTF-8, comma-separated)")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        fail(path, f"is not UTF-8 text (byte {exc.start}: {raw[exc.start:exc.start + 1]!r})", where=f"line {line}",
             todo="save it as UTF-8")


DELIMITERS = {";": "';'", "\t": "a tab", "|": "'|'"}


def _check_delimiter(path, header: str):
    """A header with no comma but another separator: a CSV saved with a locale's separator."""
    if "," in header:
        return
    for sep, name in DELIMITERS.items():
        if sep in header:
            fail(path, f"separates its columns with {name}, not commas: {excerpt(header)}", where="line 1",
                 todo="save it comma-separated, with decimal points")


READ_FLOOR_BYTES = 256 * 2**20
"""A CSV up to this size is read whole (about twice its size in memory); a larger one only when the
declared rate and the maneuvers' span need it (`size_cap`)."""

MARGIN_S = 6 * 3600.0
"""Data a campaign file may hold beyond its maneuvers, either side (a whole recording day's share)."""


def size_cap(path, rate_hz, maneuvers) -> tuple:
    """The most bytes ``path`` may hold, and the rate and span that judge it: `READ_FLOOR_BYTES`, or
    what its rate (``rate_hz``, declared; else its first rows' median step) over the maneuvers' span
    and `MARGIN_S` either side needs, at twice its first rows' length per row; read from its first
    64 KiB only."""
    with open(path, "rb") as handle:
        head = handle.read(2**16).splitlines()[1:-1]
    rows = [line.split(b",")[0] for line in head if line.strip()]
    try:
        times = np.array([float(t) for t in rows])
    except ValueError:
        return READ_FLOOR_BYTES  # the full read names the bad cell
    if rate_hz is None:
        steps = np.diff(times)
        steps = steps[steps > 0]
        rate_hz = 1.0 / float(np.median(steps)) if steps.size else 1.0
    span = max(m.t_end for m in maneuvers) - min(m.t_start for m in maneuvers) + 2 * MARGIN_S if maneuvers else MARGIN_S
    per_row = 2.0 * max(np.mean([len(line) + 1 for line in head]) if head else 200.0, 1.0)
    return int(max(READ_FLOOR_BYTES, rate_hz * 1.01 * span * per_row)), rate_hz, span


def _check_size(path, cap):
    """Refuse a file larger than ``cap`` (`size_cap`) before reading it."""
    limit, rate_hz, span = cap
    size = path.stat().st_size
    if size > limit:
        fail(path, f"is {size / 2**30:.2f} GiB, more than a campaign needs: at {rate_hz:.4g} Hz over the maneuvers' "
                   f"span and {MARGIN_S / 3600:g} h either side ({span:.0f} s) it holds at most {limit / 2**20:.0f} MiB",
             todo="cut it to the maneuvers' windows (with a margin), or split the campaign")


def _check_header(path, header: str):
    """Every column of the header named, once: a trailing comma or an empty name would shift the
    columns pandas reads (the first becoming the index), and a repeated name would be renamed."""
    names = [name.strip() for name in header.split(",")]
    if "" in names:
        fail(path, f"column {names.index('') + 1} of the header has no name (a trailing or doubled comma?): "
                   f"{excerpt(header)}", where="line 1")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        fail(path, f"the header names column(s) {repeated} more than once: {excerpt(header)}", where="line 1")


def _check_finite(path, frame, columns, rows=None):
    values = frame[columns].to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if rows is not None:
        bad &= rows[:, None]
    if bad.any():
        row, col = np.argwhere(bad)[0]
        line, fields = frame.attrs["lines"][row], frame.attrs["fields"][row]
        if fields < frame.shape[1]:
            fail(path, f"line {line} has {fields} of the header's {frame.shape[1]} fields (a short or truncated "
                        f"row): column '{columns[col]}' has no value")
        fail(path, f"line {line}, column '{columns[col]}': value is NaN or infinite")


MAX_EXTRA_ABS = 1e12
"""No reading a regressor can use (a temperature, a voltage, a current, in any unit) is this large: an
extra column's value beyond it is a corrupt cell, and squared in the regression it would overflow."""


def _check_extras(path, frame, columns):
    """Extra columns (candidate regressors) hold plausible readings: within `MAX_EXTRA_ABS`."""
    for column in columns:
        values = frame[column].to_numpy(dtype=float)
        bad = np.flatnonzero(np.abs(values) > MAX_EXTRA_ABS)
        if bad.size:
            fail(path, f"line {frame.attrs['lines'][bad[0]]}, column '{column}': {values[bad[0]]:.6g} is larger than "
                       f"any reading a regressor can use ({MAX_EXTRA_ABS:g}; {bad.size} such row(s)): a corrupt cell",
                 todo="correct the cell, or remove the column")


def _check_time(path, frame):
    time = frame["time"].to_numpy(dtype=float)
    steps = np.diff(time)
    if (steps <= 0).any():
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        fail(path, f"line {frame.attrs['lines'][row]}, column 'time': time {time[row]} does not increase "
                    f"(line {frame.attrs['lines'][row - 1]} has {time[row - 1]})")
    return time


def _check_overlap(spath, st_time, gpath, gyro_time):
    """The two files' times must overlap: where they do not, one clock is offset (a different epoch,
    another unit) and no maneuver window can hold both; named before any maneuver is blamed."""
    if st_time[0] <= gyro_time[-1] and gyro_time[0] <= st_time[-1]:
        return
    later, earlier = (gpath, spath) if gyro_time[0] > st_time[-1] else (spath, gpath)
    gap = max(gyro_time[0] - st_time[-1], st_time[0] - gyro_time[-1])
    fail(gpath, f"its times [{gyro_time[0]:.10g}, {gyro_time[-1]:.10g}] s and {spath.name}'s "
                f"[{st_time[0]:.10g}, {st_time[-1]:.10g}] s do not overlap: {later.name} starts {gap:.6g} s after "
                f"{earlier.name} ends, a time offset between the two clocks (another epoch or unit?)",
         where="column 'time'", todo="give both files' times in seconds on one clock")


def _cap(path, section, maneuvers):
    """`size_cap` of a campaign file that is larger than `READ_FLOOR_BYTES`, or None (read it whole)."""
    if not path.is_file() or path.stat().st_size <= READ_FLOOR_BYTES:
        return None
    return size_cap(path, (section or {}).get("rate_hz"), maneuvers)


def read_campaign(directory) -> Campaign:
    """Read and validate a campaign directory (docs/interface.md section 3)."""
    directory = Path(directory)
    meta = read_meta(directory)
    cpath = directory / "campaign.yaml"
    channels, maneuvers = meta["channels"], meta["maneuvers"]
    names = [c.name for c in channels]

    spath = directory / "star_tracker.csv"
    st = _read_csv(spath, ["time"] + QUAT_COLUMNS, _cap(spath, meta["star_tracker"], maneuvers))
    unknown = set(st.columns) - {"time", "valid", *QUAT_COLUMNS}
    if unknown:
        fail(spath, f"unknown column(s) {sorted(unknown)}; expected time, q1..q4 and optional valid")
    _check_finite(spath, st, ["time"])
    valid = np.ones(len(st), dtype=int)
    if "valid" in st.columns:
        raw_valid = st["valid"].to_numpy(dtype=float)
        bad = ~np.isin(raw_valid, [0.0, 1.0])
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            fail(spath, f"line {st.attrs['lines'][row]}, column 'valid': must be 0 or 1, got {raw_valid[row]:g}")
        valid = raw_valid.astype(int)
    if not valid.any():
        fail(spath, "no sample is valid (every row has valid = 0): there is no reference to calibrate against",
             where="column 'valid'")
    _check_finite(spath, st, QUAT_COLUMNS, rows=valid == 1)
    st_time = _check_time(spath, st)
    quat = st[QUAT_COLUMNS].to_numpy(dtype=float)
    with np.errstate(over="ignore"):  # a huge component is refused below, by its norm
        norm = np.linalg.norm(quat, axis=1)
    bad = (np.abs(norm - 1.0) > NORM_REFUSE_TOL) & (valid == 1)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        fail(spath, f"line {st.attrs['lines'][row]}, columns q1..q4: quaternion norm is {norm[row]:.9f}, "
                     f"not 1 (tolerance {NORM_REFUSE_TOL}; an invalid sample needs valid=0)")
    renormalised = (np.abs(norm - 1.0) > UNIT_NORM_TOL) & (valid == 1)
    quat[renormalised] /= norm[renormalised, None]

    gpath = directory / "gyro.csv"
    gy = _read_csv(gpath, ["time"] + names, _cap(gpath, meta["gyro"], maneuvers))
    unknown_channels = [c for c in gy.columns if CHANNEL_PATTERN.match(c) and c not in names]
    if unknown_channels:
        fail(gpath, f"column(s) {unknown_channels} look like gyro channels but campaign.yaml "
                     f"does not declare them (channels: {names})")
    _check_finite(gpath, gy, list(gy.columns))
    _check_extras(gpath, gy, [c for c in gy.columns if c != "time" and c not in names])
    gyro_time = _check_time(gpath, gy)

    _check_overlap(spath, st_time, gpath, gyro_time)
    for m in maneuvers:
        lo = max(st_time[0], gyro_time[0])
        hi = min(st_time[-1], gyro_time[-1])
        if m.t_start < lo or m.t_end > hi:
            fail(cpath, f"maneuver {m.id}: [{m.t_start}, {m.t_end}] s lies outside the data, "
                         f"which cover [{lo}, {hi}] s in both star_tracker.csv and gyro.csv "
                         f"(star_tracker.csv: [{st_time[0]}, {st_time[-1]}] s; gyro.csv: "
                         f"[{gyro_time[0]}, {gyro_time[-1]}] s)")

    columns = {c: gy[c].to_numpy(dtype=float) for c in gy.columns if c != "time"}
    return Campaign(
        name=meta["name"], channels=channels,
        star_tracker=meta["star_tracker"], gyro=meta["gyro"], maneuvers=maneuvers,
        st_time=st_time, st_quat=quat, st_valid=valid,
        gyro_time=gyro_time, gyro_columns=columns, source=directory,
        lines={"star_tracker.csv": st.attrs["lines"], "gyro.csv": gy.attrs["lines"]},
        st_renormalised=int(renormalised.sum()))


def write_campaign(campaign: Campaign, directory) -> Path:
    """Write a campaign directory whole or not at all (a temporary directory is renamed)."""
    directory = Path(directory)
    directory.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", dir=directory.parent))
    try:
        (tmp / "campaign.yaml").write_text(yaml.safe_dump(campaign.to_yaml_dict(), sort_keys=False))
        st = pd.DataFrame({"time": campaign.st_time})
        for i, c in enumerate(QUAT_COLUMNS):
            st[c] = campaign.st_quat[:, i]
        st["valid"] = campaign.st_valid.astype(int)
        st.to_csv(tmp / "star_tracker.csv", index=False, float_format="%.17g")
        gy = pd.DataFrame({"time": campaign.gyro_time, **campaign.gyro_columns})
        gy.to_csv(tmp / "gyro.csv", index=False, float_format="%.17g")
        tmp.chmod(0o755)
        if directory.exists():
            shutil.rmtree(directory)
        tmp.rename(directory)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(directory, exc) from exc
        raise
    return directory


def checksums(directory) -> dict:
    """SHA-256 of each campaign file, so a report can be traced to its input."""
    directory = Path(directory)
    return {name: hashlib.sha256((directory / name).read_bytes()).hexdigest()
            for name in ("campaign.yaml", "star_tracker.csv", "gyro.csv")}


def summary(campaign: Campaign) -> str:
    """The short text ``gyrocal validate`` prints."""
    dt_g = np.median(np.diff(campaign.gyro_time))
    dt_s = np.median(np.diff(campaign.st_time))
    lines = [
        f"campaign {campaign.name}: OK",
        f"  channels   {', '.join(campaign.channel_names)}",
        f"  extras     {', '.join(campaign.extras()) or 'none'}",
        f"  gyro       {len(campaign.gyro_time)} rows at {1 / dt_g:.3g} Hz, "
        f"{campaign.gyro_time[0]:.1f} to {campaign.gyro_time[-1]:.1f} s",
        f"  star trk   {len(campaign.st_time)} rows at {1 / dt_s:.3g} Hz, "
        f"{int((campaign.st_valid == 0).sum())} flagged invalid",
        f"  duration   {campaign.gyro_time[-1] - campaign.gyro_time[0]:.1f} s",
        f"  maneuvers  {len(campaign.maneuvers)}",
    ]
    for m in campaign.maneuvers:
        lines.append(f"    {m.id:<12} {m.turn:<7} {m.t_start:10.1f} to {m.t_end:10.1f} s "
                     f"({m.t_end - m.t_start:.0f} s)")
    return "\n".join(lines)
