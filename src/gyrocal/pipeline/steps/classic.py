"""Step ``classic``, the last of the preprocess rule's job: the paper's method over every maneuver."""

from gyrocal.inference import classic
from gyrocal.io.outputs import write_csv
from gyrocal.model import spec
from gyrocal.pipeline.paths import CampaignPaths
from gyrocal.pipeline.steps.common import load_maneuvers

__all__ = ["run"]


def run(paths: CampaignPaths, maneuver_ids):
    """The paper's method over every maneuver, once per campaign."""
    maneuvers = load_maneuvers(paths.maneuvers(maneuver_ids))
    write_csv(classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels)), paths.classic)
