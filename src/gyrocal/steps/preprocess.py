"""Rule ``preprocess``: one maneuver sliced and propagated nominally, with its table and figure."""

from scipy.spatial.transform import Rotation

from .. import consistency, plots, preprocess, telemetry
from ..outputs import write_csv, write_with
from .common import read_json


def run(campaign_dir, input_json, maneuver_id, out_npz, out_csv, out_png):
    """Slice one maneuver, leaving out the star-tracker outliers that validation listed;
    propagate every channel set nominally, save table and figure (none when ``out_png`` is None:
    the validation study reads no figure)."""
    info = read_json(input_json)
    campaign = telemetry.read_campaign(campaign_dir)
    if info["mounting"]:
        campaign = consistency.aligned(campaign, Rotation.from_quat(info["mounting"]["quat"]))
    outliers = [o["time_s"] for o in info["star_tracker_outliers"]]
    data = preprocess.slice_maneuver(campaign, maneuver_id, outliers)
    table = preprocess.error_table(data)
    write_with(data.save, out_npz)
    write_csv(table, out_csv)
    if out_png is None:
        return
    m = campaign.maneuver(maneuver_id)
    fig = plots.maneuver_figure(table, f"{campaign.name}: {m.id} ({m.turn}), nominal parameters")
    write_with(lambda handle: plots.save(fig, handle), out_png)
