"""The paper's method: the error held after each rotation, per unit rotation.

It needs no model beyond the channel model, so a campaign has one classic estimate,
whatever model variants it runs; the full-trajectory WLS (`estimate`) starts from it.
"""

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from gyrocal.inference import errormodel
from gyrocal.inference.preprocess import ManeuverData, body_increments, error_angles, propagate_set
from gyrocal.model import channels as ch
from gyrocal.model import kinematics
from gyrocal.model.channels import MOVING_RATE_FRACTION
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import AXES, AXIS_INDEX

__all__ = [
    "MIN_HOLD_SAMPLES", "classic", "classic_start", "classic_table", "classic_vector", "hold_bias", "hold_windows",
    "missing_holds"
]


def hold_windows(data: ManeuverData, channel_set=None):
    """Star-tracker masks of the inertial holds before and after the rotation: where the
    maneuver-axis rate is below `MOVING_RATE_FRACTION` of its peak."""
    channel_set = channel_set or data.sets[0]
    inc = body_increments(data, channel_set, ch.ChannelParams.zeros(data.channels))
    rate = np.abs(inc[:, AXIS_INDEX[data.axis]] / data.dt)
    moving = np.flatnonzero(rate > MOVING_RATE_FRACTION * rate.max())
    t_first, t_last = data.gyro_time[moving[0]], data.gyro_time[moving[-1] + 1]
    return data.st_time < t_first, data.st_time > t_last


MIN_HOLD_SAMPLES = 3
"""Star-tracker samples a hold needs for the classic method to average over it."""


def missing_holds(data: ManeuverData) -> list:
    """Which holds (``"before"``, ``"after"``) a maneuver lacks for the classic method."""
    before, after = hold_windows(data)
    return [name for name, mask in (("before", before), ("after", after)) if mask.sum() < MIN_HOLD_SAMPLES]


def hold_bias(data: ManeuverData, channel_set, before, after) -> ch.ChannelParams:
    """Zero parameters but for the residual biases of ``channel_set``, from the drift of its error
    over both holds: the body is inertial there, so the error angle (eq. 4) drifts at minus the
    bias of each axis's channel. One slope per axis, one offset per hold, by least squares."""
    params = ch.ChannelParams.zeros(data.channels)
    err = error_angles(data, channel_set, params)
    held = before | after
    design = np.column_stack([before, after, data.st_time - data.st_time[0]])[held].astype(float)
    slope = np.linalg.lstsq(design, err[held], rcond=None)[0][2]
    names = [c.name for c in data.channels]
    params.bias_rad_s[[names.index(name) for name in channel_set]] = -slope
    return params


def classic(data: ManeuverData, bias_from_holds: bool = False) -> pd.DataFrame:
    """The paper's method on one maneuver, every channel set (values SI).

    For the channel on the rotated axis a, ``sf = -(mean error after - mean error
    before) / angle`` (the sign branch of the maneuver's direction). The channels on
    the other axes see the rotation through their misalignment toward a; their error
    turns with the body during the rotation, so instead of dividing by the angle we
    divide by the kinematic matrix of the actual trajectory, which is the angle for
    the scale factor and reduces to it for small rotations. The hold averages are
    differenced in the inertial frame, where the initial attitude offset stays put.
    A maneuver without both holds, or one that turns both ways, gets no row: the method does
    not apply to it. The paper trusts the bias known before the maneuver (zero residual bias);
    with ``bias_from_holds`` each channel set's residual bias is first estimated from the holds
    (`hold_bias`), so that it is not read as a scale factor.
    """
    if data.direction == "both" or missing_holds(data):
        return pd.DataFrame(columns=["maneuver", "set", "channel", "parameter", "value", "angle_rad"])
    before, after = hold_windows(data)
    a = AXIS_INDEX[data.axis]
    others = [b for b in range(3) if b != a]
    zeros = ch.ChannelParams.zeros(data.channels)
    st_rot = Rotation.from_quat(data.st_quat)
    end = np.flatnonzero(after)[-1]
    rows = []
    for s, channel_set in enumerate(data.sets):
        params = hold_bias(data, channel_set, before, after) if bias_from_holds else zeros
        inc, attitudes, at_st = propagate_set(data, channel_set, params)
        inertial_err = at_st.apply(kinematics.error_angles_rad(at_st, st_rot))
        mid = kinematics.compose(attitudes[:-1], Rotation.from_rotvec(0.5 * inc))
        unit = np.zeros((len(inc), 3, 3))
        unit[:, [a] + others, [0, 1, 2]] = inc[:, a:a + 1]
        inertial = np.einsum("kij,kjp->kip", mid.as_matrix(), unit)
        design = errormodel.cumulative_at_st(inertial, *data.st_interval())
        to_body = at_st[end].inv().as_matrix()
        kin = -to_body @ (design[after].mean(axis=0) - design[before].mean(axis=0))
        delta = to_body @ (inertial_err[after].mean(axis=0) - inertial_err[before].mean(axis=0))
        solution = np.linalg.solve(kin, delta)
        angle = inc[:, a].sum()
        branch = "sf_pos" if angle > 0 else "sf_neg"
        rows.append({"maneuver": data.id, "set": s, "channel": channel_set[a], "parameter": branch,
                     "value": solution[0], "angle_rad": angle})
        for j, b in enumerate(others):
            rows.append({"maneuver": data.id, "set": s, "channel": channel_set[b],
                         "parameter": f"mis_{AXES[a]}", "value": solution[1 + j], "angle_rad": angle})
    return pd.DataFrame(rows)


def classic_table(maneuvers, spec: ModelSpec, bias_from_holds: bool = False) -> pd.DataFrame:
    """`classic` over every maneuver in the parameters' units; a parameter seen twice is
    averaged, a symmetric model's ``sf`` over both directions. Columns: channel, parameter, unit,
    value, n."""
    parts = [part for part in (classic(d, bias_from_holds) for d in maneuvers) if len(part)]
    if not parts:
        return pd.DataFrame(columns=["channel", "parameter", "unit", "value", "n"])
    table = pd.concat(parts, ignore_index=True)
    symmetric = np.array([f"{c}.sf" in spec.labels for c in table["channel"]], dtype=bool)
    table.loc[symmetric & table["parameter"].str.startswith("sf_").to_numpy(), "parameter"] = "sf"
    table = (table.groupby(["channel", "parameter"], sort=False)
             .agg(value=("value", "mean"), n=("value", "size")).reset_index())
    columns = [spec.index(f"{r.channel}.{r.parameter}") for r in table.itertuples()]
    table["unit"] = [spec.units[i] for i in columns]
    table["value"] = table["value"].to_numpy() * (1.0 / spec.si_per_unit[columns])
    return table[["channel", "parameter", "unit", "value", "n"]]


def classic_start(maneuvers, spec: ModelSpec) -> np.ndarray:
    """The classic estimate as the spec's SI vector (zero where it says nothing): the start of
    the full-trajectory WLS."""
    return classic_vector(classic_table(maneuvers, spec), spec)


def classic_vector(table: pd.DataFrame, spec: ModelSpec) -> np.ndarray:
    """A `classic_table` as the spec's SI vector; parameters it lacks are zero."""
    theta = np.zeros(len(spec))
    for row in table.itertuples():
        i = spec.index(f"{row.channel}.{row.parameter}")
        theta[i] = row.value * spec.si_per_unit[i]
    return theta
