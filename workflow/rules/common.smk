"""Which campaign this run is about, and the paths every rule shares."""

import sys
import time
from pathlib import Path

from gyrocal import simulate as _simulate
from gyrocal import steps as _steps
from gyrocal import telemetry as _telemetry
from gyrocal.outputs import MODEL_FILES as _MODEL_FILES

if config["telemetry"]:
    CAMPAIGN_DIR = config["telemetry"]
    try:
        _meta = _telemetry.read_meta(CAMPAIGN_DIR)
    except _telemetry.TelemetryError as _refused:
        sys.exit(f"gyrocal: the campaign was refused:\n{_refused}")
    CAMPAIGN = _meta["name"]
    MANEUVERS = [m.id for m in _meta["maneuvers"]]
    SIMULATED = False
else:
    if not Path(config["scenario"]).exists() and Path(workflow.basedir, config["scenario"]).exists():
        config["scenario"] = str(Path(workflow.basedir, config["scenario"]))
    _meta = _simulate.peek(config["scenario"])
    CAMPAIGN = _meta["name"]
    MANEUVERS = _meta["maneuvers"]
    CAMPAIGN_DIR = f"{config['results']}/{CAMPAIGN}/simulated/campaign"
    SIMULATED = True

RESULTS = f"{config['results']}/{CAMPAIGN}"
LOGS = f"logs/{CAMPAIGN}"
MODELS = sorted(config["models"], key=lambda m: m != "baseline")  # baseline is the reference
PLUGINS = config["plugins"]

wildcard_constraints:
    maneuver="|".join(MANEUVERS),
    model="|".join(MODELS),


_STARTED = time.time()


def refusal_messages():
    """What the steps of this run refused (their logs from `gyrocal.steps.REFUSED` on), to repeat
    when a run fails."""
    found = []
    for path in sorted(Path(LOGS).rglob("*.log")):
        if path.stat().st_mtime < _STARTED:
            continue
        text = path.read_text()
        if _steps.REFUSED in text:
            found.append(text[text.index(_steps.REFUSED):].rstrip())
    return found


def campaign_input():
    """The campaign files a step reads: the simulator's output or the user's directory."""
    if SIMULATED:
        return {"campaign": CAMPAIGN_DIR}
    return {f: f"{CAMPAIGN_DIR}/{f}" for f in ("campaign.yaml", "star_tracker.csv", "gyro.csv")}


def maneuver_files(ext):
    return expand(f"{RESULTS}/preprocess/{{maneuver}}.{ext}", maneuver=MANEUVERS)


def report_model_files(wildcards):
    """Every model's files the report reads, named as gyrocal.outputs.MODEL_FILES, in MODELS' order."""
    return {name: expand(f"{RESULTS}/{{model}}/{file}", model=MODELS) for name, file in _MODEL_FILES.items()}


def section(*keys):
    """A config section as a rule's param, keys sorted at every level: Snakemake compares params by
    their repr, so the order a config file happens to give must not rerun a job."""

    def canonical(value):
        return {k: canonical(value[k]) for k in sorted(value)} if isinstance(value, dict) else value

    value = config
    for key in keys:
        value = value[key]
    return canonical(value)


def model_effects(wildcards):
    """The effects of one model variant: all its point estimate needs of the config's models."""
    return config["models"][wildcards.model]


def all_outputs():
    out = [f"{RESULTS}/input.json"] + maneuver_files("png")
    for model in MODELS:
        out += [f"{RESULTS}/{model}/calibration.csv", f"{RESULTS}/{model}/correction.json",
                f"{RESULTS}/{model}/diagnostics.json"]
    return out + [f"{RESULTS}/classic.csv", f"{RESULTS}/model_comparison.csv", f"{RESULTS}/report.html"]
