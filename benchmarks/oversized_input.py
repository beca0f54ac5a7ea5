"""`gyrocal validate` on a gyro file far larger than its campaign needs (2 GiB by default): the time
and peak memory of the refusal. Prints figures, asserts nothing.

    python benchmarks/oversized_input.py [--gib 2]

The tiny test campaign is simulated into a temporary folder and its gyro file padded with rows of
later times, as a logger left running would write; validate runs as its own process.
"""

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gyrocal.simulation import simulate

ROOT = Path(__file__).resolve().parents[1]
ROWS_AT_ONCE = 100_000


def padded(gyro: Path, size_bytes: int):
    """Append rows, the last row's values at later times, until the file holds ``size_bytes``."""
    lines = gyro.read_text().splitlines()
    first, second, last = (row.split(",") for row in (lines[1], lines[2], lines[-1]))
    step_s, t_s, values = float(second[0]) - float(first[0]), float(last[0]), ",".join(last[1:])
    size = gyro.stat().st_size
    with open(gyro, "a") as out:
        while size < size_bytes:
            times = t_s + step_s * (1 + np.arange(ROWS_AT_ONCE))
            block = "".join(f"{t:.6f},{values}\n" for t in times)
            out.write(block)
            size += len(block)
            t_s = times[-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gib", type=float, default=2.0, help="the gyro file's size, GiB")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        simulate.run(ROOT / "tests" / "data" / "tiny.yaml", Path(tmp))
        campaign = Path(tmp) / "campaign"
        padded(campaign / "gyro.csv", int(args.gib * 2**30))
        t0 = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "gyrocal.pipeline.cli", "validate", str(campaign)],
                             capture_output=True, text=True)
        wall_s = time.perf_counter() - t0
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        size_gib = (campaign / "gyro.csv").stat().st_size / 2**30
    said = (run.stderr or run.stdout).strip().replace(tmp, "TMP")
    print(f"gyro.csv {size_gib:.2f} GiB: validate exit {run.returncode} in {wall_s:.2f} s, peak RSS {peak_mb:.0f} MB")
    print(f"  {said}")


if __name__ == "__main__":
    main()
