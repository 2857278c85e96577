#!/usr/bin/env python3
"""Plots of `clothbake report error-time` (docs/rendering.md, "Error against run time").

Usage: plot_error_time.py DIR

Reads DIR/error-time.csv and DIR/error-time.json (written by the report) and writes
  DIR/error-time.png, .svg  relMSE against seconds, log-log, one curve per method: against the
                            path-traced truth (when the report has it) and against the reference,
                            the multi-scale operating point (2 spp) and brute force's equal-error
                            point marked on the latter;
  DIR/grid.png              [truth |] reference | multi-scale 2 spp | brute force at equal
                            time | brute force at equal error, and below each render its
                            false-colour relative-error map, from the PNGs the report left in
                            DIR/images/.
Needs python3-matplotlib (Debian); exits 1 with a message without it.
"""

import csv
import json
import os
import sys
from typing import Any


def ring(ax: Any, seconds: float, relmse: float, marker: str, colour: str, text: str) -> None:
    """An open marker of `marker` and `colour` at (seconds, relmse), labelled `text`."""
    ax.scatter(
        [seconds],
        [relmse],
        s=120,
        marker=marker,
        facecolors="none",
        edgecolors=colour,
        zorder=5,
        label=text,
    )


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 1
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_error_time.py: python3-matplotlib is not installed", file=sys.stderr)
        return 1
    out = sys.argv[1]
    with open(os.path.join(out, "error-time.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out, "error-time.json")) as f:
        doc = json.load(f)
    summary = doc.get("summary", {})

    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    # One panel per judge: the path-traced truth (when the report rendered it) and the reference.
    judges = [("relmse", "relMSE against the reference (compared pixels)")]
    if any(r.get("relmse_truth") for r in rows):
        judges.insert(0, ("relmse_truth", "relMSE against the path-traced truth (every pixel)"))
    fig, axes = plt.subplots(1, len(judges), figsize=(6.4 * len(judges), 4.6), squeeze=False)
    for ax, (column, label) in zip(axes[0], judges, strict=True):
        for m in methods:
            pts = sorted(
                (float(r["seconds"]), float(r[column]), int(r["spp"]))
                for r in rows
                if r["method"] == m and r.get(column) and float(r[column]) > 0
            )
            if not pts:
                continue
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", label=m)
            for s, e, spp in pts:
                ax.annotate(str(spp), (s, e), textcoords="offset points", xytext=(3, 3), fontsize=7)
        op = summary.get("operating_point")
        if op and column == "relmse":
            ring(ax, op["seconds"], op["relmse"], "o", "k", "multiscale at 2 spp")
            eq = summary.get("brute_at_equal_error")
            if eq and eq.get("seconds"):
                ring(ax, eq["seconds"], op["relmse"], "s", "r", "brute force, equal error")
        ax.set_xlabel("render time (s, wall, this machine)")
        ax.set_ylabel(label)
        ax.set_title(os.path.basename(doc.get("scene", "")) + ": error against run time")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(out, "error-time." + ext), dpi=120)
    plt.close(fig)

    panels = doc.get("grid", [])
    if panels:
        fig, axes = plt.subplots(2, len(panels), figsize=(3.2 * len(panels), 6.6), squeeze=False)
        for k, p in enumerate(panels):
            for row, key in ((0, "image"), (1, "error")):
                a = axes[row][k]
                a.axis("off")
                path = os.path.join(out, p.get(key, "")) if p.get(key) else None
                if path and os.path.exists(path):
                    a.imshow(
                        mpimg.imread(path),
                        cmap=None if row == 0 else "inferno",
                        interpolation="nearest",
                    )
                if row == 0:
                    a.set_title(p["label"], fontsize=8)
                elif path:  # the reference and the truth have no error panel: no title either
                    scale = p.get("error_scale", 0)
                    a.set_title(f"relative error (0 to {scale:.2g})", fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "grid.png"), dpi=110)
        plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
