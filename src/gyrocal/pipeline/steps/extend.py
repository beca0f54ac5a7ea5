"""Rule ``extended``: one step of the model-criticism loop (`gyrocal.criticism.extension`), a model
variant fitted in the same run where the reviewed model misfits and a library effect explains it."""

import logging

from gyrocal.criticism.extension import Extension, extension_names, next_effect
from gyrocal.io.outputs import write_json
from gyrocal.model.effects import LIBRARY
from gyrocal.pipeline.paths import STEP_FILES
from gyrocal.pipeline.settings import DiagnosticsSettings, ExtendSettings, PointEstimateSettings, PosteriorSettings
from gyrocal.pipeline.steps import common

__all__ = ["advised", "decide", "instead", "run"]

log = logging.getLogger("gyrocal")

def decide(name: str, bases, files, settings: ExtendSettings) -> Extension:
    """What the step ``name`` (`extension_names`) fits. The first extends the model the comparison of
    the variants ``bases`` reviews; each later one the step before it (``bases`` is that one alone),
    where that was fitted. ``files``: the bases' files by their `ModelPaths` name, a list in the order
    of ``bases`` each (``diagnostics``, ``summary``, ``elpd_blocks``, ``elpd_maneuvers``)."""
    bases = list(bases)
    if extension_names(settings.loop["depth"]).index(name) == 0:
        records = [common.read_refusal(path) for path in files.diagnostics]
        if all(r is not None for r in records):
            return advised(bases, records)
        from gyrocal.pipeline.steps import compare_models

        table = compare_models.table(bases, files, settings.model_choice["reject_se"])
        base = str(table.loc[table["reviewed"], "model"].iloc[0])
    else:
        base = bases[0]
        record = common.read_refusal(files.diagnostics[0])
        if record is not None:
            return instead(base, record)
    doc = common.read_json(files.diagnostics[bases.index(base)])
    return next_effect(base, doc["effects"], doc, settings.diagnostics["diagnostics"]["structure_log10_p_min"])


def advised(bases, records) -> Extension:
    """Where every variant is refused, the first step of the loop extends the first whose refusal advises
    a library effect (``advice`` in its record: `refusals.EstimateError`) by that effect, as the reviewed
    model's misfit would be extended by the effect that explains it; otherwise it stops with the reason."""
    for base, record in zip(bases, records):
        effect = record.get("advice", "")
        if effect in LIBRARY and effect not in record["effects"]:
            return Extension(base, effect, list(record["effects"]) + [effect],
                             f"every variant was refused; model {base}'s refusal ({record['step']}) advises adding "
                             f"{effect}")
    return Extension(bases[0], "", [], "every variant was refused, and no refusal advises a library effect to add")


def instead(name: str, record: dict) -> Extension:
    """A later step whose base, the loop's step ``name``, was refused (its ``record``): where the refusal
    advises a library effect, the model that step extended (its effects less the one it added, the last)
    extended by the advice instead, so that no effect whose fit was refused is carried on; otherwise the
    loop stops with the refusal's reason."""
    effect, effects = record.get("advice", ""), list(record.get("effects", []))
    if effect not in LIBRARY or not effects or effect in effects[:-1]:
        return Extension(name, "", [], f"the loop stopped at {name}: {record['reason']}")
    return Extension(name, effect, effects[:-1] + [effect],
                     f"the loop's step {name} (+ {effects[-1]}) was refused ({record['step']}), and its refusal advises "
                     f"{effect}: the model it extended, extended by {effect} instead")


def run(name: str, bases, files, maneuver_files, input_json, out, refusal_json, settings: ExtendSettings) -> Extension:
    """Decide the step (`decide`; ``out.extension``), then, where it extends, the variant's point
    estimate, posterior, calibration and diagnostics as their own rules run them, into ``out`` (its
    files by their `ModelPaths` name: a `ModelPaths`, or the rule's ``snakemake.output``); where it does
    not, the variant is skipped with the reason (in ``refusal_json``), at the cost of reading the
    diagnostics. A skipped or refused step's files and the later steps' (`STEP_FILES`, as the
    workflow's rule declares them) hold the record instead. Returns the decision."""
    step = decide(name, bases, files, settings)
    write_json(step.as_dict(), out.extension)
    log.info("loop step %s: %s", name, step.why)

    def variant_step(kind, run):
        written = [getattr(out, f) for s in common.VARIANT_STEPS[common.VARIANT_STEPS.index(kind):] for f in STEP_FILES[s]]
        return common.variant_step(refusal_json, name, kind, run, written)

    if not step.fitted:  # before the model steps' imports (the sampler's, arviz's): a skip costs next to nothing
        variant_step("point_estimate", lambda: common.skip(f"not fitted: {step.why}"))
        return step
    from gyrocal.pipeline.steps import calibrate, diagnostics, point_estimate, posterior

    pe = PointEstimateSettings(effects=step.effects, **settings.point_estimate)
    if variant_step("point_estimate", lambda: point_estimate.run(maneuver_files, input_json, out.point_estimate,
                                                                 name, pe)) is not None:
        return step

    def sample():
        sampling = PosteriorSettings(**settings.posterior)
        posterior.run(maneuver_files, out.point_estimate, out, sampling)
        calibrate.run(maneuver_files, out.point_estimate, out.summary, out.calibration, out.correction, sampling.plugins)

    if variant_step("posterior", sample) is not None:
        return step
    variant_step("diagnostics", lambda: diagnostics.run(maneuver_files, out.point_estimate, out.fit, out.summary,
                                                        out.diagnostics, DiagnosticsSettings(**settings.diagnostics)))
    return step
