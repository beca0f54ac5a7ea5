"""Command ``gyrocal joint RUN_A RUN_B ... --out DIR``: one calibration from several finished runs of
one unit, and the test that they are consistent with it.

Each run is a campaign's ``results/<campaign>`` folder; the joint fit reads one model's
``point_estimate.npz`` from each (the WLS estimate, its covariance and the specification) and the
mounting each run applied (``input.json``), and writes ``DIR/calibration.csv`` (the contract's
columns) and ``DIR/consistency.json``.
"""

import json
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.criticism.agreement import mounting_of
from gyrocal.criticism.consistency import PRIOR_SHARE_MAX, consistency
from gyrocal.criticism.joint import CampaignLikelihood, joint_fit, joint_table
from gyrocal.inference.fit.estimate import PointEstimate
from gyrocal.io.outputs import write_csv, write_json
from gyrocal.model.units import ARCSEC_RAD
from gyrocal.pipeline.paths import CampaignPaths

__all__ = ["LEVEL", "likelihoods", "report", "run"]

LEVEL = 0.05
"""The test's default level: the campaigns are called inconsistent when p < 5 %."""


def _read(run_dir, model: str):
    """A run's campaign name, its point estimate and the mounting it applied (identity if none)."""
    paths = CampaignPaths.under(run_dir)
    path = Path(paths.model(model).point_estimate)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no point estimate of model {model!r} there; give a run's "
                                f"results/<campaign> folder whose run has reached its point estimate")
    info = Path(paths.input_json)
    name = json.loads(info.read_text()).get("campaign", Path(run_dir).name) if info.is_file() else Path(run_dir).name
    turn = mounting_of(Path(paths.model(model).calibration))
    return name, PointEstimate.load(path), turn if turn is not None else Rotation.identity()


def likelihoods(run_dirs, model: str, priors_cfg: dict | None):
    """Each run's likelihood of the channel model's terms, in the first run's body frame; the first
    run's specification with the config's priors; the turns applied (arcsec roll, pitch, yaw)."""
    runs = [_read(r, model) for r in run_dirs]
    if len({name for name, _, _ in runs}) < len(runs):  # campaigns of one name: told apart by their folders
        runs = [(str(r), est, mount) for r, (_, est, mount) in zip(run_dirs, runs)]
    spec = runs[0][1].spec.with_priors(priors_cfg)
    out, turns = [], []
    for name, est, mount in runs:
        if list(est.spec.labels[est.spec.core]) != list(spec.labels[spec.core]):
            raise ValueError(f"{name}: its channel model's parameters differ from {runs[0][0]}'s; a joint fit "
                             f"needs campaigns of the same unit, with the same channels")
        own = est.spec.with_priors(priors_cfg)
        lik = CampaignLikelihood.of(name, own, est.theta, est.cov, own.prior_mean_si, own.prior_sd_si)
        turn = runs[0][2] * mount.inv()
        turns.append((turn.as_rotvec() / ARCSEC_RAD).tolist())
        out.append(lik.turned(spec, turn))
    return out, spec, turns


def _directions(test) -> list:
    return [{"chi2": d.chi2, "z": d.z, "loadings": d.loadings} for d in test["directions"]]


def report(liks, spec, turns, level: float = LEVEL, share_max: float = PRIOR_SHARE_MAX):
    """The joint table, the consistency document and the printed text."""
    prior_sd = spec.prior_sd_si[spec.core]
    fit = joint_fit(liks, spec.prior_mean_si[spec.core], prior_sd)
    table = joint_table(spec, fit)
    test = consistency([lik.estimate for lik in liks], [lik.info for lik in liks], spec.prior_mean_si[spec.core],
                       prior_sd, liks[0].labels, share_max)
    consistent = test.consistent(level)
    doc = {"campaigns": [lik.name for lik in liks], "model": spec.model, "level": level,
           "prior_share_max": share_max, "chi2": test.chi2, "dof": test.dof, "p_value": test.p_value,
           "consistent": consistent, "frame_turns_arcsec": dict(zip([lik.name for lik in liks], turns)),
           "against_rest": [{"campaign": liks[t["campaign"]].name, "chi2": t["chi2"], "dof": t["dof"],
                             "p_value": t["p_value"], "directions": _directions(t)} for t in test.against_rest]}
    lines = [f"joint fit of {len(liks)} campaigns ({', '.join(doc['campaigns'])}), model {spec.model}"]
    for lik, turn in zip(liks[1:], turns[1:]):
        if np.any(turn):
            lines.append(f"{lik.name} turned into {liks[0].name}'s body frame by "
                         + ", ".join(f"{v:+.0f}" for v in turn) + " arcsec about roll, pitch, yaw (input.json)")
    lines.append(table[["channel", "parameter", "unit", "mean", "sd", "ci95_low", "ci95_high", "prior_only"]]
                 .round(2).to_string(index=False))
    for t in test.against_rest:
        head = "B - A: " if len(liks) == 2 else f"{liks[t['campaign']].name} against the others: "
        lines.append(f"{head}chi2 = {t['chi2']:.2f} on {t['dof']} dof, p = {t['p_value']:.3g}; largest directions:")
        for d in t["directions"]:
            combo = " ".join(f"{w:+.2f} {label}" for label, w in d.loadings.items())
            lines.append(f"  z^2 = {d.chi2:6.2f} (z = {d.z:+.2f}) along {combo}")
    how = "" if len(liks) == 2 else f"the worst of {len(liks)} tests, p times {len(liks)}: "
    lines.append(f"VERDICT: {'CONSISTENT' if consistent else 'INCONSISTENT'} with one calibration: {how}chi2 = "
                 f"{test.chi2:.2f} on {test.dof} dof, p = {test.p_value:.3g} (level {level:g}; directions where the "
                 f"posteriors keep more than {share_max:g} of the prior's variance are left out)")
    return table, doc, "\n".join(lines), consistent


def run(run_dirs, out_dir, model: str = "baseline", priors_cfg: dict | None = None, level: float = LEVEL):
    """``gyrocal joint``: write ``calibration.csv`` and ``consistency.json`` to ``out_dir``; the printed
    text and whether the campaigns are consistent."""
    if len(run_dirs) < 2:
        raise ValueError("a joint fit needs at least two runs")
    liks, spec, turns = likelihoods(run_dirs, model, priors_cfg)
    table, doc, text, consistent = report(liks, spec, turns, level)
    out_dir = Path(out_dir)
    write_csv(table, out_dir / "calibration.csv")
    write_json(doc, out_dir / "consistency.json")
    return text + f"\nwrote {out_dir}/calibration.csv and consistency.json", consistent
