"""The paper's Table 1 measured in Mitsuba 3 against the path-traced truth (docs/mitsuba.md,
"Multi-scale against brute force, path traced").

    PYTHONPATH=build/python .venv/bin/python benchmarks/mitsuba_table1.py SCENE [--truth-spp N]
        [--spp 1,2,4,...] [--width W] [--json OUT.json]

SCENE is one of examples/mitsuba/render_scene.py's scenes. Three renders of it, all through the
plug-in's path tracer with the same bounces:

- the truth: camera rays jittered over each pixel, point footprints, the exact BSDF at each hit
  (method reference), --truth-spp samples per pixel: the image a path tracer converges to;
- brute force: the same rays, the BSDF estimated by one sample (method brute), as a path tracer
  without a multi-scale model renders;
- multi-scale: rays through pixel centres carrying one-pixel differentials, the cloth's first hit
  estimated over its pixel footprint (method multiscale), point footprints after it.

For each spp the relMSE against the truth (the mean over pixels of (x - t)^2 / (t^2 + 1e-4), on
the channel sum) and the render time; the equal-error speedup is brute force's time at the
multi-scale render's error (log-log interpolation between brute force's points, extrapolated with
slope -1 beyond its last) over the multi-scale time. The multi-scale image's bias against the truth
(what a pixel-centre footprint leaves out of the pixel's true preimage) is the floor of its error;
it is reported as the relMSE of its highest-spp render.
"""

from __future__ import annotations

import argparse
import importlib.util
import itertools
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location(
    "render_scene", ROOT / "examples" / "mitsuba" / "render_scene.py"
)
assert spec is not None and spec.loader is not None
scenes = importlib.util.module_from_spec(spec)
spec.loader.exec_module(scenes)
mi: Any = scenes.mi


def load(name: str, method: str, width: int, footprints: bool, centres: bool = False) -> Any:
    description = scenes.SCENES[name](method, 1, width)
    description["integrator"]["footprints"] = footprints
    description["integrator"]["pixel_centres"] = centres
    return mi.load_dict(description)


def render(scene: Any, spp: int, seed: int) -> tuple[NDArray[np.float64], float]:
    start = time.perf_counter()
    image = np.asarray(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
    return image, time.perf_counter() - start


def rel_mse(
    image: NDArray[np.float64], truth: NDArray[np.float64], mask: NDArray[np.bool_] | None = None
) -> float:
    x, t = image.sum(axis=2), truth.sum(axis=2)
    errors = (x - t) ** 2 / (t**2 + 1e-4)
    return float(np.mean(errors if mask is None else errors[mask]))


def interior(truth: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Pixels whose 3 x 3 neighbourhood is all lit in the truth: no silhouette or shadow edge."""
    lit = truth.sum(axis=2) > 1e-3 * truth.sum(axis=2).max()
    inner = lit.copy()
    inner[1:-1, 1:-1] &= lit[:-2, :-2] & lit[:-2, 2:] & lit[2:, :-2] & lit[2:, 2:]
    inner[1:-1, 1:-1] &= lit[:-2, 1:-1] & lit[2:, 1:-1] & lit[1:-1, :-2] & lit[1:-1, 2:]
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    return inner


def equal_error_time(points: list[tuple[float, float]], error: float) -> float:
    """Brute force's time at `error`: log-log interpolation over its (seconds, relMSE) points,
    sorted by time; slope -1 beyond the most accurate one."""
    points = sorted(points)
    for (t0, e0), (t1, e1) in itertools.pairwise(points):
        if e1 <= error <= e0 and e0 > e1:
            f = np.log(e0 / error) / np.log(e0 / e1)
            return float(np.exp(np.log(t0) + f * np.log(t1 / t0)))
    t_last, e_last = points[-1]
    if error < e_last:
        return t_last * e_last / error
    t_first, e_first = points[0]
    return t_first * e_first / error


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("scene", choices=sorted(scenes.SCENES))
    parser.add_argument("--truth-spp", type=int, default=1024)
    parser.add_argument("--spp", default="1,2,4,8,16,32,64")
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    spps = [int(s) for s in args.spp.split(",")]

    truth_scene = load(args.scene, "reference", args.width, footprints=False)
    truth, truth_seconds = render(truth_scene, args.truth_spp, seed=1_000_003)
    inner = interior(truth)
    rows: list[dict[str, Any]] = []
    variants = (("brute", "brute", False, False), ("multiscale", "multiscale", True, False),
                ("multiscale-centres", "multiscale", True, True))  # fmt: skip
    for label, method, footprints, centres in variants:
        scene = load(args.scene, method, args.width, footprints, centres)
        render(scene, 1, seed=0)  # compile the kernels once, outside the timings
        for spp in spps:
            image, seconds = render(scene, spp, seed=7 + spp)
            rows.append(
                {
                    "method": label,
                    "spp": spp,
                    "seconds": seconds,
                    "relmse": rel_mse(image, truth),
                    "relmse_interior": rel_mse(image, truth, inner),
                }
            )
            row = rows[-1]
            print(
                f"{label:18s} {spp:5d} spp {seconds:8.2f} s  relMSE {row['relmse']:.4g}, "
                f"interior {row['relmse_interior']:.4g}",
                flush=True,
            )
    brute = [(r["seconds"], r["relmse"]) for r in rows if r["method"] == "brute"]
    brute_inner = [(r["seconds"], r["relmse_interior"]) for r in rows if r["method"] == "brute"]
    print(f"truth: {args.truth_spp} spp reference, {truth_seconds:.1f} s")
    print("method spp | seconds | relMSE | brute force's time at that error | speedup | interior")
    for r in rows:
        if r["method"] != "brute":
            r["brute_seconds_at_error"] = equal_error_time(brute, r["relmse"])
            r["speedup"] = r["brute_seconds_at_error"] / r["seconds"]
            r["speedup_interior"] = (
                equal_error_time(brute_inner, r["relmse_interior"]) / r["seconds"]
            )
            print(
                f"{r['method']} {r['spp']} | {r['seconds']:.2f} | {r['relmse']:.4g} | "
                f"{r['brute_seconds_at_error']:.2f} | {r['speedup']:.1f}x | "
                f"{r['speedup_interior']:.1f}x"
            )
    if args.json:
        summary = {"scene": args.scene, "width": args.width, "truth_spp": args.truth_spp,
                   "truth_seconds": truth_seconds, "interior_pixels": int(inner.sum()),
                   "rows": rows}  # fmt: skip
        args.json.write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
