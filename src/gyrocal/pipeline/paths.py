"""The paths of a run, written once: every file a campaign's run reads or writes, and every file of
one model variant. The rules, the study and the tests all take them from here; a root may hold
Snakemake wildcards (``results/{campaign}``), which pass through unchanged."""

from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

__all__ = ["CALIBRATION_FILES", "GM_CLOCK", "MODEL_FILES", "REFERENCE_INTERVAL", "STEP_FILES", "CampaignPaths", "ModelPaths",
           "maneuver_files"]

REFERENCE_INTERVAL = "reference_interval.json"
"""The preprocess step's record of the reference interval it used and why, in its folder."""

GM_CLOCK = "gm_clock.json"
"""... and of the reference error's clock it chose and why, where campaign.yaml asks it to choose."""


def maneuver_files(folder, ids, ext: str = "npz") -> list:
    """The preprocess step's files of one kind (``npz``, ``csv``, ``png``) of the maneuvers ``ids``, in
    that order, in its folder ``folder`` (a rule's input ``preprocessed``)."""
    return [f"{folder}/{m}.{ext}" for m in ids]


def _under_root(name: str, doc: str = "") -> property:
    """A path property: ``name`` under the object's ``root``."""
    return property(lambda self: f"{self.root}/{name}", doc=doc or f"``{name}``")


@dataclass(frozen=True)
class ModelPaths:
    """One model variant's files, under ``<campaign results>/<model>/`` (docs/interface.md section 5)."""

    root: str

    point_estimate = _under_root("point_estimate.npz")
    posterior = _under_root("posterior.nc")
    summary = _under_root("posterior_summary.csv")
    fit = _under_root("fit.csv")
    sampler = _under_root("sampler.json")
    elpd_maneuvers = _under_root("elpd_maneuvers.csv")
    elpd_blocks = _under_root("elpd_blocks.csv")
    orthogonality = _under_root("orthogonality.csv", "The channel sets' non-orthogonality, beside ``calibration.csv`` "
                                                     "(`inferencedata.orthogonality_table`).")
    calibration = _under_root("calibration.csv")
    correction = _under_root("correction.json")
    diagnostics = _under_root("diagnostics.json")
    extension = _under_root("extension.json", "An extended variant's: the model it extends, the effect it adds, "
                                              "and why (`gyrocal.criticism.extension`).")
    refusal = _under_root("refused.json", "Where the variant was refused or skipped: the step and the reason "
                                          "(`gyrocal.pipeline.steps.common.variant_step`).")


STEP_FILES = {"point_estimate": ("point_estimate",),
              "posterior": ("posterior", "summary", "fit", "sampler", "elpd_maneuvers", "elpd_blocks",
                            "orthogonality", "calibration", "correction"),
              "diagnostics": ("diagnostics",)}
"""A model variant's result files (`ModelPaths` names) by the step whose job writes them, the steps in the
order they run, as their rules declare them: a refused variant's from that step on hold its refusal
record. The posterior's job ends with the calibration's (`CALIBRATION_FILES`)."""

CALIBRATION_FILES = ("calibration", "correction")
"""The posterior job's files that its calibrate step writes, from the posterior's summary."""

MODEL_FILES = tuple(f for files in STEP_FILES.values() for f in files)
"""A model variant's result files, by their `ModelPaths` name, in the order its steps write them."""


@dataclass(frozen=True)
class CampaignPaths:
    """One campaign's files, under ``results/<campaign>/``."""

    root: str

    input_json = _under_root("input.json", "What validation read and found (``input.json``).")
    classic = _under_root("classic.csv")
    preprocess = _under_root("preprocess", "The preprocess step's folder: ``<maneuver>.{npz,csv,png}`` each.")
    reference_interval = _under_root(f"preprocess/{REFERENCE_INTERVAL}",
                                     "The reference interval the preprocess step used, and why.")
    gm_clock = _under_root(f"preprocess/{GM_CLOCK}", "The reference error's clock the preprocess step chose, and why.")
    comparison = _under_root("model_comparison.csv")
    comparison_figure = _under_root("model_comparison.png")
    report = _under_root("report.html")
    verdict = _under_root("verdict.json")
    simulated = _under_root("simulated/campaign", "Where a simulated campaign's directory goes.")
    truth = _under_root("simulated/truth.json")

    @classmethod
    def under(cls, root) -> "CampaignPaths":
        """The paths under a folder given as a string or a `pathlib.Path`."""
        return cls(str(root))

    def model(self, name: str) -> ModelPaths:
        return ModelPaths(f"{self.root}/{name}")

    def maneuvers(self, ids, ext: str = "npz") -> list:
        """The preprocessed files of one kind of the maneuvers ``ids``, in that order."""
        return maneuver_files(self.preprocess, ids, ext)

    def per_model(self, models) -> SimpleNamespace:
        """Every model file of the variants ``models``, by its `ModelPaths` name, a list in their order
        each: what the report rule's ``snakemake.input`` gives the comparison and the report."""
        return SimpleNamespace(**{name: [getattr(self.model(m), name) for m in models] for name in MODEL_FILES})

    def outputs(self, models) -> list:
        """Everything a campaign's run leaves, as the workflow's targets: every file a rule declares, the
        intermediate ones too, so that a plain rerun redoes the step whose file went missing, and every
        step after it (Snakemake redoes no job for a missing file that nothing it must build needs)."""
        out = [self.input_json, self.preprocess]
        for name in models:
            m = self.model(name)
            out += [getattr(m, f) for f in MODEL_FILES]
        return out + [self.classic, self.comparison, self.comparison_figure, self.report, self.verdict]

    def missing_in_folders(self, ids, simulated: bool) -> list:
        """The files missing from a step's output folder that exists (the preprocessed maneuvers
        ``ids``; the simulated campaign, where ``simulated``), each with its folder: Snakemake takes a
        folder that exists for complete, and redoes the step that writes it only once it is gone."""
        folders = [(self.preprocess, [p for ext in ("npz", "csv", "png") for p in self.maneuvers(ids, ext)])]
        if simulated:
            folders.insert(0, (self.simulated, [f"{self.simulated}/{name}" for name in
                                                            ("campaign.yaml", "star_tracker.csv", "gyro.csv")]))
        return [(path, folder) for folder, files in folders if Path(folder).is_dir()
                for path in files if not Path(path).is_file()]

    def mkdirs(self, models=()):
        """Create the campaign's folder and its models' (outside Snakemake, which creates its own)."""
        for folder in [self.root] + [self.model(m).root for m in models]:
            Path(folder).mkdir(parents=True, exist_ok=True)
