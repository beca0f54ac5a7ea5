"""Step ``classic``, the last of the preprocess rule's job: the paper's method over every maneuver,
each maneuver's bias from its holds where they allow, each value with its sd from the stated noise."""

import logging

from gyrocal.inference.fit import classic
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.io.outputs import write_csv
from gyrocal.model import spec
from gyrocal.pipeline.steps.common import load_maneuvers, read_json

__all__ = ["run"]

log = logging.getLogger("gyrocal")


def run(maneuver_files, input_json, out_csv, noise: dict):
    """The paper's method over every maneuver (``maneuver_files``, the preprocessed ``.npz`` in the campaign's
    order), once per campaign, into ``out_csv``; ``noise``: the config's noise knowledge, where
    ``campaign.yaml`` (as ``input_json`` records it) is silent."""
    maneuvers = load_maneuvers(maneuver_files)
    stated = noise_knowledge(read_json(input_json), noise)
    table = classic.classic_table(maneuvers, spec.baseline(maneuvers[0].channels), "auto", stated,
                                  classic.PIPELINE_ITERATIONS)
    for note in dict.fromkeys(n for n in table["note"] if n):
        log.warning("classic: %s", note)
    write_csv(table, out_csv)
