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


LONGEST_FIRST = ("test_workflow.py", "test_report.py", "test_interval.py", "test_resume.py",
                 "test_realdata.py", "test_freemotion.py", "test_robustness.py", "test_looexact.py",
                 "test_pipeline.py", "test_properties.py", "test_spec.py", "test_refusals.py", "test_plan.py",
                 "test_degenerate.py", "test_jitter_correlated.py", "test_joint.py", "test_combinations.py",
                 "test_variants.py")
"""The fast tier's longest files, longest first (their times under ``--durations``): run before the
others, so that the two xdist workers (``--dist loadfile --no-loadscope-reorder``, tests/run.sh) end
on short files instead of one of them running a long file alone at the end."""


def pytest_collection_modifyitems(items):
    """The files of `LONGEST_FIRST` first, in its order, then the rest as collected; a file's tests keep
    their order."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def once_per_run(tmp_path_factory, name, make):
    """``make(directory)`` (its result JSON) made once for the whole test run. A session fixture is made
    once per pytest-xdist worker; here the first worker to ask makes it in the workers' common
    temporary directory while holding a lock, and the others wait on the lock and take what it made."""
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if worker is None:
        return make(tmp_path_factory.mktemp(name))
    import fcntl
    import shutil
    root = tmp_path_factory.getbasetemp().parent / "shared"  # .../pytest-N/, above each worker's popen-gwK/
    root.mkdir(exist_ok=True)
    done = root / f"{name}.json"
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)   # released when the file closes, by a worker that fails too
        if not done.exists():
            directory = root / name
            shutil.rmtree(directory, ignore_errors=True)
            directory.mkdir()
            done.write_text(json.dumps(make(directory)))
        return json.loads(done.read_text())


def _simulated(tmp_path_factory, name, scenario):
    def make(out):
        simulate.run(scenario, out)
        return str(out / "campaign")

    campaign = Path(once_per_run(tmp_path_factory, name, make))
    return campaign, json.loads((campaign.parent / "truth.json").read_text())


@pytest.fixture(scope="session")
def tiny(tmp_path_factory):
    """A small simulated campaign directory and its truth (one for the whole run: `once_per_run`)."""
    return _simulated(tmp_path_factory, "tiny", DATA / "tiny.yaml")


@pytest.fixture(scope="session")
def mom(tmp_path_factory):
    """The default Mars-Orbiter-like campaign (paper's truth) and its truth (one for the whole run)."""
    return _simulated(tmp_path_factory, "mom", ROOT / "config" / "scenarios" / "mom.yaml")


def truth_vector(channels, truth):
    """The simulation's true channel model (SI), with its biases."""
    from gyrocal.model.spec import baseline
    from gyrocal.model.units import deg_h_to_rad_s
    params = baseline(channels).params_from_contract(truth["parameters"])
    params.bias_rad_s[:] = deg_h_to_rad_s([truth["parameters"][c.name]["bias_deg_h"] for c in channels])
    return params


def run_campaign(campaign_dir, out, cfg, models=("baseline",), truth_path=None, figures=False):
    """Every workflow step in the order the rules run them (`gyrocal.pipeline.run.run_campaign`);
    the preprocessed maneuvers' files, in the campaign's order. No figures unless ``figures``: no
    maneuver figure files (most of the preprocess step's time), and the review without its figures
    (``report.figures: false``, half the report step's)."""
    from gyrocal.pipeline import run
    from gyrocal.pipeline.paths import CampaignPaths
    cfg = copy.deepcopy(cfg)
    cfg.setdefault("report", {})["figures"] = figures
    paths = CampaignPaths.under(out)
    ids = run.run_campaign(campaign_dir, paths, cfg, models, truth_path, figures)
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


def _baseline_run(campaign, out, config, figures=False):
    npz = run_campaign(campaign[0], out, config_with(config, {"baseline": ["scale_factor", "misalignment", "bias"]}),
                       truth_path=campaign[0].parent / "truth.json", figures=figures)
    return out, npz


@pytest.fixture(scope="session")
def tiny_run(tiny, tmp_path_factory, config):
    """The tiny campaign through every step with the baseline model: one run for the whole test run
    (`once_per_run`), which eight test files read."""
    def make(out):
        run = _baseline_run(tiny, out, config, figures=True)   # test_pipeline reads a maneuver's figure
        return [str(run[0]), [str(p) for p in run[1]]]

    out, npz = once_per_run(tmp_path_factory, "tiny_run", make)
    return Path(out), [Path(p) for p in npz]


@pytest.fixture(scope="session")
def tiny_short_run(tiny, short_chains, tmp_path_factory):
    """The tiny campaign through every step with the baseline model at short chains (the review's
    tables and the outputs' rows and columns, not convergence): one run for the whole test run."""
    def make(out):
        run = _baseline_run(tiny, out, short_chains)
        return [str(run[0]), [str(p) for p in run[1]]]

    out, npz = once_per_run(tmp_path_factory, "tiny_short_run", make)
    return Path(out), [Path(p) for p in npz]


@pytest.fixture(scope="session")
def mom_run(mom, tmp_path_factory, config):
    """The default campaign through every step with the baseline model, its review with its figures
    (the browser test shows it as a user sees it)."""
    return _baseline_run(mom, tmp_path_factory.mktemp("mom_run"), config, figures=True)
