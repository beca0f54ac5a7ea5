"""The paper's method: the error held after each rotation, per unit rotation, with its sd.

It needs no model beyond the channel model, so a campaign has one classic estimate,
whatever model variants it runs; the full-trajectory WLS (`estimate`) starts from it.
Each value carries an sd from the stated noise (star tracker and ARW) and, where the bias
comes from the holds, that bias's own uncertainty: the estimate is linear in the error
series, so the sd follows exactly by the delta method (`classic_sd`).
"""

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from gyrocal.inference import errormodel
from gyrocal.maneuvers.holds import MIN_HOLD_SAMPLES, hold_windows, missing_holds
from gyrocal.maneuvers.preprocess import ManeuverData, error_angles, propagate_set
from gyrocal.model import channels as ch
from gyrocal.model import kinematics
from gyrocal.model.spec import ModelSpec
from gyrocal.model.units import ARCSEC_RAD, AXES, AXIS_INDEX, DEG_SQRT_H_RAD_SQRT_S

__all__ = [
    "BIAS_CHOICES",
    "MIN_BIAS_HOLD_SAMPLES",
    "MIN_HOLD_SAMPLES",
    "PIPELINE_ITERATIONS",
    "TABLE_COLUMNS",
    "bias_source",
    "classic",
    "classic_sd",
    "classic_start",
    "classic_table",
    "classic_vector",
    "free_note",
    "hold_bias",
    "hold_slope_weights",
    "hold_windows",
    "missing_holds",
    "star_tracker_cov"
]

BIAS_CHOICES = ("auto", "holds", "trusted")
"""Where the classic method takes each maneuver's residual bias from: ``trusted`` (the paper: the
bias known before the maneuver, zero residual), ``holds`` (estimated from the inertial holds around
it) or ``auto`` (the holds where they are long enough, `MIN_BIAS_HOLD_SAMPLES`; the pipeline's)."""

MIN_BIAS_HOLD_SAMPLES = 10
"""Star-tracker samples each hold needs before ``auto`` estimates the bias from the holds: with
fewer, the bias is trusted, and the maneuver's rows say why."""

TABLE_COLUMNS = ["channel", "parameter", "unit", "value", "sd", "n", "bias_source", "maneuvers", "note"]
"""The columns of ``classic.csv`` (`classic_table`)."""

PIPELINE_ITERATIONS = 4
"""Solves of ``classic.csv``'s method (`classic`). On MOM's maneuvers with scale factors of
5000 ppm and misalignments of 1000 arcsec (1 sd), the second solve moves the values by up to
154 ppm and 6.7 arcsec, the third by 1.9 ppm, the fourth by 0.02 ppm. The WLS start keeps the
paper's single solve (so the models' outputs stay as they were)."""

_ROW_COLUMNS = ["maneuver", "set", "channel", "parameter", "value", "sd", "angle_rad", "bias_source", "note"]


def bias_source(before, after, bias: str = "auto") -> tuple:
    """``(source, note)``: where the classic method takes a maneuver's bias from (`BIAS_CHOICES`),
    and, where ``auto`` falls back to trusting it, why."""
    if bias not in BIAS_CHOICES:
        raise ValueError(f"bias must be one of {BIAS_CHOICES}, got {bias!r}")
    if bias != "auto":
        return bias, ""
    n = int(before.sum()), int(after.sum())
    if min(n) >= MIN_BIAS_HOLD_SAMPLES:
        return "holds", ""
    return "trusted", (f"holds of {n[0]} and {n[1]} star-tracker samples, under the {MIN_BIAS_HOLD_SAMPLES} each "
                       "a bias slope needs: the bias known before the maneuver is trusted, and the sd leaves out "
                       "its error")


def hold_slope_weights(data: ManeuverData, before, after) -> np.ndarray:
    """(M,) weights that give the common drift rate of a series over both holds (one offset per
    hold, one slope, least squares); zero outside the holds."""
    held = before | after
    design = np.column_stack([before, after, data.st_time - data.st_time[0]])[held].astype(float)
    weights = np.zeros(len(data.st_time))
    weights[held] = np.linalg.pinv(design)[2]
    return weights


def hold_bias(data: ManeuverData, channel_set, before, after) -> ch.ChannelParams:
    """Zero parameters but for the residual biases of ``channel_set``, from the drift of its error
    over both holds: the body is inertial there, so the error angle (eq. 4) drifts at minus the
    bias of each axis's channel. One slope per axis, one offset per hold, by least squares."""
    params = ch.ChannelParams.zeros(data.channels)
    err = error_angles(data, channel_set, params)
    slope = hold_slope_weights(data, before, after) @ err
    names = [c.name for c in data.channels]
    params.bias_rad_s[[names.index(name) for name in channel_set]] = -slope
    return params


def star_tracker_cov(stated: dict) -> np.ndarray:
    """(3, 3) covariance (rad^2, body axes) of one star-tracker sample's attitude error, from the
    stated noise: ``sigma_cross`` across the boresight, ``sigma_about`` about it."""
    b = np.asarray(stated["boresight_body"], dtype=float)
    b = b / np.linalg.norm(b)
    along = np.outer(b, b)
    return ((stated["sigma_cross_arcsec"] * ARCSEC_RAD) ** 2 * (np.eye(3) - along)
            + (stated["sigma_about_arcsec"] * ARCSEC_RAD) ** 2 * along)


def classic_sd(data: ManeuverData, at_st: Rotation, mid: Rotation, solve: np.ndarray, before, after,
               slope_weights, stated: dict) -> np.ndarray:
    """(3,) sd (SI) of one channel set's classic solution, by the delta method.

    The solution is ``solve @ u``, ``u`` the after-minus-before hold means of the inertial error
    ``e``; with the bias from the holds, ``e`` is first corrected by ``G b`` (``G``: the inertial
    error per unit body bias, the running integral of the attitude) with ``b`` minus the holds'
    slope of the body-frame error. So the solution is ``sum_k M_k e_k``, linear in the raw error,
    whose noise is the star tracker's (white, ``R_k S R_k^T`` in inertial axes) and the gyros'
    ARW (an isotropic random walk in inertial axes, from the propagation's start)."""
    rot = at_st.as_matrix()
    w = after / after.sum() - before / before.sum()
    weights = w[:, None, None] * np.eye(3)
    if slope_weights is not None:
        walk = errormodel.cumulative_at_st(mid.as_matrix() * data.dt[:, None, None], *data.st_interval())
        g_bar = np.einsum("k,kij->ij", w, walk)
        weights = weights - np.einsum("ij,k,klj->kil", g_bar, slope_weights, rot)
    weights = np.einsum("ij,kjl->kil", solve, weights)
    through = np.einsum("kij,kjl->kil", weights, rot)
    var_st = np.einsum("kij,jl,kil->i", through, star_tracker_cov(stated), through)
    tail = np.cumsum(weights[::-1], axis=0)[::-1]
    gaps = np.diff(np.concatenate([data.gyro_time[:1], data.st_time]))
    arw = stated["arw_deg_sqrt_h"] * DEG_SQRT_H_RAD_SQRT_S
    var_walk = arw**2 * np.einsum("k,kij,kij->i", gaps, tail, tail)
    return np.sqrt(var_st + var_walk)


def _held_solution(data, channel_set, params, a, others, before, after, st_rot, end):
    """One linear solve of the method about ``params``: the correction to the rotated channel's
    scale factor and the others' misalignments toward the axis, and what its sd needs."""
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
    return np.linalg.solve(kin, delta), np.linalg.solve(kin, to_body), at_st, mid, inc[:, a].sum()


def classic(data: ManeuverData, bias: str = "trusted", stated: dict | None = None,
            iterations: int = 1) -> pd.DataFrame:
    """The paper's method on one maneuver, every channel set (values and sd SI).

    For the channel on the rotated axis a, ``sf = -(mean error after - mean error
    before) / angle`` (the sign branch of the maneuver's direction). The channels on
    the other axes see the rotation through their misalignment toward a; their error
    turns with the body during the rotation, so instead of dividing by the angle we
    divide by the kinematic matrix of the actual trajectory, which is the angle for
    the scale factor and reduces to it for small rotations. The hold averages are
    differenced in the inertial frame, where the initial attitude offset stays put.
    A maneuver without both holds, one that turns both ways, or free motion gets no row: the method does
    not apply to it. The paper trusts the bias known before the maneuver (zero residual bias);
    from the holds (``bias``, `bias_source`), each channel set's residual bias is first
    estimated from them (`hold_bias`), so that it is not read as a scale factor. With the
    ``stated`` noise (`gyrocal.inference.noise.covariance.noise_knowledge`) each value gets its sd
    (`classic_sd`); without, the sd is NaN. The paper's solve is linear about zero; with
    ``iterations`` > 1 it is repeated about its own estimate (Gauss-Newton), which removes its
    second-order error at large parameters (5000 ppm and 1000 arcsec: -35 ppm of bias, twice its sd).
    """
    if data.free or data.direction == "both" or missing_holds(data):
        return pd.DataFrame(columns=_ROW_COLUMNS)
    before, after = hold_windows(data)
    source, note = bias_source(before, after, bias)
    slope_weights = hold_slope_weights(data, before, after) if source == "holds" else None
    a = AXIS_INDEX[data.axis]
    others = [b for b in range(3) if b != a]
    st_rot = Rotation.from_quat(data.st_quat)
    end = np.flatnonzero(after)[-1]
    index = {c.name: i for i, c in enumerate(data.channels)}
    rows = []
    for s, channel_set in enumerate(data.sets):
        params = (hold_bias(data, channel_set, before, after) if source == "holds"
                  else ch.ChannelParams.zeros(data.channels))
        solution = np.zeros(3)
        for _ in range(iterations):
            step, solve, at_st, mid, angle = _held_solution(data, channel_set, params, a, others, before, after,
                                                           st_rot, end)
            solution = solution + step
            branch = "sf_pos" if angle > 0 else "sf_neg"
            params.set(index[channel_set[a]], branch, solution[0])
            for j, b in enumerate(others):
                params.set(index[channel_set[b]], f"mis_{AXES[a]}", solution[1 + j])
        sd = (np.full(3, np.nan) if stated is None else
              classic_sd(data, at_st, mid, solve, before, after, slope_weights, stated))
        rows.append({"maneuver": data.id, "set": s, "channel": channel_set[a], "parameter": branch,
                     "value": solution[0], "sd": sd[0], "angle_rad": angle, "bias_source": source, "note": note})
        for j, b in enumerate(others):
            rows.append({"maneuver": data.id, "set": s, "channel": channel_set[b], "parameter": f"mis_{AXES[a]}",
                         "value": solution[1 + j], "sd": sd[1 + j], "angle_rad": angle, "bias_source": source,
                         "note": note})
    return pd.DataFrame(rows, columns=_ROW_COLUMNS)


def classic_table(maneuvers, spec: ModelSpec, bias: str = "trusted", stated: dict | None = None,
                  iterations: int = 1) -> pd.DataFrame:
    """`classic` over every maneuver in the parameters' units; a parameter seen twice (a maneuver
    flown again) is averaged, its sd that of the mean of independent maneuvers; a symmetric model's
    ``sf`` is averaged over both directions. Columns
    `TABLE_COLUMNS`: ``bias_source`` is ``holds``, ``trusted`` or ``mixed`` over its maneuvers,
    ``maneuvers`` lists each with its source (``yaw_pos:holds``), ``note`` why a bias was trusted.
    ``iterations``: as in `classic` (the pipeline's `PIPELINE_ITERATIONS`). Free-motion maneuvers
    give no number (the method needs a rotation about one labelled axis between inertial holds):
    the note says so on every row, and a channel parameter no labelled maneuver gives has a row of
    its own with no value (``n`` 0)."""
    free = [d.id for d in maneuvers if d.free]
    parts = [part for part in (classic(d, bias, stated, iterations) for d in maneuvers) if len(part)]
    if not parts:
        return _free_rows(pd.DataFrame(columns=TABLE_COLUMNS), free, spec)
    rows = pd.concat(parts, ignore_index=True)
    symmetric = np.array([f"{c}.sf" in spec.labels for c in rows["channel"]], dtype=bool)
    rows.loc[symmetric & rows["parameter"].str.startswith("sf_").to_numpy(), "parameter"] = "sf"
    rows["var"] = rows["sd"].astype(float) ** 2
    rows["tagged"] = rows["maneuver"] + ":" + rows["bias_source"]
    table = (rows.groupby(["channel", "parameter"], sort=False)
             .agg(value=("value", "mean"), var=("var", lambda v: v.to_numpy().sum()), n=("value", "size"),
                  sources=("bias_source", lambda v: sorted(set(v))), maneuvers=("tagged", ";".join),
                  note=("note", lambda v: "; ".join(dict.fromkeys(x for x in v if x))))
             .reset_index())
    table["bias_source"] = [s[0] if len(s) == 1 else "mixed" for s in table.pop("sources")]
    columns = [spec.index(f"{r.channel}.{r.parameter}") for r in table.itertuples()]
    table["unit"] = [spec.units[i] for i in columns]
    per_unit = 1.0 / spec.si_per_unit[columns]
    table["value"] = table["value"].to_numpy() * per_unit
    table["sd"] = np.sqrt(table.pop("var").to_numpy()) / table["n"].to_numpy() * per_unit
    return _free_rows(table[TABLE_COLUMNS], free, spec)


def free_note(free_ids) -> str:
    """What ``classic.csv`` says of free-motion maneuvers: why the paper's method gives them no number."""
    return (f"free-motion maneuver(s) {', '.join(free_ids)}: no number from the paper's method, which needs a "
            "rotation about one labelled axis between inertial holds (the full-trajectory fit uses them)")


def _free_rows(table: pd.DataFrame, free_ids, spec: ModelSpec) -> pd.DataFrame:
    """``table`` with the free maneuvers' note on every row, and a row without a value for each
    channel parameter of the paper's (scale factors, misalignments) no labelled maneuver gave."""
    if not free_ids:
        return table
    note = free_note(free_ids)
    table = table.assign(note=[f"{n}; {note}" if n else note for n in table["note"]])
    have = set(zip(table["channel"], table["parameter"]))
    rows = [{"channel": spec.channels[p.channel].name, "parameter": p.name, "unit": spec.units[i],
             "value": np.nan, "sd": np.nan, "n": 0, "bias_source": "", "maneuvers": "", "note": note}
            for i, p in enumerate(spec.parameters) if p.core and p.channel is not None
            and (p.name.startswith("sf") or p.name.startswith("mis_"))
            and (spec.channels[p.channel].name, p.name) not in have]
    return pd.concat([table, pd.DataFrame(rows, columns=TABLE_COLUMNS)], ignore_index=True) if rows else table


def classic_start(maneuvers, spec: ModelSpec) -> np.ndarray:
    """The classic estimate as the spec's SI vector (zero where it says nothing): the start of
    the full-trajectory WLS. It keeps the paper's trusted bias: the WLS fits each maneuver's bias
    itself, so the start needs no more (and the WLS's results stay as they were)."""
    return classic_vector(classic_table(maneuvers, spec), spec)


def classic_vector(table: pd.DataFrame, spec: ModelSpec) -> np.ndarray:
    """A `classic_table` as the spec's SI vector; parameters it lacks are zero."""
    theta = np.zeros(len(spec))
    for row in table.itertuples():
        if not row.n:
            continue  # no number (free motion only)
        i = spec.index(f"{row.channel}.{row.parameter}")
        theta[i] = row.value * spec.si_per_unit[i]
    return theta
