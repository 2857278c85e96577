"""Path-traced clothbake scenes in Mitsuba 3 (docs/mitsuba.md, "Examples").

    scripts/mitsuba_example NAME [--spp N] [--method M] [--width W] [-o OUT]

NAME is one of
  draped-sphere  a twill cloth draped over a sphere on a floor, under a point light
  satin-ball     a silk satin ball seen from far (the pixels cover several repeats)
  room           a couch in twill and plain weave, a sheer voile curtain in a window, lit by the
                 sky of examples/scenes/sky.exr through the window and the curtain (5 bounces)

The fabrics are the examples' (examples/fabrics), baked once into the clothbake.mitsuba cache.
Writes OUT.exr (linear radiance) and OUT.png (an sRGB preview) and prints the render time.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

import clothbake.mitsuba as cm

cm.register()
import mitsuba as mi  # noqa: E402  (after register(): the variant)

HERE = Path(__file__).resolve().parent
FABRICS = HERE.parent / "fabrics"
SKY = HERE.parent / "scenes" / "sky.exr"
T = mi.ScalarTransform4f


def cloth(fabric: str, method: str, **scale: float) -> dict[str, Any]:
    return {
        "type": "clothbake",
        "filename": str(cm.fabric_asset(FABRICS / f"{fabric}.toml")),
        "method": method,
        **scale,
    }


def diffuse(value: float | list[float]) -> dict[str, Any]:
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": value}}


def camera(origin: list[float], target: list[float], fov: float, width: int, height: int,
           spp: int) -> dict[str, Any]:  # fmt: skip
    return {
        "type": "perspective",
        "fov": fov,
        "fov_axis": "y",
        "to_world": T().look_at(origin=origin, target=target, up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
        "sampler": {"type": "independent", "sample_count": spp},
    }


def draped_cloth(side: float, radius: float, cells: int, bsdf: dict[str, Any]) -> Any:
    """A square cloth of `side` metres draped over a sphere of `radius` resting on the floor: a
    height field over the floor (the sphere's cap, then a smooth fall to the floor), uv the
    flat cloth's coordinates in metres (so tiles_per_uv is tiles per metre)."""
    g = np.linspace(-side / 2, side / 2, cells + 1)
    x, z = np.meshgrid(g, g, indexing="xy")
    r = np.hypot(x, z)
    cap = np.sqrt(np.maximum(radius**2 - r**2, 0.0)) + radius
    fall = 2 * radius * np.exp(-(((r - 0.55 * radius) / (0.6 * radius)) ** 2))
    # The cap and the fall meet through a smooth maximum and minimum (log-sum-exp over 5 mm and
    # 1 cm): sharp ones made a crease, which vertex normals over cells wider than the fold shaded
    # as a row of dark dots (docs/mitsuba.md).
    fall = -0.01 * np.logaddexp(-fall / 0.01, -(cap + 0.02) / 0.01)
    y = 0.005 * np.logaddexp(np.where(r < 0.7 * radius, cap, 0.0) / 0.005, fall / 0.005) + 0.004
    positions = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    uv = np.stack([x + side / 2, z + side / 2], axis=-1).reshape(-1, 2)
    i = np.arange(cells)
    a = (i[:, None] * (cells + 1) + i[None, :]).reshape(-1)
    faces = np.concatenate(
        [
            np.stack([a, a + cells + 1, a + 1], axis=1),
            np.stack([a + 1, a + cells + 1, a + cells + 2], axis=1),
        ]
    )
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    mesh = mi.Mesh("cloth", len(positions), len(faces), props=props, has_vertex_normals=True,
                   has_vertex_texcoords=True)  # fmt: skip
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(positions.astype(np.float32).reshape(-1))
    params["vertex_texcoords"] = mi.Float(uv.astype(np.float32).reshape(-1))
    params["faces"] = mi.UInt32(faces.astype(np.uint32).reshape(-1))
    params.update()
    mesh.recompute_vertex_normals()
    return mesh


def draped_sphere(method: str, spp: int, width: int) -> dict[str, Any]:
    # uv in metres of flat cloth: tiles_per_uv = 1000 / tile_mm, from the asset (uv_span_mm).
    mesh = draped_cloth(1.2, 0.25, 480, cloth("twill", method, uv_span_mm=1000.0))
    return {
        "type": "scene",
        "integrator": {"type": "clothbake_path", "max_depth": 4},
        "sensor": camera([0.0, 0.75, 1.5], [0.0, 0.22, 0.0], 32, width, width * 3 // 4, spp),
        "cloth": mesh,
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale([3, 3, 1]),
            "bsdf": diffuse(0.4),
        },
        "light": {
            "type": "point",
            "position": [-1.0, 1.6, 1.2],
            "intensity": {"type": "rgb", "value": 6.0},
        },
    }


def satin_ball(method: str, spp: int, width: int) -> dict[str, Any]:
    # Radius 0.2 m, seen from 3 m through a 9 degree lens (examples/scenes/far-satin-sphere.toml):
    # the sphere's u spans 2 pi r and its v pi r, in metres.
    r = 0.2
    return {
        "type": "scene",
        "integrator": {"type": "clothbake_path", "max_depth": 3},
        "sensor": camera([0.0, 0.6, 3.0], [0.0, 0.0, 0.0], 9, width, width, spp),
        "ball": {
            "type": "sphere",
            "radius": r,
            "to_world": T().rotate([1, 0, 0], -90),
            "bsdf": cloth("satin", method, u_span_mm=2000 * np.pi * r, v_span_mm=1000 * np.pi * r),
        },
        # The satin covers an opaque ball: a hollow cloth ball would light its own inside through
        # the front and show it through the back (path-traced noise the far field has no use for).
        "core": {"type": "sphere", "radius": 0.985 * r, "bsdf": diffuse(0.2)},
        "light": {
            "type": "point",
            "position": [-2.0, 2.5, 2.5],
            "intensity": {"type": "rgb", "value": 12.0},
        },
    }


def room(method: str, spp: int, width: int) -> dict[str, Any]:
    """A room 4 m wide, 2.6 m high, its back wall at z = -1.5 with a window 1.6 x 1.2 m, a voile
    curtain just inside it, a couch (twill seat and back, plain-weave cushions) in front."""
    wall = diffuse(0.7)
    scene: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "clothbake_path", "max_depth": 5},
        "sensor": camera([0.6, 1.2, 3.2], [-0.1, 0.9, -1.5], 48, width, width * 3 // 4, spp),
        "sky": {"type": "envmap", "filename": str(SKY), "scale": 2.0},
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale([2, 3, 1]).translate([0, 0, 0]),
            "bsdf": diffuse(0.35),
        },
        "ceiling": {
            "type": "rectangle",
            "to_world": T().translate([0, 2.6, 0]).rotate([1, 0, 0], 90).scale([2, 3, 1]),
            "bsdf": wall,
        },
        "left": {
            "type": "rectangle",
            "to_world": T().translate([-2, 1.3, 0]).rotate([0, 1, 0], 90).scale([3, 1.3, 1]),
            "bsdf": wall,
        },
        "right": {
            "type": "rectangle",
            "to_world": T().translate([2, 1.3, 0]).rotate([0, 1, 0], -90).scale([3, 1.3, 1]),
            "bsdf": wall,
        },
    }
    # The back wall around the window (x in [-0.8, 0.8], y in [0.8, 2.0]).
    for name, (x0, x1, y0, y1) in {
        "back_left": (-2.0, -0.8, 0.0, 2.6),
        "back_right": (0.8, 2.0, 0.0, 2.6),
        "back_below": (-0.8, 0.8, 0.0, 0.8),
        "back_above": (-0.8, 0.8, 2.0, 2.6),
    }.items():
        scene[name] = {
            "type": "rectangle",
            "to_world": T()
            .translate([(x0 + x1) / 2, (y0 + y1) / 2, -1.5])
            .scale([(x1 - x0) / 2, (y1 - y0) / 2, 1]),
            "bsdf": wall,
        }
    # The curtain: 1.8 x 1.4 m of voile 10 cm inside the window, uv in [0, 1] -> 1.8 m along u.
    scene["curtain"] = {
        "type": "rectangle",
        "to_world": T().translate([0, 1.4, -1.4]).scale([0.9, 0.7, 1]),
        "bsdf": cloth("voile", method, u_span_mm=1800.0, v_span_mm=1400.0),
    }
    # The couch: boxes (cube: [-1, 1]^3, uv per face in [0, 1]).
    seat = cloth("twill", method, u_span_mm=1000.0, v_span_mm=1000.0)
    cushions = cloth("plain", method, u_span_mm=600.0, v_span_mm=600.0)
    for name, (centre, half, bsdf) in {
        "seat": ([-0.2, 0.25, 0.2], [0.9, 0.25, 0.4], seat),
        "backrest": ([-0.2, 0.65, -0.15], [0.9, 0.4, 0.12], seat),
        "cushion_left": ([-0.65, 0.58, 0.25], [0.38, 0.08, 0.3], cushions),
        "cushion_right": ([0.25, 0.58, 0.25], [0.38, 0.08, 0.3], cushions),
    }.items():
        scene[name] = {"type": "cube", "to_world": T().translate(centre).scale(half), "bsdf": bsdf}
    return scene


SCENES = {"draped-sphere": draped_sphere, "satin-ball": satin_ball, "room": room}


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("name", choices=sorted(SCENES))
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    parser.add_argument(
        "--method",
        default="multiscale",
        choices=["multiscale", "brute", "reference", "multiscale-paper"],
    )
    parser.add_argument(
        "--width", type=int, default=320, help="image width in pixels (default 320)"
    )
    parser.add_argument(
        "-o", "--output", type=Path, help="output stem (default: NAME in the current folder)"
    )
    args = parser.parse_args()
    stem = args.output or Path(args.name)
    scene = mi.load_dict(SCENES[args.name](args.method, args.spp, args.width))
    start = time.perf_counter()
    image = mi.render(scene, spp=args.spp)
    seconds = time.perf_counter() - start
    bitmap = mi.Bitmap(image)
    bitmap.write(str(stem.with_suffix(".exr")))
    bitmap.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(
        str(stem.with_suffix(".png"))
    )
    print(
        f"{args.name}: {image.shape[1]}x{image.shape[0]}, {args.spp} spp, {args.method}: "
        f"{seconds:.1f} s"
    )
    print(f"wrote {stem.with_suffix('.exr')} and {stem.with_suffix('.png')}")


if __name__ == "__main__":
    main()
