"""Rule ``preprocess``: a campaign's maneuvers sliced and propagated nominally, each with its
table and figure. One job per campaign: the work per maneuver is a fraction of a second, and a
process per maneuver spent most of its time starting up and reading the whole campaign again."""

from pathlib import Path

from scipy.spatial.transform import Rotation

from gyrocal.checks import consistency
from gyrocal.inference import preprocess
from gyrocal.io import telemetry
from gyrocal.io.outputs import atomic_dir, write_csv
from gyrocal.pipeline.steps.common import read_json
from gyrocal.report import figures as plots


def run(campaign_dir, input_json, out_dir, figures=True, processes: int = 1, campaign=None) -> list:
    """Slice every maneuver of the campaign (in its order), leaving out the star-tracker outliers
    that validation listed; propagate every channel set nominally; write ``<id>.npz``, ``<id>.csv``
    and (unless ``figures`` is false: the validation study reads none) ``<id>.png`` into
    ``out_dir``, whole or not at all. The figures, most of the step's time, are drawn by
    ``processes`` processes (`plots.render_all`). ``campaign``: the directory's campaign as
    `telemetry.read_campaign` read it, where the caller has it. Returns the ``.npz`` paths."""
    info = read_json(input_json)
    if campaign is None:
        campaign = telemetry.read_campaign(campaign_dir)
    if info["mounting"]:
        campaign = consistency.aligned(campaign, Rotation.from_quat(info["mounting"]["quat"]))
    outliers = [o["time_s"] for o in info["star_tracker_outliers"]]
    with atomic_dir(out_dir) as tmp:
        drawings = []
        for m in campaign.maneuvers:
            data = preprocess.slice_maneuver(campaign, m.id, outliers)
            table = preprocess.error_table(data)
            data.save(tmp / f"{m.id}.npz")
            write_csv(table, tmp / f"{m.id}.csv")
            if figures:
                drawings.append(("maneuver_figure", (table, f"{campaign.name}: {m.id} ({m.turn}), nominal parameters")))
        for m, image in zip(campaign.maneuvers, plots.render_all(drawings, processes, dpi=plots.SAVE_DPI)):
            (tmp / f"{m.id}.png").write_bytes(image)
    return [Path(out_dir) / f"{m.id}.npz" for m in campaign.maneuvers]
