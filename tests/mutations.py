"""Corrupted copies of a valid campaign: what real telemetry does to a campaign directory.

Each mutation takes a copy of a campaign directory and changes it in place. The tests run
every one through `gyrocal validate` and `snakemake`; run this file to print what each
case gets (``python tests/mutations.py CAMPAIGN_DIR``).
"""

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

CHANNEL_PREFIX = "dtg"


def _read(d, name):
    return pd.read_csv(d / name)


def _write(frame, d, name):
    frame.to_csv(d / name, index=False, float_format="%.17g")


def _meta(d):
    return yaml.safe_load((d / "campaign.yaml").read_text())


def _write_meta(d, meta):
    (d / "campaign.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def _maneuver(meta, mid):
    return next(m for m in meta["maneuvers"] if m["id"] == mid)


def _channels(frame):
    return [c for c in frame.columns if c.startswith(CHANNEL_PREFIX)]


def _rotation_span(d, mid):
    """Times where the maneuver's gyro rates exceed half their peak."""
    meta = _meta(d)
    m = _maneuver(meta, mid)
    gy = _read(d, "gyro.csv")
    window = gy[(gy.time >= m["t_start"]) & (gy.time <= m["t_end"])]
    rate = window[_channels(gy)].abs().max(axis=1)
    moving = window.time[rate > 0.5 * rate.max()]
    return float(moving.iloc[0]), float(moving.iloc[-1])


def gyro_scale(factor):
    def mutate(d):
        gy = _read(d, "gyro.csv")
        gy[_channels(gy)] *= factor
        _write(gy, d, "gyro.csv")
    return mutate


def gyro_rates(d):
    gy = _read(d, "gyro.csv")
    dt = np.median(np.diff(gy.time))
    gy[_channels(gy)] /= dt
    _write(gy, d, "gyro.csv")


def gyro_cumulative(d):
    gy = _read(d, "gyro.csv")
    gy[_channels(gy)] = gy[_channels(gy)].cumsum()
    _write(gy, d, "gyro.csv")


def gyro_gap(seconds):
    def mutate(d):
        t0, t1 = _rotation_span(d, "yaw_pos")
        start = 0.5 * (t0 + t1) - 0.5 * seconds
        gy = _read(d, "gyro.csv")
        _write(gy[(gy.time < start) | (gy.time > start + seconds)], d, "gyro.csv")
    return mutate


def scalar_first(d):
    st = _read(d, "star_tracker.csv")
    st[["q1", "q2", "q3", "q4"]] = st[["q4", "q1", "q2", "q3"]].to_numpy()
    _write(st, d, "star_tracker.csv")


def st_clock_offset(seconds):
    def mutate(d):
        st = _read(d, "star_tracker.csv")
        st["time"] += seconds
        _write(st, d, "star_tracker.csv")
    return mutate


def overlapping(d):
    meta = _meta(d)
    first, second = meta["maneuvers"][:2]
    second["t_start"] = first["t_end"] - 0.25 * (first["t_end"] - first["t_start"])
    _write_meta(d, meta)


def wrong_axis(d):
    meta = _meta(d)
    _maneuver(meta, "yaw_pos")["axis"] = "roll"
    _write_meta(d, meta)


def wrong_direction(d):
    meta = _meta(d)
    _maneuver(meta, "yaw_pos")["direction"] = "-"
    _write_meta(d, meta)


def no_rotation(d):
    meta = _meta(d)
    m = _maneuver(meta, "yaw_pos")
    t0, _ = _rotation_span(d, "yaw_pos")
    m["t_end"] = float(t0 - 0.2 * (t0 - m["t_start"]))
    _write_meta(d, meta)


def no_hold(d):
    meta = _meta(d)
    m = _maneuver(meta, "yaw_pos")
    t0, t1 = _rotation_span(d, "yaw_pos")
    m["t_start"], m["t_end"] = t0 + 1.0, t1 - 1.0
    _write_meta(d, meta)


def drop_maneuver(mid):
    def mutate(d):
        meta = _meta(d)
        meta["maneuvers"] = [m for m in meta["maneuvers"] if m["id"] != mid]
        _write_meta(d, meta)
    return mutate


def st_outliers(d, sizes_arcsec=(350, 450, 550, 650, 800), seed=3):
    """Five wrong star identifications: samples turned by hundreds of arcsec about random axes."""
    from scipy.spatial.transform import Rotation
    st = _read(d, "star_tracker.csv")
    rng = np.random.default_rng(seed)
    meta = _meta(d)
    rows = []
    for k, size in enumerate(sizes_arcsec):
        m = meta["maneuvers"][k % len(meta["maneuvers"])]
        inside = np.flatnonzero((st.time > m["t_start"] + 30) & (st.time < m["t_end"] - 30) & (st.get("valid", 1) == 1))
        row = int(rng.choice(inside))
        axis = rng.normal(size=3)
        turn = Rotation.from_rotvec(np.deg2rad(size / 3600) * axis / np.linalg.norm(axis))
        q = Rotation.from_quat(st.loc[row, ["q1", "q2", "q3", "q4"]].to_numpy(dtype=float)) * turn
        st.loc[row, ["q1", "q2", "q3", "q4"]] = q.as_quat()
        rows.append(row + 2)
    _write(st, d, "star_tracker.csv")
    return rows


def st_excursion(d, size_arcsec=2000.0, duration_s=2.0):
    """A reference excursion: for ``duration_s`` in the middle of the first maneuver the star
    tracker's attitude sits ``size_arcsec`` off about its cross axis, then comes back (a motion-
    capture marker swap, a filter holding a wrong attitude). Returns the lines it turned."""
    from scipy.spatial.transform import Rotation
    st = _read(d, "star_tracker.csv")
    m = _meta(d)["maneuvers"][0]
    middle = 0.5 * (m["t_start"] + m["t_end"])
    rows = np.flatnonzero((st.time >= middle) & (st.time < middle + duration_s))
    q = Rotation.from_quat(st.loc[rows, ["q1", "q2", "q3", "q4"]].to_numpy(dtype=float))
    st.loc[rows, ["q1", "q2", "q3", "q4"]] = (q * Rotation.from_rotvec([np.deg2rad(size_arcsec / 3600), 0, 0])).as_quat()
    _write(st, d, "star_tracker.csv")
    return [int(r) + 2 for r in rows]


def stuck_channel(channel="dtg1_roll", maneuvers=("roll_pos", "roll_neg"), value=0.0):
    """A dead channel: ``channel`` reads ``value`` from the start of the first of ``maneuvers`` to the
    end of the last (through their turns about its axis). Returns the first and last line it covers."""
    def mutate(d):
        meta = _meta(d)
        t0, t1 = _maneuver(meta, maneuvers[0])["t_start"], _maneuver(meta, maneuvers[-1])["t_end"]
        gy = _read(d, "gyro.csv")
        rows = np.flatnonzero((gy.time > t0) & (gy.time <= t1))
        gy.loc[rows, channel] = value
        _write(gy, d, "gyro.csv")
        return int(rows[0]) + 2, int(rows[-1]) + 2
    return mutate


def frozen_reference(seconds=20.0, maneuver="yaw_pos"):
    """The reference repeats one attitude (valid = 1) for ``seconds`` in the middle of ``maneuver``'s
    turn. Returns the first and last line that repeat it (the first is the attitude held)."""
    def mutate(d):
        t0, t1 = _rotation_span(d, maneuver)
        start = 0.5 * (t0 + t1) - 0.5 * seconds
        st = _read(d, "star_tracker.csv")
        rows = np.flatnonzero((st.time >= start) & (st.time < start + seconds))
        st.loc[rows, ["q1", "q2", "q3", "q4"]] = st.loc[rows[0], ["q1", "q2", "q3", "q4"]].to_numpy(dtype=float)
        st.loc[rows, "valid"] = 1
        _write(st, d, "star_tracker.csv")
        return int(rows[0]) + 2, int(rows[-1]) + 2
    return mutate


def lost_exponent(channel="dtg2_yaw", maneuver="yaw_pos"):
    """One gyro cell mid-turn written without its exponent (1.7477e-03 as 1.7477). Returns its line."""
    def mutate(d):
        t0, t1 = _rotation_span(d, maneuver)
        gy = _read(d, "gyro.csv")
        row = int(np.flatnonzero(gy.time >= 0.5 * (t0 + t1))[0])
        mantissa, _ = f"{gy.loc[row, channel]:.6e}".split("e")
        gy.loc[row, channel] = float(mantissa)
        _write(gy, d, "gyro.csv")
        return row + 2
    return mutate


def yaml_edit(old, new):
    def mutate(d):
        text = (d / "campaign.yaml").read_text()
        assert old in text, old
        (d / "campaign.yaml").write_text(text.replace(old, new, 1))
    return mutate


def valid_two(d):
    st = _read(d, "star_tracker.csv")
    st.loc[5, "valid"] = 2
    _write(st, d, "star_tracker.csv")


def blank_line_then_nan(d):
    lines = (d / "gyro.csv").read_text().splitlines()
    cells = lines[20].split(",")
    cells[1] = "nan"
    lines[20] = ",".join(cells)
    lines.insert(10, "")
    (d / "gyro.csv").write_text("\n".join(lines) + "\n")


def quaternion_decimals(digits):
    def mutate(d):
        st = _read(d, "star_tracker.csv")
        st[["q1", "q2", "q3", "q4"]] = st[["q1", "q2", "q3", "q4"]].round(digits)
        st.to_csv(d / "star_tracker.csv", index=False, float_format=f"%.{digits}f")
    return mutate


def boresight_strings(d):
    meta = _meta(d)
    meta.setdefault("star_tracker", {})["boresight_body"] = ["a", "b", "c"]
    _write_meta(d, meta)


def gyro_scalar(d):
    meta = _meta(d)
    meta["gyro"] = 0.003
    _write_meta(d, meta)


def unquoted_direction(d):
    text = (d / "campaign.yaml").read_text()
    (d / "campaign.yaml").write_text(text.replace("direction: '-'", "direction: -", 1))


def t_start_true(d):
    meta = _meta(d)
    meta["maneuvers"][0]["t_start"] = True
    _write_meta(d, meta)


def hyphen_name(d):
    meta = _meta(d)
    meta.pop("name", None)
    _write_meta(d, meta)


REFUSED = {
    "gyro increments in degrees": gyro_scale(180 / np.pi),
    "gyro increments 1000x too large": gyro_scale(1000.0),
    "gyro rates instead of increments": gyro_rates,
    "gyro cumulative angle": gyro_cumulative,
    "gyro gap inside a rotation": gyro_gap(60.0),
    "scalar-first quaternions under q1..q4": scalar_first,
    "5 s star-tracker clock offset": st_clock_offset(5.0),
    "overlapping maneuvers": overlapping,
    "axis label names the wrong axis": wrong_axis,
    "direction label is the wrong one": wrong_direction,
    "window with no rotation": no_rotation,
    "valid=2": valid_two,
    "boresight given as strings": boresight_strings,
    "gyro: a scalar": gyro_scalar,
    "unquoted direction: -": unquoted_direction,
    "blank line, then a NaN": blank_line_then_nan,
    "t_start: true": t_start_true,
    "a dead channel through the roll maneuvers": stuck_channel(),
    "a channel stuck at a constant": stuck_channel("dtg2_pitch", ("pitch_pos",), 3e-6),
    "a frozen reference mid-turn": frozen_reference(),
    "a gyro cell that lost its exponent": lost_exponent(),
}
"""Corruptions `gyrocal validate` must refuse, each with a message a user can act on."""

ACCEPTED = {
    "quaternions written to 5 decimals": quaternion_decimals(5),
    "directory name with a hyphen, no name key": hyphen_name,
    "window with no hold": no_hold,
    "five star-tracker outliers": st_outliers,
    "pitch_neg not flown": drop_maneuver("pitch_neg"),
}
"""Messy but legitimate campaigns that must pass `validate` (with warnings where due)."""


def corrupted_copy(source, target, mutate):
    """A copy of campaign ``source`` at ``target`` with ``mutate`` applied; returns what it returns."""
    shutil.copytree(source, target)
    return mutate(Path(target))


def main(source, workdir, command=("gyrocal",)):
    """Make every corrupted copy of ``source`` under ``workdir`` and print what ``command validate``
    says of each (its exit code and first lines)."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    for name, mutate in {**REFUSED, **ACCEPTED}.items():
        target = workdir / ("my-campaign" if name.startswith("directory name") else
                            "".join(c if c.isalnum() else "_" for c in name))
        shutil.rmtree(target, ignore_errors=True)
        corrupted_copy(source, target, mutate)
        out = subprocess.run([*command, "validate", str(target)], capture_output=True, text=True)
        text = (out.stderr or out.stdout).strip().splitlines()
        print(f"## {name} (exit {out.returncode})\n" + "\n".join(text[:6]) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "/tmp/gyrocal-mutations",
         sys.argv[3].split() if len(sys.argv) > 3 else ("gyrocal",))
