"""Two calibrations of the same gyros, parameter by parameter: do they agree within their uncertainty?

The same sensor calibrated twice (two trials, two campaigns) must give answers that differ by
no more than their intervals allow. For each parameter both ``calibration.csv`` files hold,
``z = (mean_B - mean_A) / sqrt(sd_A^2 + sd_B^2)``: independent campaigns, normal posteriors.

Misalignments are relative to the body frame each run aligned its reference to (``mounting:
estimate``, a coarse alignment from that run's own data). Where the two runs' mountings differ,
B is first turned into A's body frame, so that the same physical axis is compared.

The derived rows (``sf_mean``, ``sf_asym``: combinations of a channel's scale factors) are
compared too, and shown, but the verdict counts the parameters alone: a combination repeats
what its parameters say (with the correlation they lacked).
"""

import json
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from gyrocal.io.calibration import combination_rows
from gyrocal.model.units import ARCSEC_RAD, AXES, PPM

__all__ = ["KEYS", "compare", "compare_files", "into_frame", "mounting_of", "turnable"]

KEYS = ["channel", "parameter"]


def mounting_of(calibration_path) -> Rotation | None:
    """The reference mounting a run applied (``input.json`` of ``results/<campaign>/``, beside the
    model folder that holds ``calibration.csv``); None where that file is not there."""
    info = Path(calibration_path).resolve().parent.parent / "input.json"
    if not info.is_file():
        return None
    mounting = json.loads(info.read_text()).get("mounting") or {}
    return Rotation.from_quat(mounting["quat"]) if "quat" in mounting else Rotation.identity()


def turnable(table: pd.DataFrame) -> list:
    """The channels `into_frame` can turn: those with misalignments toward exactly two axes."""
    mis = table[table["parameter"].str.startswith("mis_")].groupby("channel")["parameter"].nunique()
    return sorted(mis.index[mis == 2])


def into_frame(table: pd.DataFrame, turn: Rotation) -> pd.DataFrame:
    """A calibration table with its body frame turned by ``turn`` (taking its body axes into the
    other run's). Each channel senses ``(1 + s) (e_a + m) . omega``; its row ``e_a + m`` turns
    exactly, the misalignments become the row's components across over the one along, and the
    scale factors (and their mean) take the one along; the asymmetry ``sf_pos - sf_neg`` scales
    by it. Means and point estimates move; sds and intervals move
    with the means (a shift of frame does not change what the data told)."""
    out = table.copy()
    columns = [c for c in ("mean", "point", "ci95_low", "ci95_high") if c in out]
    for channel in turnable(out):
        rows = out[out["channel"] == channel]
        mis = {p.removeprefix("mis_"): i for i, p in zip(rows.index, rows["parameter"]) if p.startswith("mis_")}
        a = next(AXES.index(axis) for axis in AXES if axis not in mis)
        row = np.zeros(3)
        row[a] = 1.0
        for b, i in mis.items():
            row[AXES.index(b)] = out.at[i, "mean"] * ARCSEC_RAD
        turned = turn.apply(row)
        shift = {i: turned[AXES.index(b)] / turned[a] / ARCSEC_RAD - out.at[i, "mean"] for b, i in mis.items()}
        for i in rows.index[rows["parameter"].isin(("sf", "sf_pos", "sf_neg", "sf_mean"))]:
            shift[i] = ((1.0 + out.at[i, "mean"] * PPM) * turned[a] - 1.0) / PPM - out.at[i, "mean"]
        for i in rows.index[rows["parameter"] == "sf_asym"]:
            shift[i] = out.at[i, "mean"] * (turned[a] - 1.0)
        for i, d in shift.items():
            out.loc[i, columns] += d
    return out


def compare(first: pd.DataFrame, second: pd.DataFrame) -> pd.DataFrame:
    """One row per parameter both tables hold: means, sds, difference, its sd and z. A parameter
    prior-only in either is listed with no z (the data said nothing to compare)."""
    merged = first.merge(second, on=KEYS, suffixes=("_a", "_b"), how="inner", validate="one_to_one")
    units = merged["unit_a"] != merged["unit_b"]
    if units.any():
        row = merged[units].iloc[0]
        raise ValueError(f"{row.channel}.{row.parameter} is in {row.unit_a} in the first file, {row.unit_b} in the second")
    prior_only = np.zeros(len(merged), dtype=bool)
    for column in ("prior_only_a", "prior_only_b"):
        if column in merged:
            prior_only |= merged[column].fillna(False).astype(bool).to_numpy()
    diff = merged["mean_b"] - merged["mean_a"]
    sd = np.hypot(merged["sd_a"], merged["sd_b"])
    return pd.DataFrame({"channel": merged["channel"], "parameter": merged["parameter"], "unit": merged["unit_a"],
                         "mean_a": merged["mean_a"], "sd_a": merged["sd_a"], "mean_b": merged["mean_b"],
                         "sd_b": merged["sd_b"], "difference": diff, "difference_sd": sd,
                         "z": np.where(prior_only, np.nan, diff / sd), "prior_only": prior_only})


def compare_files(first, second, z_max: float = 3.0) -> tuple:
    """``gyrocal compare-campaigns``: the table as text, a verdict line, and whether they agree."""
    a, b = pd.read_csv(first), pd.read_csv(second)
    out = [f"A = {first}", f"B = {second}"]
    mount_a, mount_b = mounting_of(first), mounting_of(second)
    if mount_a is not None and mount_b is not None:
        turn = mount_a * mount_b.inv()
        if turn.magnitude() > 0:
            b = into_frame(b, turn)
            out.append("B turned into A's body frame: the runs aligned their references differently, by "
                       + ", ".join(f"{v:+.0f}" for v in turn.as_rotvec() / ARCSEC_RAD)
                       + " arcsec about roll, pitch, yaw (input.json, mounting)")
            channels = set(b.loc[b["parameter"].str.startswith(("sf_", "mis_")), "channel"])
            left = sorted(channels - set(turnable(b)))
            if left:
                out.append(f"not turned (no misalignment toward two axes): {', '.join(left)}")
    table = compare(a, b)
    derived = combination_rows(table)
    compared = table[~table["prior_only"].to_numpy() & ~derived]
    worst = compared.loc[compared["z"].abs().idxmax()] if len(compared) else None
    agree = bool(len(compared)) and bool((compared["z"].abs() < z_max).all())
    shown = table.round(3).astype({"z": object})
    shown.loc[table["prior_only"].to_numpy(), "z"] = "prior-only"  # the data said nothing to compare, not NaN
    out.append(shown.to_string(index=False))
    if worst is None:
        out.append("VERDICT: nothing to compare (no parameter informed in both)")
    else:
        out.append(f"VERDICT: {'AGREE' if agree else 'DISAGREE'}: {int((compared['z'].abs() >= z_max).sum())} of "
                   f"{len(compared)} parameters beyond |z| = {z_max:g}; largest {worst.channel}.{worst.parameter} "
                   f"z = {worst.z:+.2f}")
    combos = table[derived & ~table["prior_only"].to_numpy()]
    if len(combos):
        far = combos.loc[combos["z"].abs().idxmax()]
        out.append(f"combinations (not counted above): {int((combos['z'].abs() >= z_max).sum())} of {len(combos)} "
                   f"beyond |z| = {z_max:g}; largest {far.channel}.{far.parameter} z = {far.z:+.2f}")
    return "\n".join(out), agree
