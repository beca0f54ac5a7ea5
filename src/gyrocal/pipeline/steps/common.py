"""What every step shares: its process set-up, the refusal of bad input, a model variant's refusal
record, and small readers."""

import json
import logging
import os
import sys
import warnings
from contextlib import contextmanager
from pathlib import Path

from gyrocal.errors import InputError, OutputError
from gyrocal.io.outputs import write_json, write_text
from gyrocal.maneuvers import preprocess
from gyrocal.pipeline.paths import STEP_FILES
from gyrocal.pipeline.steps import REFUSED

__all__ = ["REFUSAL_KEYS", "VARIANT_STEPS", "compared", "finish", "load_maneuvers", "peak_rss", "read_json", "read_refusal",
           "refusal", "refusals", "skip", "start", "variant_step"]

log = logging.getLogger("gyrocal")


_LOG_PATH = None
"""The step's log, from `start`: `finish` writes the job's peak memory beside it."""


def start(log_path):
    """Set up a workflow step's process: gyrocal's log and Python's warnings go to the step's
    log file, and figures render headless (Agg), also where the step's module has imported
    matplotlib already and a display is at hand."""
    global _LOG_PATH
    _LOG_PATH = str(log_path)
    os.environ["MPLBACKEND"] = "Agg"
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg")
    logging.basicConfig(filename=log_path, level=logging.INFO, force=True,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    logging.captureWarnings(True)
    # arviz 0.23's matplotlib backend calls an API matplotlib 3.11 deprecates; not ours to fix.
    warnings.filterwarnings("ignore", message="Passing a dict or None as alias_mapping", category=DeprecationWarning)


def finish():
    """End a workflow step's process once its outputs are written: flush the logs and exit at once.

    ``os._exit`` stays on purpose: it is no workaround for a hang. At this point only the main thread
    is alive (no pool, timer or writer thread is left), and a normal exit does end; but the
    interpreter's teardown, which frees every module and object one by one, costs a job its
    imports' worth of time with nothing left to do: 5.5 s against 0.2 s for a process holding the
    posterior and report steps' imports (arviz, xarray, h5netcdf, matplotlib) on the loaded 2-core
    machine, 0.2-0.6 s per job on an idle one (more than some steps' own work, and 2 s on the
    default run's critical path). Every output is already written whole and closed
    (`gyrocal.io.outputs`), and the logs are flushed here first. A step that fails never gets here,
    and exits as Python does.

    First it records the job's peak resident memory (`peak_rss`) in its log and in
    ``<log without .log>.peak_rss.json`` beside it (and beside the rule's benchmark file):
    Snakemake's benchmark samples memory every few seconds and misses a short peak."""
    if _LOG_PATH is not None:
        peak = peak_rss()
        log.info("peak memory (RSS): %.0f MB this process, %.0f MB its largest child process; CPU %.2f s",
                 peak["self_mb"], peak["children_mb"], peak["cpu_s"])
        base = _LOG_PATH[:-len(".log")] if _LOG_PATH.endswith(".log") else _LOG_PATH
        write_json(peak, f"{base}.peak_rss.json")
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def peak_rss() -> dict:
    """The process's peak resident memory and that of its largest child process that has ended
    (the figure pools' workers), in MB of 10^6 bytes, from ``getrusage``: exact, however short the
    peak. A job's peak is at most ``self_mb`` plus ``children_mb`` times its concurrent children.
    Beside them ``cpu_s``: the CPU seconds (user and system) of the process and its ended children,
    exact where Snakemake's benchmark file samples them."""
    import resource
    unit = 1 if sys.platform == "darwin" else 1024  # ru_maxrss: bytes on macOS, KiB on Linux
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"self_mb": round(own.ru_maxrss * unit / 1e6, 1), "children_mb": round(children.ru_maxrss * unit / 1e6, 1),
            "cpu_s": round(own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime, 2)}


@contextmanager
def refusal():
    """Turn refused input (`gyrocal.errors.InputError`: a campaign, a plugin, a point estimate no
    sensor can give) into its message on stderr and in the step's log, and exit 1: a user reads
    what is wrong, not a traceback."""
    try:
        yield
    except InputError as exc:
        log.error("%s\n%s", REFUSED, exc)
        sys.exit(f"{REFUSED}\n{exc}")
    except OutputError as exc:  # a full disk: not the input's fault, but a message, not a traceback
        log.error("%s", exc)
        sys.exit(f"gyrocal: {exc}")


VARIANT_STEPS = tuple(STEP_FILES)
"""A model variant's steps, in order (`gyrocal.pipeline.paths.STEP_FILES`); the first starts the variant afresh."""


REFUSAL_KEYS = ("model", "status", "step", "reason")
"""A variant's refusal record (``refused.json``, and every later file of the variant in place of its
results; ``gyrocal/io/schemas/refusal.schema.json``)."""
ADVICE_KEYS = ("advice", "effects")
"""What a refusal record may add: the library effect its reason advises adding, and the variant's effects."""


def read_refusal(path) -> dict | None:
    """The refusal record in ``path`` (a variant's ``refused.json``, or any file of a refused variant,
    which holds the record in place of its results), or None where there is none: the file is missing
    or holds results."""
    path = Path(path)
    if not path.is_file():
        return None
    with open(path, "rb") as handle:
        head = handle.read(1)
    if head != b"{":  # a result: a .npz, .nc or .csv, or a JSON result other than a record
        return None
    doc = read_json(path)
    known = isinstance(doc, dict) and set(REFUSAL_KEYS) <= set(doc) <= set(REFUSAL_KEYS + ADVICE_KEYS)
    return doc if known else None


def refusals(models, files) -> dict:
    """The refusal records of the variants ``models`` whose file in ``files`` (one per model, in their
    order: any file every variant's run writes, as the report's rule gives its diagnostics) holds one,
    by model, in their order."""
    return {m: r for m, f in zip(models, files, strict=True) if (r := read_refusal(f)) is not None}


def compared(models, files) -> list:
    """The variants ``models`` that were not refused (`refusals` of their ``files``), in their order
    (the first the comparison's reference); refused with every variant's reason where none is left."""
    records = refusals(models, files)
    kept = [m for m in models if m not in records]
    if not kept:
        raise InputError("every model variant was refused or skipped, so there is nothing to review: "
                         + " ".join(f"[{m}, {r['status']} at {r['step']}] {r['reason']}" for m, r in records.items()))
    return kept


def skip(reason: str):
    """Skip a variant with ``reason`` (`gyrocal.inference.sampling.refusals.VariantSkipped`, which `variant_step` records)."""
    from gyrocal.inference.sampling.refusals import VariantSkipped  # the refusals' imports, only where a variant is skipped

    raise VariantSkipped(reason)


def variant_step(record_path, model: str, step: str, run, outputs=()) -> dict | None:
    """Run one step of a model variant (``run()``, a `VARIANT_STEPS` step) so that a refused variant
    does not stop the others: refused input (`gyrocal.errors.InputError`; a variant skipped because
    the data cannot inform what it adds, `gyrocal.inference.sampling.refusals.VariantSkipped`) is written to the
    variant's refusal record ``record_path`` (its ``refused.json``: model, status refused or skipped,
    step, reason) and logged; a later step of a variant refused earlier does not run. Either way each
    of ``outputs`` (the files the workflow's rule declares) is written with that record in place of
    its results. Returns the record, or None where the step ran."""
    if step == VARIANT_STEPS[0]:
        Path(record_path).unlink(missing_ok=True)  # a new point estimate: an earlier refusal no longer holds
    record = read_refusal(record_path)
    if record is None:
        try:
            run()
            return None
        except InputError as exc:
            record = {"model": model, "status": getattr(exc, "status", "refused"), "step": step, "reason": str(exc)}
            if getattr(exc, "advice", ""):  # a library effect the refusal advises adding, for the loop
                record.update(advice=exc.advice, effects=list(exc.effects))
            said = f"gyrocal: model {model} {record['status']} at step {step} (the other variants go on):\n{exc}"
            # a variant skipped (nothing for it to add: the loop with no misfit) is a decision, not a fault
            (log.info if record["status"] == "skipped" else log.warning)("%s", said)
            print(said, file=sys.stderr)
            write_json(record, record_path)
    text = json.dumps(record, indent=1)
    for path in outputs:
        write_text(text, path)
    return record


def load_maneuvers(npz_paths) -> list:
    return [preprocess.ManeuverData.load(p) for p in npz_paths]


def read_json(path):
    with open(path) as handle:
        return json.load(handle)

