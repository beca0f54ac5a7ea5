"""Which campaigns this run is about, and the paths every rule shares.

One run calibrates one campaign (``telemetry=DIR``, or the simulated scenario) or a fleet
(``campaigns=DIR``: every directory under DIR that holds a ``campaign.yaml``), each as
independent jobs under ``results/<campaign>/``; a fleet adds ``results/fleet/``.
"""

import re
import sys
from pathlib import Path

from gyrocal.errors import InputError as _InputError
from gyrocal.criticism.extension import extension_names as _extension_names
from gyrocal.io import scenario as _scenario
from gyrocal.pipeline.paths import MODEL_FILES
from gyrocal.pipeline.paths import CampaignPaths as _CampaignPaths
from gyrocal.pipeline.settings import ExtendSettings as _ExtendSettings
from gyrocal.pipeline.settings import canonical as _canonical
from gyrocal.pipeline.settings import models_to_run as _models_to_run
from gyrocal.pipeline.settings import section as _section


def _user_campaign(directory):
    from gyrocal.io import telemetry as _telemetry  # pandas: 0.4 s of every run's start, where no user campaign is read

    try:
        meta = _telemetry.read_meta(directory)
    except _InputError as refused:
        sys.exit(f"gyrocal: the campaign was refused:\n{refused}")
    return meta["name"], {"dir": str(directory), "maneuvers": [m.id for m in meta["maneuvers"]], "simulated": False}


def results_of(campaign):
    """Where a campaign's results go (``campaign`` may be the wildcard ``{campaign}``)."""
    return f"{config['results']}/{campaign}"


CAMPAIGNS = {}
"""Campaign name -> its directory, maneuver ids and whether the scenario simulates it."""
FLEET = bool(config["campaigns"])
if FLEET:
    if not Path(config["campaigns"]).is_dir():
        sys.exit(f"gyrocal: campaigns={config['campaigns']} is not a directory: give the folder that holds the "
                 "campaign directories (each with a campaign.yaml)")
    _found = sorted(d for d in Path(config["campaigns"]).iterdir() if (d / "campaign.yaml").is_file())
    if not _found:
        sys.exit(f"gyrocal: no campaign directory (with a campaign.yaml) under {config['campaigns']}")
    for _d in _found:
        _name, _entry = _user_campaign(_d)
        if _name == "fleet":
            sys.exit(f"gyrocal: {_d} is campaign 'fleet', the name of the fleet's summary; give it another name")
        if _name in CAMPAIGNS:
            sys.exit(f"gyrocal: {_d} and {CAMPAIGNS[_name]['dir']} are both campaign {_name!r}; names must differ")
        CAMPAIGNS[_name] = _entry
elif config["telemetry"]:
    _name, _entry = _user_campaign(config["telemetry"])
    CAMPAIGNS[_name] = _entry
else:
    if not Path(config["scenario"]).exists() and Path(ROOT, config["scenario"]).exists():
        config["scenario"] = str(Path(ROOT, config["scenario"]))
    try:
        _meta = _scenario.peek(config["scenario"])
    except _InputError as refused:
        sys.exit(f"gyrocal: the scenario was refused:\n{refused}")
    CAMPAIGNS[_meta["name"]] = {"dir": _CampaignPaths(results_of(_meta["name"])).simulated,
                                "maneuvers": _meta["maneuvers"], "simulated": True}

for _name, _entry in CAMPAIGNS.items():
    _missing = _CampaignPaths(results_of(_name)).missing_in_folders(_entry["maneuvers"], _entry["simulated"])
    if _missing:
        _path, _folder = _missing[0]
        sys.exit(f"gyrocal: {_path} is missing, and Snakemake takes the folder that held it for complete: delete "
                 f"the folder {_folder} and run again, which redoes the step that writes it and every step after it")

PATHS = _CampaignPaths(results_of("{campaign}"))
"""Every file of a campaign's run (`gyrocal.pipeline.paths`), with the campaign a wildcard."""
MODEL = PATHS.model("{model}")
"""Every file of one model variant, with the campaign and the model wildcards."""
LOGS = "logs/{campaign}"
try:
    MODELS = _models_to_run(config)
    """The variants this run calibrates, the first the comparison's reference (config ``run_models``)."""
except _InputError as refused:
    sys.exit(f"gyrocal: the config was refused:\n{refused}")
PLUGINS = config["plugins"]
EXTENDED = _extension_names(config["loop"]["depth"])
"""The loop's variants (config ``loop.depth``), each fitted where the one before misfits
(`gyrocal.criticism.extension`); compared and reviewed after MODELS."""
EXTENDED_MODEL = PATHS.model("{extension}")
"""Every file of one extended variant, with the campaign and the extension wildcards."""

wildcard_constraints:
    campaign="|".join(re.escape(c) for c in CAMPAIGNS),
    maneuver="|".join(sorted({re.escape(m) for c in CAMPAIGNS.values() for m in c["maneuvers"]})),
    model="|".join(MODELS),
    extension="|".join(EXTENDED) or "(?!)",


def campaign_dir(wildcards):
    return CAMPAIGNS[wildcards.campaign]["dir"]


def maneuver_ids(wildcards):
    """The campaign's maneuvers, in its order (the order of the point estimate's biases)."""
    return CAMPAIGNS[wildcards.campaign]["maneuvers"]


def campaign_input(wildcards):
    """The campaign files a step reads: the simulator's output or the user's directory."""
    entry = CAMPAIGNS[wildcards.campaign]
    if entry["simulated"]:
        return {"campaign": entry["dir"]}
    return {f: f"{entry['dir']}/{f}" for f in ("campaign.yaml", "star_tracker.csv", "gyro.csv")}


def truth_input(wildcards):
    """The simulation's truth, for a simulated campaign's report."""
    if CAMPAIGNS[wildcards.campaign]["simulated"]:
        return [_CampaignPaths(results_of(wildcards.campaign)).truth]
    return []


def model_files(name):
    """One file of every model variant (a `ModelPaths` property), the loop's after MODELS, as an input."""
    return [getattr(PATHS.model(m), name) for m in MODELS + EXTENDED]


def extension_bases(wildcards):
    """The variants a step of the loop reads: the first, every variant (it extends the reviewed one);
    a later one, the step before it."""
    k = EXTENDED.index(wildcards.extension)
    return MODELS if k == 0 else [EXTENDED[k - 1]]


def extension_input(wildcards):
    """The files of the variants a step of the loop reads (`extension_bases`), by their `ModelPaths`
    name, a list in the order of the variants each: what the comparison reads."""
    paths = _CampaignPaths(results_of(wildcards.campaign))
    return {f: [getattr(paths.model(m), f) for m in extension_bases(wildcards)]
            for f in ("diagnostics", "summary", "elpd_blocks", "elpd_maneuvers")}


def extend_settings():
    """The loop's settings (`gyrocal.pipeline.settings.ExtendSettings`), as its rule's param."""
    return _canonical(vars(_ExtendSettings.of(config)))


def settings(step):
    """The config a model step reads (`gyrocal.pipeline.settings.SECTIONS`), as its rule's param:
    canonical, so that the order a config file gives does not rerun a job."""
    return _section(config, step)


def point_estimate_settings(wildcards):
    """The point estimate's settings: its model's effects beside the config it reads."""
    return {"effects": config["models"][wildcards.model], **_section(config, "point_estimate")}


def whole_config():
    """The whole config, canonical: the report shows all of it."""
    return _canonical(config)


def all_outputs():
    out = [path for campaign in CAMPAIGNS for path in _CampaignPaths(results_of(campaign)).outputs(MODELS + EXTENDED)]
    if FLEET:
        out += [f"{results_of('fleet')}/summary.csv", f"{results_of('fleet')}/summary.png"]
    return out
