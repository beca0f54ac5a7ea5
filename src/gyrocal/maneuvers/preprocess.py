"""Per-maneuver preprocessing: slice the window, start the gyro attitude from the star
tracker at ``t_start`` and compute the error angles of eq. 4 for each channel set."""

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation, Slerp

from gyrocal.io.campaign_yaml import DEFAULT_NOISE_GROUP, GM_CLOCK_KEY, Labelled, stated_clock_s_per_rad
from gyrocal.io.importer import reference_rows
from gyrocal.io.telemetry import MIN_REFERENCE_SAMPLES, Campaign, TelemetryError
from gyrocal.model import channels as ch
from gyrocal.model import kinematics
from gyrocal.model.units import AXES, rad_to_arcsec

__all__ = [
    "ManeuverData", "body_increments", "end_of_rotation_error", "error_angles", "error_table", "noise_groups",
    "propagate_set", "slice_maneuver"
]


@dataclass
class ManeuverData(Labelled):
    """One maneuver's window: gyro increments from ``t0`` and valid star-tracker samples."""

    id: str
    axis: str | None
    """The labelled axis; None for free motion (`gyrocal.io.campaign_yaml.Maneuver`)."""
    direction: str | None
    channels: tuple
    in_loop: tuple
    gyro_time: np.ndarray
    """(K+1,) times; the first is the propagation start t0."""
    increments: np.ndarray
    """(K, n_channels) raw incremental angles (rad)."""
    st_time: np.ndarray
    st_quat: np.ndarray
    attitude0_quat: np.ndarray
    extras: dict = field(default_factory=dict)
    counts: dict = field(default_factory=dict)
    noise_group: str = DEFAULT_NOISE_GROUP
    """The maneuvers sharing one noise level (campaign.yaml's ``noise_group``)."""
    gm_clock_s_per_rad: float = 0.0
    """The seconds the reference error's Gauss-Markov clock runs per radian turned (campaign.yaml's
    ``star_tracker: gm_clock_s_per_rad``; 0: time only): `errormodel.linearize` steps it."""

    def turned(self) -> dict:
        """``{(axis, sign): angle}``: how far the body turned about each axis each way (rad, the in-loop
        set's nominal increments summed by sign): the motion, whatever the label says."""
        inc = body_increments(self, self.sets[0], ch.ChannelParams.zeros(self.channels))
        return {(a, sign): float(np.abs(inc[:, i].clip(min=0) if sign == "+" else inc[:, i].clip(max=0)).sum())
                for i, a in enumerate(AXES) for sign in "+-"}

    @property
    def dt(self) -> np.ndarray:
        return np.diff(self.gyro_time)

    @property
    def sets(self) -> list:
        return ch.channel_sets(self.channels, self.in_loop or None)

    def st_interval(self):
        """Gyro interval ``k`` holding each star-tracker sample, and how far into it (0..1)."""
        k = np.clip(np.searchsorted(self.gyro_time, self.st_time, side="left") - 1, 0, len(self.dt) - 1)
        return k, (self.st_time - self.gyro_time[k]) / self.dt[k]

    def set_increments(self, channel_set) -> np.ndarray:
        index = {c.name: i for i, c in enumerate(self.channels)}
        return self.increments[:, [index[n] for n in channel_set]]

    def save(self, path):
        np.savez_compressed(
            path, id=self.id, axis=self.axis or "", direction=self.direction or "",
            channel_names=[c.name for c in self.channels], channel_dtg=[-1 if c.dtg is None else c.dtg for c in self.channels],
            channel_axis=[c.axis for c in self.channels], in_loop=list(self.in_loop),
            gyro_time=self.gyro_time, increments=self.increments, st_time=self.st_time,
            st_quat=self.st_quat, attitude0_quat=self.attitude0_quat,
            extra_names=list(self.extras),
            extra_values=np.array(list(self.extras.values())).reshape(len(self.extras), len(self.increments)),
            count_names=list(self.counts), count_values=np.array(list(self.counts.values()), dtype=int),
            noise_group=self.noise_group, **({GM_CLOCK_KEY: self.gm_clock_s_per_rad}
                                             if self.gm_clock_s_per_rad > 0 else {}))

    @classmethod
    def load(cls, path):
        z = np.load(path, allow_pickle=False)
        channels = tuple(ch.Channel(str(n), None if int(d) < 0 else int(d), str(a))
                         for n, d, a in zip(z["channel_names"], z["channel_dtg"], z["channel_axis"]))
        return cls(str(z["id"]), str(z["axis"]) or None, str(z["direction"]) or None, channels,
                   tuple(str(n) for n in z["in_loop"]), z["gyro_time"], z["increments"], z["st_time"],
                   z["st_quat"], z["attitude0_quat"],
                   {str(n): v for n, v in zip(z["extra_names"], z["extra_values"])},
                   {str(n): int(v) for n, v in zip(z["count_names"], z["count_values"])},
                   str(z["noise_group"]) if "noise_group" in z.files else DEFAULT_NOISE_GROUP,
                   float(z[GM_CLOCK_KEY]) if GM_CLOCK_KEY in z.files else 0.0)


def slice_maneuver(campaign: Campaign, maneuver_id: str, outlier_times_s=(), reference_interval_s: float = 0.0
                   ) -> ManeuverData:
    """Cut one maneuver out of a campaign; invalid star-tracker samples and the outliers
    (at ``outlier_times_s``, as `gyrocal.checks` lists them) are counted, not used, and so are the
    samples between those kept every ``reference_interval_s`` seconds (`importer.reference_rows`;
    0: every one). Only the maneuver's rows are copied or rotated (the start attitude interpolates
    the two valid samples around it), so cutting every maneuver costs the campaign's length once."""
    m = campaign.maneuver(maneuver_id)
    g = campaign.gyro_time
    i0 = int(np.searchsorted(g, m.t_start, side="left"))
    i1 = int(np.searchsorted(g, m.t_end, side="right")) - 1
    if i1 - i0 < 2:
        raise TelemetryError(f"{campaign.source}/gyro.csv: maneuver {m.id} holds fewer than two gyro samples")
    in_window = (campaign.st_time >= m.t_start) & (campaign.st_time <= m.t_end)
    outlier = np.isin(campaign.st_time, np.asarray(outlier_times_s, dtype=float))
    valid = (campaign.st_valid == 1) & ~outlier
    usable = valid & (campaign.st_time > g[i0]) & (campaign.st_time <= g[i1])
    st_idx = np.flatnonzero(valid)
    if g[i0] < campaign.st_time[st_idx[0]] or g[i0] > campaign.st_time[st_idx[-1]]:
        raise TelemetryError(f"{campaign.source}/star_tracker.csv: no valid sample brackets the start "
                             f"of maneuver {m.id} at {g[i0]} s")
    k = int(np.clip(np.searchsorted(campaign.st_time[st_idx], g[i0], side="right") - 1, 0, max(len(st_idx) - 2, 0)))
    keys = st_idx[k:k + 2]
    attitude0 = Slerp(campaign.st_time[keys], Rotation.from_quat(campaign.st_quat[keys]))([g[i0]])[0]
    thinned = usable.copy()
    if usable.sum() > 1:
        thinned[usable] = reference_rows(campaign.st_time[usable], reference_interval_s)
    st_time = campaign.st_time[thinned]
    quat = campaign.st_quat[thinned]
    if len(st_time) < MIN_REFERENCE_SAMPLES:
        kept = f" kept every reference_interval_s = {reference_interval_s:g} s" if reference_interval_s else ""
        raise TelemetryError(f"{campaign.source}/star_tracker.csv: maneuver {m.id} has only "
                             f"{len(st_time)} valid samples{kept}")
    extras = {k: v[i0 + 1:i1 + 1] for k, v in campaign.extras().items()}
    counts = {"st_read": int(in_window.sum()), "st_invalid": int((in_window & (campaign.st_valid == 0)).sum()),
              "st_outliers": int((in_window & outlier).sum()),
              "st_thinned": int(usable.sum() - thinned.sum()), "st_used": int(thinned.sum()),
              "gyro_read": int(i1 - i0 + 1), "gyro_used": int(i1 - i0)}
    return ManeuverData(m.id, m.axis, m.direction, campaign.channels, m.in_loop, g[i0:i1 + 1].copy(),
                        campaign.increments(slice(i0 + 1, i1 + 1)), st_time, quat, attitude0.as_quat(),
                        extras, counts, m.noise_group, stated_clock_s_per_rad(campaign.star_tracker) or 0.0)


def noise_groups(maneuvers) -> tuple:
    """The noise groups of ``maneuvers`` (anything with a ``noise_group``), in order of first
    appearance, and each maneuver's index into them: ``(names, index)``."""
    names = list(dict.fromkeys(m.noise_group for m in maneuvers))
    return names, np.array([names.index(m.noise_group) for m in maneuvers], dtype=int)


def body_increments(data: ManeuverData, channel_set, params: ch.ChannelParams) -> np.ndarray:
    """Body-frame increments from one channel set, corrected with ``params``."""
    return ch.solve_body(data.set_increments(channel_set), params.subset(channel_set), dt_s=data.dt)


def propagate_set(data: ManeuverData, channel_set, params: ch.ChannelParams):
    """Gyro attitude at the gyro times and at the star-tracker times, from ``R(t0)``."""
    inc = body_increments(data, channel_set, params)
    attitudes = kinematics.propagate(Rotation.from_quat(data.attitude0_quat), inc)
    at_st = kinematics.attitude_at(data.gyro_time, attitudes, inc, data.st_time)
    return inc, attitudes, at_st


def error_angles(data: ManeuverData, channel_set, params: ch.ChannelParams) -> np.ndarray:
    """(M, 3) eq. 4 error of the star tracker relative to the gyro attitude (rad, body axes)."""
    _, _, at_st = propagate_set(data, channel_set, params)
    return kinematics.error_angles_rad(at_st, Rotation.from_quat(data.st_quat))


def end_of_rotation_error(data: ManeuverData, channel_set, params: ch.ChannelParams, before, after):
    """Error left by the rotation, in body axes at the end (rad): the hold-averaged error
    after it minus the one before, compared in the inertial frame so that the initial
    attitude offset (the star-tracker noise at t_start) does not turn into other axes."""
    _, _, at_st = propagate_set(data, channel_set, params)
    err = kinematics.error_angles_rad(at_st, Rotation.from_quat(data.st_quat))
    inertial = at_st.apply(err)
    shift = inertial[after].mean(axis=0) - inertial[before].mean(axis=0)
    return at_st[np.flatnonzero(after)[-1]].inv().apply(shift)


def error_table(data: ManeuverData, params: ch.ChannelParams = None) -> pd.DataFrame:
    """Star-tracker times, body rates (deg/s) and the error along each axis (arcsec) per set."""
    params = params or ch.ChannelParams.zeros(data.channels)
    sets = data.sets
    inc = body_increments(data, sets[0], params)
    rate = inc / data.dt[:, None]
    k, _ = data.st_interval()
    table = {"time": data.st_time}
    for i, a in enumerate(AXES):
        table[f"rate_{a}_deg_s"] = np.rad2deg(rate[k, i])
    for s_index, channel_set in enumerate(sets):
        err = rad_to_arcsec(error_angles(data, channel_set, params))
        for i, a in enumerate(AXES):
            table[f"set{s_index}_error_{a}_arcsec"] = err[:, i]
    return pd.DataFrame(table)
