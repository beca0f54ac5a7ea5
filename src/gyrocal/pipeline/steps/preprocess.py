"""Rule ``preprocess``: a campaign's maneuvers sliced and propagated nominally, each with its
table and figure. One job per campaign: the work per maneuver is a fraction of a second, and a
process per maneuver spent most of its time starting up and reading the whole campaign again."""


import dataclasses
import json
import logging

from scipy.spatial.transform import Rotation

from gyrocal import checks
from gyrocal.inference import clock, interval
from gyrocal.inference.noise.covariance import noise_knowledge
from gyrocal.io import telemetry
from gyrocal.io.campaign_yaml import GM_CLOCK_AUTO, GM_CLOCK_KEY, stated_clock_s_per_rad
from gyrocal.io.outputs import atomic_dir, write_csv
from gyrocal.maneuvers import preprocess
from gyrocal.pipeline.paths import GM_CLOCK, REFERENCE_INTERVAL
from gyrocal.pipeline.steps.common import read_json
from gyrocal.report import figures as plots

__all__ = ["run"]

log = logging.getLogger("gyrocal")


def run(campaign_dir, input_json, out_dir, figures=True, processes: int = 1, campaign=None,
        reference_interval_s=0.0, noise=None) -> list:
    """Slice every maneuver of the campaign (in its order), leaving out the star-tracker outliers
    that validation listed (in ``input_json``) and the samples between those kept every ``reference_interval_s``
    seconds (0: every one; ``"auto"``: as `interval.sliced` chooses from the data, with the config's
    ``noise`` where campaign.yaml states none); propagate every channel set nominally; write
    ``<id>.npz``, ``<id>.csv``, ``reference_interval.json``, where campaign.yaml asks the
    reference error's clock to be chosen (``star_tracker: gm_clock_s_per_rad: auto``, `clock.choose`)
    ``gm_clock.json``, and (unless ``figures`` is false: the
    validation study reads none) ``<id>.png`` into the folder ``out_dir``, whole or not at all. The
    figures, most of the step's time, are drawn by ``processes`` processes (`plots.render_all`).
    ``campaign``: the directory's campaign as `telemetry.read_campaign` read it, where the caller has
    it. Returns the maneuver ids, in the campaign's order."""
    info = read_json(input_json)
    if campaign is None:
        campaign = telemetry.read_campaign(campaign_dir)
    if info["mounting"]:
        campaign = checks.aligned(campaign, Rotation.from_quat(info["mounting"]["quat"]))
    outliers = [o["time_s"] for o in info["star_tracker_outliers"]]
    seconds = interval.requested(reference_interval_s)
    choose_clock = stated_clock_s_per_rad(campaign.star_tracker) is None
    stated = noise_knowledge(info, noise) if seconds is None or choose_clock else None
    maneuvers, record = interval.sliced(campaign, outliers, seconds, stated, info["gyro"].get("sensor_class"))
    capped = [m for m, r in record.get("maneuvers", {}).items() if r["interval_s"] != record["interval_s"]]
    log.log(logging.WARNING if capped else logging.INFO, "reference interval: %s", record["reason"])
    clock_record = None
    if choose_clock:
        choice = clock.choose(maneuvers, stated, info["gyro"].get("sensor_class"))
        maneuvers = [dataclasses.replace(d, gm_clock_s_per_rad=choice.clock_s_per_rad) for d in maneuvers]
        clock_record = choice.record()
        log.info("reference error's clock (star_tracker.%s: %s): %s", GM_CLOCK_KEY, GM_CLOCK_AUTO, choice.reason)
    with atomic_dir(out_dir) as tmp:
        drawings = []
        for m, data in zip(campaign.maneuvers, maneuvers):
            table = preprocess.error_table(data)
            data.save(tmp / f"{m.id}.npz")
            write_csv(table, tmp / f"{m.id}.csv")
            if figures:
                drawings.append(("maneuver_figure", (table, f"{campaign.name}: {m.id} ({m.turn}), nominal parameters")))
        (tmp / REFERENCE_INTERVAL).write_text(json.dumps(record, indent=1))
        if clock_record is not None:
            (tmp / GM_CLOCK).write_text(json.dumps(clock_record, indent=1))
        for m, image in zip(campaign.maneuvers, plots.render_all(drawings, processes, dpi=plots.SAVE_DPI)):
            (tmp / f"{m.id}.png").write_bytes(image)
    return [m.id for m in campaign.maneuvers]
