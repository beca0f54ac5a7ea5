"""The axis conventions (docs/images/axes.png): body axes, the MOM gyro channels' input axes and the
star tracker's boresight of the default scenario. From the repository's root: python docs/images/axes.py"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
AXES = {"roll": (1.0, 0.0, 0.0), "pitch": (0.0, 1.0, 0.0), "yaw": (0.0, 0.0, 1.0)}
BODY = {"roll": "x = roll", "pitch": "y = pitch", "yaw": "z = yaw"}
CHANNELS = {"roll": ["dtg1_roll", "dtg3_roll"], "pitch": ["dtg1_pitch", "dtg2_pitch"], "yaw": ["dtg2_yaw", "dtg3_yaw"]}
SPREAD = 0.1
"""Sideways offset of each channel's arrow from its body axis, for legibility only: a channel's input
axis is its body axis turned by its misalignments (arcseconds to arcminutes)."""


def main():
    scenario = yaml.safe_load((ROOT / "config/scenarios/mom.yaml").read_text())
    boresight = np.asarray(scenario["star_tracker"]["boresight_body"], float)
    boresight /= np.linalg.norm(boresight)
    fig = plt.figure(figsize=(6.2, 5.6))
    ax = fig.add_subplot(projection="3d")
    for name, axis in AXES.items():
        ax.quiver(0, 0, 0, *axis, color="k", lw=2, arrow_length_ratio=0.08)
        ax.text(*(1.12 * np.array(axis)), BODY[name], fontsize=11, weight="bold")
        side = np.roll(axis, 1)
        for k, channel in enumerate(CHANNELS[name]):
            start = (k - 0.5) * 2 * SPREAD * side
            length = 0.55 + 0.25 * k
            ax.quiver(*start, *(length * np.array(axis)), color=f"C{k}", lw=1.2, arrow_length_ratio=0.12)
            ax.text(*(start + (length + 0.03) * np.array(axis)), channel, color=f"C{k}", fontsize=8)
    ax.quiver(0, 0, 0, *boresight, color="C3", lw=2, ls="--", arrow_length_ratio=0.08)
    ax.text(*(1.05 * boresight + np.array([0.0, -0.35, 0.0])), "star-tracker\nboresight", color="C3", fontsize=9)
    ax.set(xlim=(-0.2, 1.1), ylim=(-0.6, 1.1), zlim=(-0.1, 1.1), xticks=[], yticks=[], zticks=[])
    ax.view_init(elev=22, azim=35)
    ax.set_title("Body axes, the gyro channels' input axes (MOM: DTG1 roll, pitch; DTG2 yaw, pitch;\n"
                 "DTG3 yaw, roll) and the default scenario's boresight, 30° off yaw toward -pitch", fontsize=9)
    fig.savefig(Path(__file__).with_name("axes.png"), dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()
