import os

# One BLAS thread, as Snakemake gives each one-thread job and tests/run.sh exports: the same numbers to
# the last bit in this process as in the rules' (set before numpy is first imported).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import copy
import json
from pathlib import Path

import pytest
import yaml

from gyrocal.simulation import simulate

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="session")
def config():
    """The default config with the schema's defaults, as Snakemake would hand it on."""
    from snakemake.utils import validate
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    validate(cfg, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))
    return cfg


@pytest.fixture(scope="session")
def short_chains(config):
    """The default config with the short chains of ``tests/data/short_chains.yaml``: for tests of
    wiring, files and determinism, which need no converged posterior."""
    from snakemake.utils import update_config
    cfg = copy.deepcopy(config)
    update_config(cfg, yaml.safe_load((DATA / "short_chains.yaml").read_text()))
    return cfg


@pytest.fixture(scope="session")
def tiny(tmp_path_factory):
    """A small simulated campaign directory and its truth."""
    out = tmp_path_factory.mktemp("tiny")
    simulate.run(DATA / "tiny.yaml", out)
    return out / "campaign", json.loads((out / "truth.json").read_text())


@pytest.fixture(scope="session")
def mom(tmp_path_factory):
    """The default Mars-Orbiter-like campaign (paper's truth) and its truth."""
    out = tmp_path_factory.mktemp("mom")
    simulate.run(ROOT / "config" / "scenarios" / "mom.yaml", out)
    return out / "campaign", json.loads((out / "truth.json").read_text())


def truth_vector(channels, truth):
    """The simulation's true channel model (SI), with its biases."""
    from gyrocal.model.spec import baseline
    from gyrocal.model.units import deg_h_to_rad_s
    params = baseline(channels).params_from_contract(truth["parameters"])
    params.bias_rad_s[:] = deg_h_to_rad_s([truth["parameters"][c.name]["bias_deg_h"] for c in channels])
    return params


def run_campaign(campaign_dir, out, cfg, models=("baseline",), truth_path=None):
    """Every workflow step in the order the rules run them (`gyrocal.pipeline.run.run_campaign`);
    the preprocessed maneuvers' files, in the campaign's order."""
    from gyrocal.pipeline import run
    from gyrocal.pipeline.paths import CampaignPaths
    paths = CampaignPaths.under(out)
    ids = run.run_campaign(campaign_dir, paths, cfg, models, truth_path)
    return [Path(p) for p in paths.maneuvers(ids)]


def rerun_from(out, dest, model="baseline"):
    """A copy of a finished run's preprocessed maneuvers, input.json and one model's point estimate
    under ``dest``, for a later step to run again there; its `CampaignPaths` and maneuver ids."""
    import shutil

    from gyrocal.pipeline.paths import CampaignPaths
    paths = CampaignPaths.under(dest)
    paths.mkdirs([model])
    shutil.copytree(Path(out) / "preprocess", paths.preprocess)
    shutil.copy(Path(out) / "input.json", paths.input_json)
    shutil.copy(Path(out) / model / "point_estimate.npz", paths.model(model).point_estimate)
    return paths, json.loads(Path(paths.input_json).read_text())["maneuvers"]


def config_with(cfg, models=None, plugins=None):
    out = copy.deepcopy(cfg)
    if models is not None:
        out["models"] = models
    if plugins is not None:
        out["plugins"] = plugins
    return out


def _baseline_run(campaign, tmp_path_factory, config, name):
    out = tmp_path_factory.mktemp(name)
    npz = run_campaign(campaign[0], out, config_with(config, {"baseline": ["scale_factor", "misalignment", "bias"]}),
                       truth_path=campaign[0].parent / "truth.json")
    return out, npz


@pytest.fixture(scope="session")
def tiny_run(tiny, tmp_path_factory, config):
    """The tiny campaign through every step with the baseline model."""
    return _baseline_run(tiny, tmp_path_factory, config, "tiny_run")


@pytest.fixture(scope="session")
def mom_run(mom, tmp_path_factory, config):
    """The default campaign through every step with the baseline model."""
    return _baseline_run(mom, tmp_path_factory, config, "mom_run")
