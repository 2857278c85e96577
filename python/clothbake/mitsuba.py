"""clothbake.mitsuba: clothbake assets in Mitsuba 3, path traced (docs/mitsuba.md).

``register()`` selects Mitsuba's ``llvm_ad_rgb`` variant, switches Dr.Jit's symbolic loops, calls
and conditionals off (so that every plug-in call receives evaluated wavefronts that can go to
numpy) and registers two plug-ins:

- the BSDF ``clothbake``: an asset (or a fabric TOML, baked once into a cache), its scale on the
  surface, the method (``multiscale``, ``brute``, ``reference``, ``multiscale-paper``), the sheen
  convention. eval / pdf / sample run the project's evaluator (clothbake.Evaluator, the C
  interface) on whole wavefronts of lanes, never Python per ray. Footprints come from the
  interaction's uv partials (``si.duv_dx``, ``si.duv_dy``) by clothbake's own footprint rule
  (clothbake.pixel_footprints); partials of zero (any bounce after the first) are point footprints.
- the integrator ``clothbake_path``: a unidirectional path tracer (emitter sampling and BSDF
  sampling combined by the power heuristic, Russian roulette, a maximum depth, the cloth's delta
  lobe straight through its gaps) whose camera rays carry one-pixel differentials to the first
  hit, where it computes the uv partials the BSDF reads. Mitsuba's own ``path`` integrator drops
  ray differentials, so with it the cloth is shaded with point footprints everywhere.

Scenes are ordinary Mitsuba scenes (XML or dict) with ``{"type": "clothbake", ...}`` as the cloth's
BSDF. Conventions: the BSDF's local frame is Mitsuba's shading frame (z the shading normal, x along
dP/du), which is the asset's frame when the surface's u runs along the tile's warp. Mitsuba's
``si.wi`` (towards the viewer) is clothbake's ``wo``, and Mitsuba's ``wo`` (towards the light) is
clothbake's ``wi``; both return f times abs(cos) of the light direction.

The module needs ``mitsuba`` and ``drjit`` (pinned in python/requirements.txt) and an LLVM 15 or
newer with x86 fmaximum support for Dr.Jit's LLVM backend: Debian 12's ``libllvm19``
(scripts/setup installs it). ``DRJIT_LIBLLVM_PATH`` is set to it when unset and the file exists.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import clothbake

_DEBIAN_LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(_DEBIAN_LIBLLVM):
    os.environ["DRJIT_LIBLLVM_PATH"] = _DEBIAN_LIBLLVM

import drjit as dr  # noqa: E402  (after DRJIT_LIBLLVM_PATH)
import mitsuba as mi  # noqa: E402

VARIANT = "llvm_ad_rgb"
"""The Mitsuba variant the plug-ins run in: vectorised on the CPU, RGB."""

_CONTINUOUS = int(clothbake.Lobe.ALL & ~clothbake.Lobe.DELTA_TRANSMISSION)
_DELTA = int(clothbake.Lobe.DELTA_TRANSMISSION)
_SEED_MIX = 0x9E3779B97F4A7C15

_registered = False


def register() -> None:
    """Selects the llvm_ad_rgb variant, turns Dr.Jit's symbolic loops, calls and conditionals off,
    and registers the BSDF ``clothbake`` and the integrator ``clothbake_path``. Idempotent.

    Raises ImportError when the variant is missing and RuntimeError when Dr.Jit finds no usable
    LLVM (its own message). Symbolic modes stay off for the process: Mitsuba plug-ins written in
    C++ work either way, and a Python BSDF called from inside a symbolic scope would receive
    symbolic arrays that cannot reach the C interface.
    """
    global _registered
    if _registered:
        return
    mi.set_variant(VARIANT)
    for flag in (
        dr.JitFlag.SymbolicLoops,
        dr.JitFlag.SymbolicCalls,
        dr.JitFlag.SymbolicConditionals,
    ):
        dr.set_flag(flag, False)
    bsdf_class, integrator_class = _define_plugins()
    mi.register_bsdf("clothbake", lambda props: bsdf_class(props))
    mi.register_integrator("clothbake_path", lambda props: integrator_class(props))
    _registered = True


def fabric_asset(
    fabric: str | os.PathLike[str], cache: str | os.PathLike[str] | None = None
) -> Path:
    """The asset of a fabric TOML, baked once with clothbake.bake into ``cache`` (default
    ``$CLOTHBAKE_CACHE/mitsuba``, else ``~/.cache/clothbake/mitsuba``) as ``<stem>-<key>.cbk``,
    the key the SHA-256 of the TOML's bytes and of the baker (the ``clothbake._bake`` extension's
    file, so that a rebuilt baker bakes again). A fabric whose maps are image files is keyed by
    its TOML only: bake it yourself (``clothbake bake``) when the images change. Raises what
    clothbake.bake raises; OSError when the TOML or the extension cannot be read.
    """
    path = Path(fabric)
    baker = importlib.util.find_spec("clothbake._bake")
    if baker is None or baker.origin is None:
        raise OSError("clothbake._bake is not installed: the module cannot bake")
    key = hashlib.sha256(path.read_bytes())
    key.update(Path(baker.origin).read_bytes())
    digest = key.hexdigest()[:16]
    root = Path(cache) if cache is not None else _default_cache()
    asset = root / f"{path.stem}-{digest}.cbk"
    if not asset.exists():
        root.mkdir(parents=True, exist_ok=True)
        clothbake.bake(path, asset)
    return asset


def _default_cache() -> Path:
    base = os.environ.get("CLOTHBAKE_CACHE")
    return (Path(base) if base else Path.home() / ".cache" / "clothbake") / "mitsuba"


def _numpy(value: Any, columns: int, n: int) -> NDArray[np.float64]:
    """A Dr.Jit vector (columns > 1) or scalar array as float64 numpy rows, a width-1 value (a
    literal Mitsuba broadcasts) repeated to n rows. Shape (n, columns), or (n,) for columns 1."""
    array = np.asarray(value.numpy() if hasattr(value, "numpy") else value, dtype=np.float64)
    if columns == 1:
        return np.ascontiguousarray(np.broadcast_to(array.reshape(-1), (n,)))
    array = array.reshape(columns, -1).T  # Dr.Jit gives vectors as (columns, width)
    return np.ascontiguousarray(np.broadcast_to(array, (n, columns)))


def _rows_to_dr(kind: Any, rows: NDArray[np.float64]) -> Any:
    """(n, 3) numpy rows as a Dr.Jit 3-vector type (mi.Color3f, mi.Vector3f) of width n."""
    return kind(mi.Float(rows[:, 0]), mi.Float(rows[:, 1]), mi.Float(rows[:, 2]))


def _tile_scale(props: Any, asset: clothbake.Asset, filename: str) -> tuple[float, float]:
    """Tiles per uv unit along u and v from the BSDF's properties (ClothBSDF's docstring)."""
    tile_mm = asset.info.tile_size_mm
    scales = []
    for axis in ("u", "v"):
        keys = [k for k in (f"tiles_per_{axis}", f"{axis}_span_mm") if k in props]
        keys = keys or [k for k in ("tiles_per_uv", "uv_span_mm") if k in props]
        if len(keys) > 1:
            raise ValueError(f"clothbake BSDF: give one of {' or '.join(keys)}, not both")
        key = keys[0] if keys else "tiles_per_uv"
        value = float(props.get(key, 1.0))
        if key.endswith("_mm"):
            if tile_mm is None:
                raise ValueError(
                    f"clothbake BSDF: {key} needs the asset's tile size, and {filename} does not "
                    f"record one; give tiles_per_{axis} or tiles_per_uv"
                )
            value /= tile_mm
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"clothbake BSDF: {key} must be finite and > 0, got {value}")
        scales.append(value)
    return scales[0], scales[1]


def _usable(rows: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Rows that are finite non-zero directions (the C interface refuses the others)."""
    usable: NDArray[np.bool_] = np.all(np.isfinite(rows), axis=1) & (np.abs(rows).sum(axis=1) > 0)
    return usable


def _width(*values: Any) -> int:
    """The wavefront width of a call: the widest of its arguments (literals have width 1)."""
    return max(dr.width(v) for v in values)


def _define_plugins() -> tuple[type, type]:
    """The plug-in classes, defined once the variant is set (mi.BSDF depends on it)."""

    class ClothBSDF(mi.BSDF):
        """The BSDF ``clothbake`` (docs/mitsuba.md, "The BSDF"). Properties:

        - ``filename`` (string): the asset (.cbk), or a fabric TOML baked by fabric_asset();
        - the fabric's scale on the surface: ``tiles_per_uv`` (float, default 1), fabric tiles
          per unit of the surface's uv, or ``uv_span_mm``, the millimetres one uv unit spans (with
          the tile size the asset records); ``tiles_per_u``, ``tiles_per_v``, ``u_span_mm``,
          ``v_span_mm`` set one axis (a sphere's v spans half of what its u does);
        - ``method`` (``multiscale`` | ``brute`` | ``reference`` | ``multiscale-paper``),
          ``spp`` (int, evaluator samples per estimate, default 1), ``sheen`` (``published`` |
          ``converged``), ``tables`` (``auto`` | ``raw`` | ``compressed``), ``seed`` (int),
          ``trusted`` (bool: skip the asset's full validation), ``threads`` (int, 0 every core).
        """

        def __init__(self, props: Any) -> None:
            mi.BSDF.__init__(self, props)
            filename = str(props["filename"])
            if filename.endswith(".toml"):
                filename = str(fabric_asset(filename))
            trusted = bool(props.get("trusted", False))
            self.asset = clothbake.open_asset(filename, trusted=trusted)
            self.method = str(props.get("method", "multiscale"))
            self.evaluator = clothbake.Evaluator(
                self.asset,
                method=self.method,  # type: ignore[arg-type]
                spp=int(props.get("spp", 1)),
                tables=str(props.get("tables", "auto")),  # type: ignore[arg-type]
                sheen_convention=str(props.get("sheen", "published")),  # type: ignore[arg-type]
            )
            self.tiles_per_u, self.tiles_per_v = _tile_scale(props, self.asset, filename)
            self.seed = int(props.get("seed", 1))
            self.threads = int(props.get("threads", 0)) or None
            self.calls = 0
            sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            continuous = (
                mi.BSDFFlags.GlossyReflection
                | mi.BSDFFlags.GlossyTransmission
                | mi.BSDFFlags.DiffuseReflection
                | mi.BSDFFlags.DiffuseTransmission
                | mi.BSDFFlags.SpatiallyVarying
                | mi.BSDFFlags.Anisotropic
                | sides
            )
            delta = mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.SpatiallyVarying | sides
            self.m_components = [continuous, delta]
            self.m_flags = continuous | delta

        # --- helpers -------------------------------------------------------------------------
        def _next_seed(self) -> int:
            """A fresh estimate seed per call: the estimates of two calls are independent."""
            self.calls += 1
            return (self.seed * _SEED_MIX + self.calls) % (1 << 64)

        def _lanes(
            self, si: Any, active: Any, n: int
        ) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]]:
            """The active lanes of n, their footprints (tile units) and clothbake's wo (Mitsuba's
            si.wi)."""
            mask = _numpy(active if isinstance(active, bool) else mi.Float(active), 1, n) != 0
            view = _numpy(si.wi, 3, n)
            mask &= _usable(view)
            lanes = np.nonzero(mask)[0]
            uv = _numpy(si.uv, 2, n)[lanes]
            dx = _numpy(si.duv_dx, 2, n)[lanes]
            dy = _numpy(si.duv_dy, 2, n)[lanes]
            # Tile units first (the scale may differ along u and v), then the rule at scale 1.
            scale = np.array([self.tiles_per_u, self.tiles_per_v])
            footprints = clothbake.pixel_footprints(uv * scale, dx * scale, dy * scale, 1.0)
            return lanes, footprints, view[lanes]

        def _estimate(
            self,
            footprints: NDArray[np.float64],
            wi: NDArray[np.float64],
            wo: NDArray[np.float64],
            lobes: int,
        ) -> NDArray[np.float64]:
            if len(footprints) == 0:
                return np.zeros((0, 3))
            return self.evaluator.estimate(
                footprints, wi, wo, lobes=lobes, seed=self._next_seed(), threads=self.threads
            )

        def _pdf(
            self, footprints: NDArray[np.float64], wi: NDArray[np.float64], wo: NDArray[np.float64]
        ) -> NDArray[np.float64]:
            if len(footprints) == 0:
                return np.zeros(0)
            return self.evaluator.pdf(footprints, wi, wo, threads=self.threads)

        @staticmethod
        def _spread(n: int, lanes: NDArray[np.intp], values: NDArray[Any]) -> NDArray[Any]:
            """values of the active lanes scattered into n rows of zeros (their dtype)."""
            out = np.zeros((n, *values.shape[1:]), dtype=values.dtype)
            out[lanes] = values
            return out

        def _continuous_enabled(self, ctx: Any) -> bool:
            return bool(ctx.is_enabled(mi.BSDFFlags.Glossy | mi.BSDFFlags.Diffuse, 0))

        def _delta_enabled(self, ctx: Any) -> bool:
            return bool(ctx.is_enabled(mi.BSDFFlags.DeltaTransmission, 1))

        # --- the BSDF interface ----------------------------------------------------------------
        def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            value, _ = self._eval_pdf(ctx, si, wo, active, want_pdf=False)
            return value

        def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            _, pdf = self._eval_pdf(ctx, si, wo, active, want_value=False)
            return pdf

        def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            return self._eval_pdf(ctx, si, wo, active)

        def _eval_pdf(
            self,
            ctx: Any,
            si: Any,
            wo: Any,
            active: Any,
            want_value: bool = True,
            want_pdf: bool = True,
        ) -> tuple[Any, Any]:
            n = _width(wo, si.uv, si.wi, active)
            lanes, footprints, view = self._lanes(si, active, n)
            light = _numpy(wo, 3, n)[lanes]
            ok = _usable(light)  # a zero direction (a failed light sample) shades 0
            lanes, footprints, view, light = lanes[ok], footprints[ok], view[ok], light[ok]
            value = np.zeros((len(lanes), 3))
            pdf = np.zeros(len(lanes))
            if self._continuous_enabled(ctx):
                if want_value:
                    value = self._estimate(footprints, light, view, _CONTINUOUS)
                if want_pdf:
                    pdf = self._pdf(footprints, light, view)
            return (
                _rows_to_dr(mi.Color3f, self._spread(n, lanes, value)),
                mi.Float(self._spread(n, lanes, pdf)),
            )

        def sample(self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True) -> Any:
            n = _width(sample1, sample2, si.uv, si.wi, active)
            lanes, footprints, view = self._lanes(si, active, n)
            u = np.stack(
                [
                    _numpy(sample1, 1, n)[lanes],
                    _numpy(sample2, 2, n)[lanes, 0],
                    _numpy(sample2, 2, n)[lanes, 1],
                ],
                axis=1,
            )
            u = np.clip(u, 0.0, np.nextafter(1.0, 0.0))
            weight = np.zeros((len(lanes), 3))
            wi = np.zeros((len(lanes), 3))
            pdf = np.zeros(len(lanes))
            kind = np.zeros(len(lanes), dtype=np.uint32)
            component = np.zeros(len(lanes), dtype=np.uint32)
            if len(lanes):
                s = self.evaluator.sample(footprints, view, u, threads=self.threads)
                wi, pdf = s.wi.copy(), s.pdf.copy()
                cont = s.valid & ~s.is_delta & (pdf > 0)
                delta = s.valid & s.is_delta & (pdf > 0)
                if self._continuous_enabled(ctx) and cont.any():
                    value = self._estimate(footprints[cont], wi[cont], view[cont], _CONTINUOUS)
                    weight[cont] = value / pdf[cont, None]
                    reflect = wi[cont, 2] * view[cont, 2] > 0
                    kind[cont] = np.where(
                        reflect,
                        int(mi.BSDFFlags.GlossyReflection),
                        int(mi.BSDFFlags.GlossyTransmission),
                    )
                if self._delta_enabled(ctx) and delta.any():
                    through = -view[delta]
                    value = self._estimate(footprints[delta], through, view[delta], _DELTA)
                    weight[delta] = value / pdf[delta, None]
                    wi[delta] = through
                    kind[delta] = int(mi.BSDFFlags.DeltaTransmission)
                    component[delta] = 1
                pdf[kind == 0] = 0.0
            bs = dr.zeros(mi.BSDFSample3f, n)
            bs.wo = _rows_to_dr(mi.Vector3f, self._spread(n, lanes, wi))
            bs.pdf = mi.Float(self._spread(n, lanes, pdf))  # type: ignore[assignment]
            bs.eta = mi.Float(np.ones(n))  # type: ignore[assignment]
            bs.sampled_type = mi.UInt32(self._spread(n, lanes, kind))  # type: ignore[assignment]
            bs.sampled_component = mi.UInt32(  # type: ignore[assignment]
                self._spread(n, lanes, component)
            )
            return bs, _rows_to_dr(mi.Color3f, self._spread(n, lanes, weight))

        def traverse(self, callback: Any) -> None:
            pass

        def to_string(self) -> str:
            return (
                f"ClothBSDF[asset={self.asset.source!r}, method={self.method!r}, "
                f"tiles_per_u={self.tiles_per_u}, tiles_per_v={self.tiles_per_v}]"
            )

    class ClothPathIntegrator(mi.SamplingIntegrator):
        """The integrator ``clothbake_path`` (docs/mitsuba.md, "The path tracer"). Properties:

        - ``max_depth`` (int, default 8; 1: emitters seen directly, 2: direct light only),
          ``rr_depth`` (int, default 5: Russian roulette from this depth on);
        - ``footprints`` (bool, default true): camera rays through pixel centres carrying
          one-pixel differentials, the first hit's uv partials computed for the BSDF (clothbake's
          renderer's pixel footprints); false: rays jittered over the pixel, point footprints
          everywhere (plain path tracing, as brute force renders).
        - ``pixel_centres`` (bool, default: as ``footprints``): true puts every camera ray
          through its pixel's centre.
        """

        def __init__(self, props: Any) -> None:
            mi.SamplingIntegrator.__init__(self, props)
            self.max_depth = int(props.get("max_depth", 8))
            self.rr_depth = int(props.get("rr_depth", 5))
            self.footprints = bool(props.get("footprints", True))
            self.pixel_centres = bool(props.get("pixel_centres", self.footprints))
            if self.max_depth < 1:
                raise ValueError(f"clothbake_path: max_depth must be >= 1, got {self.max_depth}")

        def render(  # type: ignore[override]
            self,
            scene: Any,
            sensor: Any = 0,
            seed: int = 0,
            spp: int = 0,
            develop: bool = True,
            evaluate: bool = True,
        ) -> Any:
            """The image as a (height, width, 3) TensorXf: spp passes of one sample per pixel
            averaged (box filter over the pixel for jittered rays)."""
            if isinstance(sensor, int):
                sensor = scene.sensors()[sensor]
            film = sensor.film()
            width, height = (int(c) for c in film.crop_size())
            ox, oy = (int(c) for c in film.crop_offset())
            full_w, full_h = (int(c) for c in film.size())
            sampler = sensor.sampler().clone()
            spp = int(spp) if spp else int(sampler.sample_count())
            pixels = width * height
            index = dr.arange(mi.UInt32, pixels)
            px = mi.Float(index % width + ox)
            py = mi.Float(index // width + oy)
            image = np.zeros((pixels, 3))
            for sample_pass in range(spp):
                sampler.seed(seed * spp + sample_pass, pixels)
                if self.pixel_centres:
                    offset = mi.Point2f(0.5, 0.5)
                    sampler.next_2d()  # keep the streams of both modes aligned
                else:
                    offset = sampler.next_2d()
                position = mi.Point2f((px + offset.x) / full_w, (py + offset.y) / full_h)
                ray, ray_weight = sensor.sample_ray_differential(
                    time=0.0, sample1=sampler.next_1d(), sample2=position, sample3=mi.Point2f(0.5)
                )
                radiance = self.trace(scene, sampler, ray, sensor) * ray_weight
                image += _numpy(radiance, 3, pixels)
            image /= spp
            return mi.TensorXf(image.reshape(height, width, 3).astype(np.float32))

        def _camera_uv_partials(self, sensor: Any, ray: Any, si: Any) -> None:
            """Sets si.duv_dx, si.duv_dy at camera rays' hits as clothbake's renderer computes
            them (clothbake.uv_differentials: the unit direction's exact derivatives carried to
            the tangent plane). For a perspective camera the image plane is linear in the pixel
            position, so the derivative of the unnormalised direction d / (d . forward) is the
            difference of Mitsuba's one-pixel differential rays, exactly; other sensors keep
            Mitsuba's own transfer (si.compute_uv_partials). That one starts the differential
            rays at the camera ray's origin on the near clip plane, so its footprints come out
            near_clip / distance too narrow (0.33 % on the test plane at 3 m)."""
            if sensor.class_name() != "PerspectiveCamera":
                si.compute_uv_partials(ray)
                return
            n = dr.width(si.t)
            forward: NDArray[np.float64] = _numpy(
                sensor.world_transform() @ mi.Vector3f(0, 0, 1), 3, 1
            )[0]

            def plane(d: NDArray[np.float64]) -> NDArray[np.float64]:
                scaled: NDArray[np.float64] = d / (d @ forward)[:, None]
                return scaled

            d = _numpy(ray.d, 3, n)
            base = plane(d)
            length2 = np.einsum("ij,ij->i", base, base)[:, None]

            def unit_derivative(offset: Any) -> NDArray[np.float64]:
                step = plane(_numpy(offset, 3, n)) - base
                along = np.einsum("ij,ij->i", base, step)[:, None]
                derivative: NDArray[np.float64] = (step * length2 - base * along) / (
                    length2 * np.sqrt(length2)
                )
                return derivative

            # The distance from the pinhole: Mitsuba starts camera rays on the near clip plane.
            pinhole = _numpy(sensor.world_transform() @ mi.Point3f(0, 0, 0), 3, 1)[0]
            hit = np.isfinite(_numpy(si.t, 1, n))
            t = np.where(hit, np.linalg.norm(_numpy(si.p, 3, n) - pinhole, axis=1), 0.0)
            duv_dx, duv_dy = clothbake.uv_differentials(
                t,
                d / np.linalg.norm(d, axis=1)[:, None],
                unit_derivative(ray.d_x),
                unit_derivative(ray.d_y),
                _numpy(si.n, 3, n),
                _numpy(si.dp_du, 3, n),
                _numpy(si.dp_dv, 3, n),
            )
            duv_dx[~hit] = 0.0
            duv_dy[~hit] = 0.0
            si.duv_dx = mi.Vector2f(duv_dx[:, 0], duv_dx[:, 1])
            si.duv_dy = mi.Vector2f(duv_dy[:, 0], duv_dy[:, 1])

        def trace(self, scene: Any, sampler: Any, ray: Any, sensor: Any) -> Any:
            """The radiance along each camera ray (a wavefront loop, each bounce evaluated)."""
            n = dr.width(ray.o)
            radiance = dr.zeros(mi.Color3f, n)
            throughput = dr.full(mi.Color3f, 1.0, n)
            active = dr.full(mi.Bool, True, n)
            prev_si = dr.zeros(mi.SurfaceInteraction3f, n)
            prev_pdf = dr.full(mi.Float, 1.0, n)
            prev_delta = dr.full(mi.Bool, True, n)
            ctx = mi.BSDFContext()
            current = mi.Ray3f(ray)
            for depth in range(self.max_depth):
                si = scene.ray_intersect(
                    current, ray_flags=mi.RayFlags.All, coherent=depth == 0, active=active
                )
                if depth == 0 and self.footprints:
                    self._camera_uv_partials(sensor, ray, si)
                else:
                    si.duv_dx = dr.zeros(mi.Vector2f, n)
                    si.duv_dy = dr.zeros(mi.Vector2f, n)
                # Emitters hit by the path: weighted against emitter sampling at the last vertex.
                emitter = si.emitter(scene, active)
                hit_emitter = active & (emitter != None)  # noqa: E711 (Dr.Jit pointer comparison)
                ds = mi.DirectionSample3f(scene, si, prev_si)
                emitter_pdf = dr.select(
                    prev_delta,
                    0.0,
                    scene.pdf_emitter_direction(prev_si, ds, hit_emitter & ~prev_delta),
                )
                radiance += dr.select(
                    hit_emitter,
                    throughput
                    * _power_heuristic(prev_pdf, emitter_pdf)
                    * emitter.eval(si, hit_emitter),
                    0.0,
                )
                active &= si.is_valid()
                if depth + 1 >= self.max_depth:
                    break
                bsdf = si.bsdf(current)
                # Emitter sampling.
                smooth = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                ds, emitter_weight = scene.sample_emitter_direction(
                    si, sampler.next_2d(smooth), True, smooth
                )
                lit = smooth & (ds.pdf != 0)
                value, bsdf_pdf = bsdf.eval_pdf(ctx, si, si.to_local(ds.d), lit)
                mis = dr.select(ds.delta, 1.0, _power_heuristic(ds.pdf, bsdf_pdf))
                radiance += dr.select(lit, throughput * value * emitter_weight * mis, 0.0)
                # BSDF sampling.
                bs, weight = bsdf.sample(
                    ctx, si, sampler.next_1d(active), sampler.next_2d(active), active
                )
                throughput *= dr.select(active, weight, 0.0)
                current = si.spawn_ray(si.to_world(bs.wo))
                prev_si = si
                prev_pdf = bs.pdf
                prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
                active &= (bs.pdf > 0) & dr.any(throughput != 0)
                if depth + 1 >= self.rr_depth:
                    q = dr.minimum(dr.max(dr.abs(throughput)), 0.95)
                    survive = sampler.next_1d(active) < q
                    throughput *= dr.select(survive, dr.rcp(q), 0.0)
                    active &= survive
                sampler.schedule_state()
                dr.eval(radiance, throughput, active, current, prev_si, prev_pdf, prev_delta)
            return radiance

        def aov_names(self) -> list[str]:
            return []

        def to_string(self) -> str:
            return f"ClothPathIntegrator[max_depth={self.max_depth}, footprints={self.footprints}]"

    return ClothBSDF, ClothPathIntegrator


def _power_heuristic(a: Any, b: Any) -> Any:
    a2, b2 = a * a, b * b
    return dr.select(a2 + b2 > 0, a2 / (a2 + b2), 0.0)
