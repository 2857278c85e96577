#!/usr/bin/env python3
"""Plots of `clothbake report compression` (docs/compression.md, "Report") and of the study
sat_layout_study (the same CSV columns; "The paper's whole-SAT layout").

Usage: plot_compression.py compression.csv OUTDIR

Reads the CSV the report or the study wrote (one row per compression setting) and writes, as PNG
and SVG:
  compression_size_error  stored size against footprint error (4^2 texels), log-log, per layout;
  compression_error_time  footprint error (4^2) against query time, with raw tables for reference;
  compression_classes     footprint error against footprint side for a few settings.
The paper's operating point (whole-SAT layout, plane+unit normalisation, k=4, r=10; the study's
rows) is marked where the CSV has it.
Needs python3-matplotlib (Debian); exits 1 with a message without it.
"""
import csv
import math
import os
import sys


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 1
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_compression.py: python3-matplotlib is not installed", file=sys.stderr)
        return 1
    path, outdir = sys.argv[1], sys.argv[2]
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print("plot_compression.py: no rows in " + path, file=sys.stderr)
        return 1

    def num(row, key):
        try:
            v = float(row[key])
        except (KeyError, ValueError):
            return math.nan
        return v

    def label(row):
        if row["layout"] == "sat":
            return "paper SAT layout, " + row["normalisation"] + " (N=" + row["resolution"] + ")"
        if row["layout"] == "texel":
            kind = "target error" if row["mode"] == "target" else "k=" + row["clusters"]
            return "texel layout, " + kind + " (N=" + row["resolution"] + ")"
        return "raw tables"

    groups = {}
    for r in rows:
        groups.setdefault(label(r), []).append(r)
    markers = "osD^v<>ph*"

    def scatter(ax, xkey, ykey, xscale=1.0):
        for i, (name, rs) in enumerate(sorted(groups.items())):
            xs = [num(r, xkey) * xscale for r in rs]
            ys = [num(r, ykey) for r in rs]
            ax.plot(xs, ys, markers[i % len(markers)], label=name, alpha=0.8)
        for r in rows:
            if r.get("paper_point") == "1":
                ax.plot(num(r, xkey) * xscale, num(r, ykey), "r*", markersize=18, fillstyle="none")
                ax.annotate("paper: k=4, r=10", (num(r, xkey) * xscale, num(r, ykey)),
                            textcoords="offset points", xytext=(8, 8), color="r")

    def save(fig, name):
        fig.tight_layout()
        for ext in ("png", "svg"):
            fig.savefig(os.path.join(outdir, name + "." + ext), dpi=120)
        plt.close(fig)

    # Size against error: the raw size of the same resolution over the stored size is the ratio.
    fig, ax = plt.subplots(figsize=(8, 5.5))
    scatter(ax, "ratio", "fp_4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(0.01, color="grey", linestyle=":", linewidth=1)
    ax.axvline(200, color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel("compression ratio against raw float tables (higher = smaller)")
    ax.set_ylabel("RMS relative error, 4x4-texel footprints")
    ax.set_title("Size against footprint error")
    ax.legend(fontsize=7)
    save(fig, "compression_size_error")

    fig, ax = plt.subplots(figsize=(8, 5.5))
    scatter(ax, "query_ns", "fp_4")
    ax.set_xscale("log")
    ax.set_yscale("symlog", linthresh=1e-5)
    ax.set_xlabel("query time, all clusters, one thread (ns, CPU time)")
    ax.set_ylabel("RMS relative error, 4x4-texel footprints")
    ax.set_title("Error against run time (SAT-layout rows: unoptimised model)")
    ax.legend(fontsize=7)
    save(fig, "compression_error_time")

    fig, ax = plt.subplots(figsize=(8, 5.5))
    sides = ["fp_1", "fp_2", "fp_4", "fp_8", "fp_16", "fp_64", "fp_tile", "fp_3tiles"]
    names = ["1", "2", "4", "8", "16", "64", "tile", "3 tiles"]
    picked = [r for r in rows if r["layout"] == "texel" and r["mode"] == "target"]
    picked += [r for r in rows if r.get("paper_point") == "1"]
    for r in picked:
        ax.plot(range(len(sides)), [num(r, k) for k in sides], "-o",
                label=label(r) + (" " + r["target"] if r["mode"] == "target" else ""))
    ax.set_xticks(range(len(sides)))
    ax.set_xticklabels(names)
    ax.set_yscale("log")
    ax.axhline(0.01, color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel("footprint side (texels)")
    ax.set_ylabel("RMS relative error")
    ax.set_title("Footprint error by size")
    ax.legend(fontsize=7)
    save(fig, "compression_classes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
