import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from gyrocal import simulate

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
    from gyrocal.channels import ChannelParams
    return ChannelParams.from_contract(channels, truth["parameters"])
