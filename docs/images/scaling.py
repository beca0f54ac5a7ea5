"""Cost against telemetry length on log-log axes (docs/images/scaling.png), from the times
`benchmarks/scaling.py --csv docs/images/scaling.csv` measured. From the repository's root:

    python benchmarks/scaling.py --csv docs/images/scaling.csv && python docs/images/scaling.py
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

HERE = Path(__file__).parent


def main():
    table = pd.read_csv(HERE / "scaling.csv")
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for i, (stage, rows) in enumerate(table.groupby("stage", sort=False)):
        x, y = rows["st_samples"].to_numpy(), rows["seconds"].to_numpy()
        slope = np.log(y[-1] / y[0]) / np.log(x[-1] / x[0])
        ax.loglog(x, y, "o-", color=f"C{i}", label=f"{stage} (slope {slope:.2f})")
    x = np.array([table["st_samples"].min(), table["st_samples"].max()])
    ax.loglog(x, table["seconds"].max() * x / x[-1], "k--", lw=1, label="linear (slope 1)")
    ax.set_xlabel("star-tracker samples (the default campaign flown 1, 2, 4, 8 times)")
    ax.set_ylabel("wall time, one BLAS thread (s)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1))
    ax.grid(True, which="both", lw=0.3)
    fig.savefig(HERE / "scaling.png", dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()
