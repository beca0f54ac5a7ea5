"""Step ``classic``, the last of the preprocess rule's job: the paper's method over every maneuver."""

from gyrocal.inference import classic
from gyrocal.io.outputs import write_csv
from gyrocal.model import spec
from gyrocal.pipeline.steps.common import load_maneuvers


def run(npz_paths, out_csv):
    """The paper's method over every maneuver, once per campaign."""
    maneuvers = load_maneuvers(npz_paths)
    write_csv(classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels)), out_csv)
