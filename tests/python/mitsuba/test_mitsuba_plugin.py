"""The Mitsuba 3 plug-in (clothbake.mitsuba, docs/mitsuba.md) shades the same model as clothbake.

- its sampling density is the one it samples (Mitsuba's own chi-square test, BSDFAdapter);
- with the reference method at pixel centres it renders what ``clothbake render --method
  reference`` renders, pixel for pixel, on a plane and on a sphere under a point light;
- its multi-scale estimate is unbiased against the reference within its standard error;
- its path tracer agrees with Mitsuba's own ``path`` integrator on the same scene (two renderers
  agreeing), with the cloth's delta lobe and an environment map in play.
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

import clothbake
from conftest import Baked

mitsuba_plugin = pytest.importorskip("clothbake.mitsuba")
mi: Any = pytest.importorskip("mitsuba")
dr: Any = pytest.importorskip("drjit")

# The plane of both renderers: side 2 world units in the xy plane at the origin, facing +z, the
# camera 3 units in front of it looking down -z, the light up and to the left.
PLANE_SIDE = 2.0
TILES_PER_UNIT = 3.0
CAMERA_Z = 3.0
FOV_DEG = 30.0
RESOLUTION = 24
LIGHT = (-1.0, 1.5, 2.5)
INTENSITY = 4.0


@pytest.fixture(scope="module", autouse=True)
def registered() -> None:
    mitsuba_plugin.register()


def bsdf_dict(baked: Baked, method: str, **extra: Any) -> dict[str, Any]:
    return {
        "type": "clothbake",
        "filename": str(baked.path),
        "method": method,
        "tiles_per_uv": TILES_PER_UNIT * PLANE_SIDE,
        **extra,
    }


def plane_scene(baked: Baked, method: str, integrator: dict[str, Any], spp: int = 1) -> Any:
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": integrator,
            "sensor": {
                "type": "perspective",
                "fov": FOV_DEG,
                "fov_axis": "y",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0, 0, CAMERA_Z], target=[0, 0, 0], up=[0, 1, 0]
                ),
                "film": {
                    "type": "hdrfilm",
                    "width": RESOLUTION,
                    "height": RESOLUTION,
                    "rfilter": {"type": "box"},
                },
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "cloth": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().scale([PLANE_SIDE / 2, PLANE_SIDE / 2, 1]),
                "bsdf": bsdf_dict(baked, method),
            },
            "light": {
                "type": "point",
                "position": list(LIGHT),
                "intensity": {"type": "rgb", "value": [INTENSITY] * 3},
            },
        }
    )


def render(scene: Any, seed: int = 0, spp: int = 0) -> NDArray[np.float64]:
    return np.asarray(mi.render(scene, seed=seed, spp=spp), dtype=np.float64)


def test_pixel_footprints_follow_the_rule_of_clothbakes_renderer() -> None:
    # A parallelogram with edges (0.2, 0.1) and (0.0, 0.3) uv units per pixel: bounding box
    # 0.2 x 0.4, area 0.06, so the rectangle is the box shrunk by sqrt(0.06 / 0.08), times the
    # scale 10; zero derivatives give a point, NaN the widest side.
    f = clothbake.pixel_footprints(
        [[0.5, 0.25], [0.1, 0.2], [0.0, 0.0]],
        [[0.2, 0.1], [0.0, 0.0], [np.nan, 0.0]],
        [[0.0, 0.3], [0.0, 0.0], [0.0, 0.0]],
        10.0,
    )
    shrink = np.sqrt(0.06 / 0.08)
    w, h = 2.0 * shrink, 4.0 * shrink
    np.testing.assert_allclose(f[0], [5 - w / 2, 2.5 - h / 2, 5 + w / 2, 2.5 + h / 2], rtol=1e-12)
    np.testing.assert_array_equal(f[1], [1.0, 2.0, 1.0, 2.0])
    assert f[2, 2] - f[2, 0] == clothbake.MAX_FOOTPRINT_TILES
    with pytest.raises(ValueError, match="tiles_per_uv"):
        clothbake.pixel_footprints([[0, 0]], [[0, 0]], [[0, 0]], 0.0)
    with pytest.raises(ValueError, match=r"duv_dx has 2 rows"):
        clothbake.pixel_footprints([[0, 0]], [[0, 0], [0, 0]], [[0, 0]], 1.0)


@pytest.mark.parametrize("view", [(0.0, 0.0, 1.0), (0.6, 0.2, 0.3), (-0.3, 0.5, -0.7)])
def test_sampling_density_passes_mitsubas_chi_square_test(
    baked: Baked, view: tuple[float, ...]
) -> None:
    # At tile point (0.25, 0.25), on a yarn beside a gap, where the sampler picks the delta lobe
    # now and then. The delta lobe is masked out of the context: its draws then come back with
    # sampled_type 0 and count for nothing, so the histogram integrates to 1 - P(delta), as the
    # continuous density does. Every continuous draw counts 1, whatever the BSDF's value there
    # (Mitsuba's BSDFAdapter drops draws whose weight is 0, but the cloth's visibility makes f 0
    # where the density is not).
    ctx = mi.BSDFContext()
    ctx.type_mask = int(mi.BSDFFlags.All) & ~int(mi.BSDFFlags.DeltaTransmission)
    wi = (np.asarray(view) / np.linalg.norm(view)).tolist()
    bsdf = mi.load_dict(bsdf_dict(baked, "reference"))
    uv = [0.25 / (TILES_PER_UNIT * PLANE_SIDE)] * 2

    def interaction(n: int) -> Any:
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(wi)
        si.uv = mi.Point2f(uv)
        return si

    def sample(u: Any) -> tuple[Any, Any]:
        n = dr.width(u)
        bs, _ = bsdf.sample(ctx, interaction(n), u[0], mi.Point2f(u[1], u[2]))
        return bs.wo, dr.select(bs.sampled_type != 0, 1.0, 0.0)

    def pdf(wo: Any) -> Any:
        return bsdf.pdf(ctx, interaction(dr.width(wo)), wo)

    test = mi.chi2.ChiSquareTest(
        domain=mi.chi2.SphericalDomain(),
        sample_func=sample,
        pdf_func=pdf,
        sample_dim=3,
        res=24,
        ires=8,
        sample_count=200_000,
    )
    assert test.run(), test.messages


def clothbake_render(
    clothbake_exe: str,
    folder: Path,
    name: str,
    camera: tuple[float, float, float],
    up: tuple[float, float, float],
    light: tuple[float, float, float],
    cloth: str,
) -> NDArray[np.float64]:
    """`cloth` (a TOML [[object]] body) rendered by clothbake's own renderer with the reference
    method, every pixel from its centre, as linear RGB; the camera looks at the origin."""
    scene = folder / f"{name}.toml"
    scene.write_text(
        f"""[camera]
position = [{camera[0]}, {camera[1]}, {camera[2]}]
look_at = [0.0, 0.0, 0.0]
up = [{up[0]}, {up[1]}, {up[2]}]
fov_deg = {FOV_DEG}
resolution = [{RESOLUTION}, {RESOLUTION}]

[[light]]
type = "point"
position = [{light[0]}, {light[1]}, {light[2]}]
intensity = {INTENSITY}

[[object]]
{cloth}tiles_per_unit = {TILES_PER_UNIT}
"""
    )
    out = folder / f"{name}.exr"
    command = [clothbake_exe, "render", str(scene), "-o", str(out), "--method", "reference"]
    done = subprocess.run(
        [*command, "--edges", "centre"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return np.asarray(mi.Bitmap(str(out)), dtype=np.float64)[..., :3]


def interior_pixels(expected: NDArray[np.float64], image: NDArray[np.float64]) -> Any:
    """The pixels that are cloth in both renders, with their four neighbours."""
    cloth = (expected.sum(axis=2) > 0) & (image.sum(axis=2) > 0)
    interior = cloth.copy()
    interior[1:-1, 1:-1] &= cloth[:-2, 1:-1] & cloth[2:, 1:-1] & cloth[1:-1, :-2] & cloth[1:-1, 2:]
    interior[[0, -1], :] = False
    interior[:, [0, -1]] = False
    return interior


def clothbake_reference(baked: Baked, clothbake_exe: str, folder: Path) -> NDArray[np.float64]:
    """The plane rendered by clothbake's own renderer."""
    plane = (
        f'shape = "plane"\nnormal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n'
        f'size = [{PLANE_SIDE}, {PLANE_SIDE}]\nasset = "{baked.path}"\n'
    )
    return clothbake_render(
        clothbake_exe, folder, "plane", (0.0, 0.0, CAMERA_Z), (0.0, 1.0, 0.0), LIGHT, plane
    )


def test_reference_at_pixel_centres_equals_clothbake_render(
    baked: Baked, clothbake_exe: str, tmp_path: Path
) -> None:
    expected = clothbake_reference(baked, clothbake_exe, tmp_path)
    scene = plane_scene(baked, "reference", {"type": "clothbake_path", "max_depth": 2})
    image = render(scene)
    assert image.shape == expected.shape
    # Interior pixels: those whose footprint lies on the plane in both renders (the plane fills
    # the middle of the picture; a silhouette pixel's centre may fall on either side of the edge
    # in float32 and float64).
    interior = interior_pixels(expected, image)
    assert interior.sum() > 100
    relative = np.abs(image - expected)[interior] / np.maximum(expected[interior], 1e-6)
    assert relative.max() < 1e-3, f"largest relative difference {relative.max():.3g}"


# The sphere of both renderers: radius 1 at the origin, its pole +z. clothbake maps it u = R phi
# from the pole's frame's first vector (x for a pole on +z, docs/scene-format.md) and v = R theta
# from the pole; Mitsuba's sphere u = phi / 2 pi from its local x, v = theta / pi from its local
# +z, so the same tiles are 2 pi R and pi R tiles per unit of Mitsuba's u and v. The camera looks
# at the equator from -y, away from the seam at phi = 0.
SPHERE_CAMERA = (0.0, -4.0, 0.5)
SPHERE_LIGHT = (-2.0, -3.0, 2.0)


def sphere_scene(baked: Baked) -> Any:
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "clothbake_path", "max_depth": 2},
            "sensor": {
                "type": "perspective",
                "fov": FOV_DEG,
                "fov_axis": "y",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=list(SPHERE_CAMERA), target=[0, 0, 0], up=[0, 0, 1]
                ),
                "film": {
                    "type": "hdrfilm",
                    "width": RESOLUTION,
                    "height": RESOLUTION,
                    "rfilter": {"type": "box"},
                },
                "sampler": {"type": "independent", "sample_count": 1},
            },
            "cloth": {
                "type": "sphere",
                "bsdf": {
                    "type": "clothbake",
                    "filename": str(baked.path),
                    "method": "reference",
                    "tiles_per_u": 2 * np.pi * TILES_PER_UNIT,
                    "tiles_per_v": np.pi * TILES_PER_UNIT,
                },
            },
            "light": {
                "type": "point",
                "position": list(SPHERE_LIGHT),
                "intensity": {"type": "rgb", "value": [INTENSITY] * 3},
            },
        }
    )


def clothbake_sphere(baked: Baked, clothbake_exe: str, folder: Path) -> NDArray[np.float64]:
    """The sphere rendered by clothbake's own renderer."""
    sphere = f'shape = "sphere"\naxis = [0.0, 0.0, 1.0]\nradius = 1.0\nasset = "{baked.path}"\n'
    return clothbake_render(
        clothbake_exe, folder, "sphere", SPHERE_CAMERA, (0.0, 0.0, 1.0), SPHERE_LIGHT, sphere
    )


def test_reference_on_a_sphere_equals_clothbake_render(
    baked: Baked, clothbake_exe: str, tmp_path: Path
) -> None:
    expected = clothbake_sphere(baked, clothbake_exe, tmp_path)
    image = render(sphere_scene(baked))
    assert image.shape == expected.shape
    # Interior pixels: the pixel and its four neighbours on the cloth in both renders.
    interior = interior_pixels(expected, image)
    assert interior.sum() > 100
    relative = np.abs(image - expected)[interior] / np.maximum(expected[interior], 1e-6)
    assert relative.max() < 1e-3, f"largest relative difference {relative.max():.3g}"
    # At the silhouette the footprints are the widest (the uv partials grow as 1 / cos of the
    # view) and both renderers clamp them by the same rule, so those pixels agree as well; what
    # may differ there is which pixels' centres hit the sphere (float32 against float64 hit
    # tests), a whole pixel's value, and none does at this size.
    assert ((expected.sum(axis=2) > 0) == (image.sum(axis=2) > 0)).all()
    cloth = expected.sum(axis=2) > 0
    edge = np.abs(image - expected)[cloth] / np.maximum(expected[cloth], 1e-6)
    assert edge.max() < 1e-3, f"largest relative difference on the cloth {edge.max():.3g}"


def test_multiscale_is_unbiased_against_the_reference(baked: Baked) -> None:
    integrator = {"type": "clothbake_path", "max_depth": 2}
    reference = render(plane_scene(baked, "reference", integrator))
    scene = plane_scene(baked, "multiscale", integrator)
    passes = np.stack([render(scene, seed=s, spp=1) for s in range(6)])
    cloth = reference.sum(axis=2) > 0
    # The picture's mean over the cloth: one value per pass, its standard error from the passes.
    means = passes[:, cloth].mean(axis=(1, 2))
    target = reference[cloth].mean()
    error = abs(means.mean() - target)
    standard_error = means.std(ddof=1) / np.sqrt(len(means))
    assert error < 4 * standard_error + 1e-4 * target, (error, standard_error, target)


def furnace_scene(baked: Baked, integrator: dict[str, Any], spp: int) -> Any:
    """A cloth panel in front of a grey wall under a constant environment: light reaches the camera
    through the cloth's gaps (the delta lobe), by transmission and after bounces off the wall."""
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": integrator,
            "sensor": {
                "type": "perspective",
                "fov": 40.0,
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0.4, 0.3, 3.0], target=[0, 0, 0], up=[0, 1, 0]
                ),
                "film": {"type": "hdrfilm", "width": 16, "height": 16, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "cloth": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().scale([0.8, 0.8, 1]),
                "bsdf": {
                    "type": "clothbake",
                    "filename": str(baked.path),
                    "method": "brute",
                    "tiles_per_uv": 20.0,
                },
            },
            "wall": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().translate([0, 0, -0.5]).scale([3, 3, 1]),
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.6}},
            },
            "light": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        }
    )


def test_path_tracer_agrees_with_mitsubas_own(baked: Baked) -> None:
    # Point footprints in both (Mitsuba's path integrator drops differentials; ours is told to),
    # so both estimate the same image; four bounces, Russian roulette from the third.
    ours = furnace_scene(
        baked,
        {"type": "clothbake_path", "max_depth": 5, "rr_depth": 3, "footprints": False},
        spp=64,
    )
    theirs = furnace_scene(baked, {"type": "path", "max_depth": 5, "rr_depth": 3}, spp=64)
    a = np.stack([render(ours, seed=s) for s in range(3)])
    b = np.stack([render(theirs, seed=10 + s) for s in range(3)])

    # Compare 4x4 blocks of pixels, channel sums: means and standard errors from the passes.
    def blocks(x: NDArray[np.float64]) -> NDArray[np.float64]:
        s = x.sum(axis=3)
        means: NDArray[np.float64] = s.reshape(len(x), 4, 4, 4, 4).mean(axis=(2, 4))
        return means.reshape(len(x), -1)

    ba, bb = blocks(a), blocks(b)
    difference = ba.mean(axis=0) - bb.mean(axis=0)
    standard_error = np.sqrt(ba.var(axis=0, ddof=1) / len(ba) + bb.var(axis=0, ddof=1) / len(bb))
    z = difference / np.maximum(standard_error, 1e-9)
    assert np.all(np.abs(z) < 5), z
    assert abs(z.mean()) * np.sqrt(len(z)) < 4, z


def test_bad_properties_are_refused_naming_them(baked: Baked, tmp_path: Path) -> None:
    with pytest.raises(Exception, match="tiles_per_uv or uv_span_mm, not both"):
        mi.load_dict(bsdf_dict(baked, "reference", uv_span_mm=10.0))
    with pytest.raises(Exception, match=r"tiles_per_v must be finite and > 0"):
        mi.load_dict(bsdf_dict(baked, "reference", tiles_per_v=-1.0))
    missing = tmp_path / "missing.cbk"
    with pytest.raises(Exception, match=r"missing\.cbk"):
        mi.load_dict({"type": "clothbake", "filename": str(missing)})
    with pytest.raises(Exception, match="method must be one of multiscale"):
        mi.load_dict(bsdf_dict(baked, "fastest"))


def test_fabric_asset_bakes_once_per_toml(baked: Baked, tmp_path: Path) -> None:
    fabric = tmp_path / "twill.toml"
    fabric.write_bytes(baked.fabric.read_bytes())
    first = mitsuba_plugin.fabric_asset(fabric, tmp_path / "cache")
    stamp = first.stat().st_mtime_ns
    assert mitsuba_plugin.fabric_asset(fabric, tmp_path / "cache") == first
    assert first.stat().st_mtime_ns == stamp  # not baked again
    clothbake.open_asset(first)  # a valid asset
    fabric.write_text(fabric.read_text().replace('name = "twill 32"', 'name = "twill 32b"'))
    second = mitsuba_plugin.fabric_asset(fabric, tmp_path / "cache")
    assert second != first and second.exists()
