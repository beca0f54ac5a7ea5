"""What the review is made from (`ReviewInputs`: the files the report step read, and the verdict's
findings) and what its template shows (`ReviewContext`: every table and figure, ready to render)."""

from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
from markupsafe import Markup

__all__ = ["FLIGHT_WORDS", "LAB_WORDS", "CorrectionSet", "ReviewContext", "ReviewInputs", "campaign_words"]


@dataclass(frozen=True)
class ReviewInputs:
    """The reviewed model's files, the campaign's, and the findings of `gyrocal.criticism.verdict`."""

    model: str
    """The reviewed model's name."""
    spec: object
    """Its `gyrocal.model.spec.ModelSpec` (the point estimate's, with the priors its posterior used)."""
    maneuvers: list
    """The campaign's preprocessed maneuvers."""
    tables: list
    """Their preprocess tables (``preprocess/<maneuver>.csv``), in the same order."""
    calibration: pd.DataFrame
    """The model's ``calibration.csv``."""
    fit: pd.DataFrame
    """The model's ``fit.csv``."""
    posterior: object
    """The model's posterior, as arviz InferenceData."""
    diagnostics: dict
    sampler: dict
    correction: dict
    """``correction.json``, as written to ``correction_path``."""
    correction_path: Path
    comparison: pd.DataFrame
    """``model_comparison.csv``."""
    info: dict
    """``input.json``: the campaign's name, rows read, warnings, outliers, mounting and checksums."""
    config: dict
    """The whole config."""
    findings: list
    """The checks behind the verdict, as `gyrocal.finding.Finding` (`gyrocal.criticism.verdict.checks`)."""
    effect_table: pd.DataFrame
    """The end-of-maneuver error before and after the correction (`gyrocal.criticism.verdict.estimate_effect`)."""
    truth: dict | None = None
    """The simulation's true parameters (channel -> parameter -> value), or None for real data."""
    refused: list = field(default_factory=list)
    """The refusal records (``<model>/refused.json``) of the variants refused or skipped."""
    reference_interval: dict | None = None
    """``preprocess/reference_interval.json``: the reference interval used and why; None for runs before it."""
    gm_clock: dict | None = None
    """``preprocess/gm_clock.json``: the reference error's clock chosen and why; None where campaign.yaml states it."""
    loop: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The loop's error before and after each fitted step (`gyrocal.criticism.extension.before_after`)."""
    loop_steps: list = field(default_factory=list)
    """Every step of the loop (``extension.json``), fitted or not, with why."""
    disagreement: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The model disagreement behind the sensitivity check (`gyrocal.criticism.modelchoice.disagreement_table`)."""
    orthogonality: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The model's ``orthogonality.csv``: each channel set's non-orthogonality (`gyrocal.model.orthogonality`)."""
    flown: pd.DataFrame | None = None
    """The scale factors as uplinked, at the campaign's rates, where the model's changes with the rate
    (`gyrocal.criticism.uplinked.uplinked_intervals`); None where it does not."""


@dataclass(frozen=True)
class CorrectionSet:
    """One channel set of the correction to uplink, as the report shows it."""

    in_loop: bool
    channels: list
    matrices: dict
    """``matrix_pos``, ``matrix_neg`` and ``misalignment_correction`` as tables of 9-decimal text."""
    scale_correction_pos: str
    scale_correction_neg: str


FLIGHT_WORDS = {"kind": "flight", "review": "pre-uplink review", "axis": "spacecraft axis",
                "correction": "The correction to uplink", "first_set": "In-loop", "other_set": "Redundant",
                "first_set_figure": "in-loop set", "reference": "star tracker",
                "reference_adj": "Star-tracker"}
"""The report's words for a flight campaign: the paper's spacecraft, its uplink and in-loop channels."""
LAB_WORDS = {"kind": "lab", "review": "calibration review", "axis": "body axis",
             "correction": "The correction to apply", "first_set": "First", "other_set": "Other",
             "first_set_figure": "first channel set", "reference": "reference",
             "reference_adj": "Reference"}
"""...and for a lab's (free motion, an imported recording): no spacecraft, no uplink, no onboard loop."""


def campaign_words(maneuvers) -> dict:
    """`LAB_WORDS` for a campaign with any free-motion maneuver (a lab's reference, an importer's
    recordings), `FLIGHT_WORDS` otherwise."""
    return LAB_WORDS if any(getattr(m, "axis", "") is None for m in maneuvers) else FLIGHT_WORDS


@dataclass(frozen=True)
class ReviewContext:
    """Everything the review template shows: tables as DataFrames, figures as embedded ``<img>``."""

    campaign: str
    model: str
    effects: list
    version: str
    verdict: str
    """``GO`` or ``NO-GO``, from `gyrocal.criticism.verdict.verdict` of ``findings``."""
    findings: list
    simulated: bool
    tables: dict
    """The paper's tables 1-3 (`gyrocal.report.review.paper_tables`)."""
    maneuver_figures: dict
    """Per maneuver id: its fit and residual figures."""
    posterior_figures: Markup
    convergence: pd.DataFrame
    confounded: pd.DataFrame
    correlation_max: float
    resolution: pd.DataFrame
    """Per channel its terms and combinations against their priors (`gyrocal.report.resolution`)."""
    resolution_sentences: list
    """One sentence per channel: what is resolved, what is not, and which maneuver would resolve it."""
    resolution_uplinked: bool
    """Whether the resolution's scale factors are the uplinked ones, at the campaign's rates (`ReviewInputs.flown`)."""
    resolved_ratio_max: float
    prior_directions: pd.DataFrame
    """The directions of the channel parameters left to the prior."""
    mounting_separability: pd.DataFrame
    """With an estimated mounting, which misalignment combinations it takes up; empty otherwise."""
    orthogonality: pd.DataFrame
    """Each channel set's non-orthogonality (``orthogonality.csv``), beside the channels' ``sf_mean``."""
    diagnostics: dict
    noise: pd.DataFrame
    """Each sampled noise scale beside the stated one (`gyrocal.report.noisemodel.noise_table`)."""
    noise_clock: str
    """What the correlated part's time means on its clock, in words; empty for white reference noise."""
    misfit_checks: pd.DataFrame
    ranking: pd.DataFrame
    comparison: pd.DataFrame
    comparison_figure: Markup
    convention: str
    correction_path: str
    correction_sets: list
    """`CorrectionSet` per channel set, in-loop first."""
    effect_table: pd.DataFrame
    mounting: str
    reference_interval: str
    """The reference interval used and why, in words."""
    accounting: pd.DataFrame
    outliers: pd.DataFrame
    warnings: list
    renormalised: int
    unit_norm_tol: float
    checksums: str
    """``input.json``'s SHA-256 of each input file, as indented JSON."""
    sampler: dict
    acceptance: float
    """The sampler's mean acceptance fraction."""
    config: str
    """The whole config as YAML."""
    channel_kind: str = "gyro"
    """What the campaign's channels are called: ``DTG`` where campaign.yaml gives each a ``dtg:``."""
    reviewed_why: str = ""
    """Why the model-choice rule reviews this variant (`gyrocal.criticism.modelchoice.reviewed_reason`)."""
    refused: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The variants refused or skipped: model, status, step, reason."""
    words: dict = field(default_factory=lambda: dict(FLIGHT_WORDS))
    """The words that fit the campaign (`campaign_words`): a flight's (spacecraft axes, the correction to
    uplink, the in-loop set) or a lab's (body axes, the correction to apply, the first set)."""
    loop: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The loop's error before and after each fitted step; empty where none was fitted."""
    loop_steps: list = field(default_factory=list)
    """Every step of the loop, fitted or not, with why (``extension.json``)."""
    disagreement: pd.DataFrame = field(default_factory=pd.DataFrame)
    """The model disagreement: pair, term, difference, what would separate them; empty where they agree."""

