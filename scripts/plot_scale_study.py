#!/usr/bin/env python3
"""Speed-up against footprint size, from `footprint_scale_study --csv` (docs/performance.md).

Usage: plot_scale_study.py STUDY.csv -o OUT.png

One panel per asset (columns) and order (rows): each candidate's equal-error speed-up in time over footprint brute
force (log) against the footprint's side in weave repeats (log); hollow markers where the figure is
a bound (brute force never reached the candidate's error in its sweep, or was more accurate at 1
spp), crosses where every estimate was brute force's (1 by definition). Lines at 1x and at the 3x
target. Needs python3-matplotlib (Debian); exits 1 without it.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections import defaultdict


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv_path")
    parser.add_argument("-o", "--output", required=True)
    args = parser.parse_args()
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(
            "plot_scale_study.py: python3-matplotlib is not installed", file=sys.stderr
        )
        return 1
    with open(args.csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print(f"plot_scale_study.py: {args.csv_path} has no rows", file=sys.stderr)
        return 1
    panels: dict[tuple[str, str], dict[str, list[dict[str, str]]]] = defaultdict(
        lambda: defaultdict(list)
    )
    for row in rows:
        panels[(row["asset"], row["order"])][row["candidate"]].append(row)
    assets = sorted({asset for asset, _ in panels})
    orders = sorted({order for _, order in panels})
    fig, axes = plt.subplots(
        len(orders),
        len(assets),
        figsize=(4.6 * len(assets), 3.7 * len(orders)),
        squeeze=False,
    )
    for (asset, order), by_candidate in sorted(panels.items()):
        ax = axes[orders.index(order)][assets.index(asset)]
        for candidate, series in by_candidate.items():
            series.sort(key=lambda r: float(r["size_repeats"]))
            x = [float(r["size_repeats"]) for r in series]
            y = [float(r["speedup_time"]) for r in series]
            (line,) = ax.plot(x, y, marker="o", label=candidate)
            for xi, yi, r in zip(x, y, series):
                if r["speedup_time_bound"] == "brute":  # every estimate brute force's
                    ax.plot([xi], [yi], marker="x", color=line.get_color())
                elif r["speedup_time_bound"] != "none":
                    ax.plot(
                        [xi],
                        [yi],
                        marker="o",
                        color="white",
                        markeredgecolor=line.get_color(),
                    )
        ax.axhline(1.0, color="grey", linewidth=0.8)
        ax.axhline(3.0, color="grey", linewidth=0.8, linestyle="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("footprint side (weave repeats)")
        ax.set_ylabel("equal-error speed-up over footprint brute force")
        ax.set_title(f"{asset}, {order} order", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.output, dpi=80)
    return 0


if __name__ == "__main__":
    sys.exit(main())
