"""What every step shares: its process set-up, the refusal of bad input, and small readers."""

import json
import logging
import os
import sys
import warnings
from contextlib import contextmanager

from gyrocal.checks.fit import EstimateError
from gyrocal.inference import preprocess
from gyrocal.io.telemetry import TelemetryError
from gyrocal.model import effects
from gyrocal.pipeline.steps import REFUSED

__all__ = ["finish", "known_effects", "load_maneuvers", "read_json", "refusal", "start"]

log = logging.getLogger("gyrocal")


def start(log_path):
    """Set up a workflow step's process: gyrocal's log and Python's warnings go to the step's
    log file, and figures render headless (Agg), also where the step's module has imported
    matplotlib already and a display is at hand."""
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

    The interpreter's teardown, which frees every module and object one by one, took 0.2-0.6 s
    per job (more than some steps' own work, and 2 s on the default run's critical path) with
    nothing left to do: every output is already written whole and closed (`gyrocal.io.outputs`).
    A step that fails never gets here, and exits as Python does."""
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


@contextmanager
def refusal():
    """Turn bad input (`telemetry.TelemetryError`, `gyrocal.checks.fit.EstimateError`) into its message on
    stderr and in the step's log, and exit 1: a user reads what is wrong, not a traceback."""
    try:
        yield
    except (TelemetryError, EstimateError) as exc:
        log.error("%s\n%s", REFUSED, exc)
        sys.exit(f"{REFUSED}\n{exc}")


known_effects = effects.known


def load_maneuvers(npz_paths) -> list:
    return [preprocess.ManeuverData.load(p) for p in npz_paths]


def read_json(path):
    with open(path) as handle:
        return json.load(handle)
