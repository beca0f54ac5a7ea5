"""Propagation speed of a 25-minute maneuver at 10 Hz: prints figures, asserts nothing.

    python benchmarks/kinematics.py
"""

import time

import numpy as np
from scipy.spatial.transform import Rotation

from gyrocal.model import kinematics


def main():
    increments = np.random.default_rng(0).normal(0, 1e-3, (25 * 60 * 10, 3))
    start = Rotation.random(random_state=1)
    runs = 20
    t0 = time.perf_counter()
    for _ in range(runs):
        kinematics.propagate(start, increments)
    scan = (time.perf_counter() - t0) / runs
    t0 = time.perf_counter()
    attitude = start
    for d in increments:
        attitude = attitude * Rotation.from_rotvec(d)
    loop = time.perf_counter() - t0
    print(f"{len(increments)} increments: vectorised scan {scan * 1e3:.1f} ms, "
          f"Python loop of Rotation products {loop * 1e3:.0f} ms, ratio {loop / scan:.0f}x")


if __name__ == "__main__":
    main()
