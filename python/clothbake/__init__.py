"""clothbake: shade and bake multi-scale cloth assets from Python (docs/python.md).

The shading half is the C interface (capi/clothbake.h) over numpy arrays: open an asset, create an
Evaluator, and estimate the cloth BSDF over pixel footprints, sample light directions and give
their densities, vectorised over rows, with the GIL released and the rows split across the cores.
The baking half runs the library behind ``clothbake bake``: a fabric description into an asset,
with progress reported to a Python callable.

Conventions (those of capi/clothbake.h, for every function here):

- Directions are in the cloth's local shading frame: z along the surface normal, x along the
  tile's u axis (the warp), y along v. ``wi`` points towards the light, ``wo`` towards the viewer;
  any finite non-zero vectors (normalised by the library).
- Footprints are rows ``(u0, v0, u1, v1)``: axis-aligned rectangles in tile units (one unit is one
  repeat of the fabric's tile; u1 >= u0, v1 >= v0; a zero-area footprint is a point). The tile
  wraps: any position with corners within 2**40 texels of the origin, any size up to 2**24 tiles.
- An estimate is Eq. 5 of docs/evaluator.md: the footprint average of the BSDF times the
  visibility times abs(cos) of wi, parallax included, in linear RGB. Multiply by the light's
  radiance (and divide by its sampling density).
- Arrays: footprints of shape (n, 4), directions and random numbers of shape (n, 3) (a direction
  may also be one row of shape (3,), used for every footprint); any real dtype, converted to
  float64. A wrong shape raises ValueError, a non-real dtype TypeError, both naming the argument.
- Errors of the library raise clothbake.Error subclasses (see clothbake._errors), carrying the
  cb_result name as ``code`` and the library's message; an error at one row raises for the
  lowest failing row (its index is in the message) and returns nothing.
- Threads: every call releases the GIL; estimate, sample and pdf split the rows into chunks of
  CHUNK_SIZE and run them on ``threads`` threads (default: one per core). One Evaluator may serve
  several Python threads at once. Do not modify the input arrays during a call.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntFlag
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _shading
from ._errors import (
    BakeError,
    Error,
    FileError,
    InvalidArgumentError,
    InvalidAssetError,
    NotFoundError,
    OutOfMemoryError,
    OutOfPlanError,
    UnsupportedError,
)

__all__ = [
    "CHUNK_SIZE",
    "MAX_FOOTPRINT_TILES",
    "Asset",
    "AssetInfo",
    "BakeError",
    "BakeResult",
    "DirectionSamples",
    "Error",
    "Evaluator",
    "FileError",
    "InvalidArgumentError",
    "InvalidAssetError",
    "Lobe",
    "Method",
    "NotFoundError",
    "OutOfMemoryError",
    "OutOfPlanError",
    "SheenConvention",
    "TableChoice",
    "UnsupportedError",
    "bake",
    "chunk_seed",
    "open_asset",
    "pixel_footprints",
    "uv_differentials",
]

CHUNK_SIZE: int = _shading.CHUNK_SIZE
"""Rows per chunk of estimate/sample/pdf; each chunk of an estimate has its own generator."""

Method = Literal["multiscale", "multiscale-paper", "brute", "reference"]
TableChoice = Literal["auto", "raw", "compressed"]
SheenConvention = Literal["published", "converged"]

_METHODS: dict[str, int] = {"multiscale": 0, "multiscale-paper": 1, "brute": 2, "reference": 3}
_TABLES: dict[str, int] = {"auto": 0, "raw": 1, "compressed": 2}
_SHEEN: dict[str, int] = {"published": 0, "converged": 1}
_UINT64 = 1 << 64


class Lobe(IntFlag):
    """The lobes of Eq. 4, to restrict an estimate to (combine with |); ALL for the whole BSDF."""

    SPECULAR_REFLECTION = 1
    SPECULAR_TRANSMISSION = 2
    DIFFUSE_REFLECTION = 4
    DIFFUSE_TRANSMISSION = 8
    DELTA_TRANSMISSION = 16
    SHEEN = 32
    ALL = 63


class AssetInfo(NamedTuple):
    """What cb_asset_get_info gives."""

    resolution: int
    """Texels per tile side (tiles are square)."""
    tile_size_mm: float | None
    """The tile's physical side in millimetres; None when the asset does not know it."""
    scene_planned: bool
    """True when a scene plan left parts out (queries may raise OutOfPlanError)."""


class DirectionSamples(NamedTuple):
    """Evaluator.sample's result, one row per footprint."""

    wi: NDArray[np.float64]
    """(n, 3) unit light directions in the local frame (meaningless where not valid)."""
    pdf: NDArray[np.float64]
    """(n,) solid-angle densities of the continuous techniques at wi, or P(delta) where is_delta."""
    valid: NDArray[np.bool_]
    """(n,) False where the BSDF is 0 for wo (no sample)."""
    is_delta: NDArray[np.bool_]
    """(n,) True where the delta transmission lobe was picked: wi = -wo."""


def chunk_seed(seed: int, chunk: int) -> int:
    """The generator seed of chunk ``chunk`` of an estimate seeded with ``seed``.

    ``seed`` itself for chunk 0, else SplitMix64's finaliser of
    ``seed ^ (chunk * 0x9E3779B97F4A7C15)`` (mod 2**64). Row i of ``estimate(..., seed=s)`` is
    therefore the (i % CHUNK_SIZE)-th estimate of a generator seeded
    ``chunk_seed(s, i // CHUNK_SIZE)``, whatever the thread count. Pure.
    """
    return int(_shading.chunk_seed(_check_uint64("seed", seed), _check_uint64("chunk", chunk)))


MAX_FOOTPRINT_TILES: float = 2.0**24
"""The widest footprint side the C interface accepts, in tiles (pixel_footprints clamps to it)."""


def pixel_footprints(
    uv: ArrayLike, duv_dx: ArrayLike, duv_dy: ArrayLike, tiles_per_uv: float
) -> NDArray[np.float64]:
    """The footprints of pixels from their surface coordinates and ray differentials.

    The rule of clothbake's renderer (docs/rendering.md, "Pixel footprints"; the same C++ code,
    model/pixel_footprint.hpp): the pixel's parallelogram, edges ``duv_dx`` and ``duv_dy`` (surface
    uv units per pixel) around ``uv``, becomes the axis-aligned rectangle with its bounding box's
    aspect ratio and its own area, all scaled by ``tiles_per_uv`` (tiles per uv unit). Rows of
    shape (n, 2) each; returns (n, 4) rows (u0, v0, u1, v1) in tile units, ready for
    Evaluator.estimate. Zero derivatives give points; sides are clamped to MAX_FOOTPRINT_TILES
    (non-finite derivatives too). Raises ValueError for shapes that differ or tiles_per_uv that
    is not finite and > 0. Pure.
    """
    if not (np.isfinite(tiles_per_uv) and tiles_per_uv > 0):
        raise ValueError(f"tiles_per_uv must be finite and > 0, got {tiles_per_uv}")
    arrays = []
    for name, value in (("uv", uv), ("duv_dx", duv_dx), ("duv_dy", duv_dy)):
        array = _real_array(name, value)
        if array.ndim != 2 or array.shape[1] != 2:
            raise ValueError(f"{name} must have shape (n, 2), got shape {array.shape}")
        arrays.append(array)
    n = arrays[0].shape[0]
    for name, array in zip(("duv_dx", "duv_dy"), arrays[1:], strict=True):
        if array.shape[0] != n:
            raise ValueError(f"{name} has {array.shape[0]} rows, uv has {n}")
    out = np.empty((n, 4), dtype=np.float64)
    uv_rows, dx_rows, dy_rows = arrays
    _shading.pixel_footprints(
        uv_rows, dx_rows, dy_rows, float(tiles_per_uv), MAX_FOOTPRINT_TILES, out
    )
    return out


def uv_differentials(
    t: ArrayLike,
    direction: ArrayLike,
    ddx: ArrayLike,
    ddy: ArrayLike,
    normal: ArrayLike,
    dpdu: ArrayLike,
    dpdv: ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The uv derivatives of camera rays' hits, for pixel_footprints.

    The transfer of clothbake's renderer (docs/rendering.md, "Pixel footprints"; the same C++
    code, model/pixel_footprint.hpp): the derivatives ``ddx``, ``ddy`` of each ray's unit
    ``direction`` per pixel (the origin fixed) carried to the tangent plane of its hit at distance
    ``t`` with geometric ``normal``, dP = t dD - ((t dD).n / (D.n)) D, and solved for (du, dv) in
    the basis ``dpdu``, ``dpdv`` by least squares. Rows: t of shape (n,), the others (n, 3).
    Returns (duv_dx, duv_dy), each (n, 2); zero rows where a ray grazes its surface or the basis
    is degenerate. Raises ValueError for shapes that differ. Pure.
    """
    times = _real_array("t", t).reshape(-1)
    n = times.shape[0]
    rows = [
        _rows(name, value, n, broadcast=False, against="t")
        for name, value in (
            ("direction", direction),
            ("ddx", ddx),
            ("ddy", ddy),
            ("normal", normal),
            ("dpdu", dpdu),
            ("dpdv", dpdv),
        )
    ]
    out_dx = np.empty((n, 2), dtype=np.float64)
    out_dy = np.empty((n, 2), dtype=np.float64)
    d, dx, dy, normals, du, dv = rows
    _shading.uv_differentials(times, d, dx, dy, normals, du, dv, out_dx, out_dy)
    return out_dx, out_dy


class Asset:
    """An open asset. Create it with open_asset(); it stays open while an Evaluator uses it."""

    __slots__ = ("_asset", "_info", "_trusted")

    def __init__(self, handle: _shading.Asset, trusted: bool) -> None:
        self._asset = handle
        self._trusted = trusted
        self._info: AssetInfo | None = None

    @property
    def source(self) -> str:
        """The path it was opened from, or "asset in memory"."""
        return self._asset.source

    @property
    def trusted(self) -> bool:
        """True when it was opened with trusted=True (structure checked, no full validation)."""
        return self._trusted

    @property
    def info(self) -> AssetInfo:
        """Resolution, tile size and scene plan (cb_asset_get_info).

        Raises NotFoundError or InvalidAssetError when the fabric record or the scene-plan record
        of an asset opened trusted is missing or damaged.
        """
        if self._info is None:
            resolution, tile_size_mm, scene_planned = self._asset.info()
            self._info = AssetInfo(
                int(resolution), float(tile_size_mm) if tile_size_mm > 0 else None, scene_planned
            )
        return self._info

    def __repr__(self) -> str:
        return f"<clothbake.Asset {self.source!r}{' trusted' if self._trusted else ''}>"


def open_asset(
    source: str | os.PathLike[str] | bytes | bytearray | memoryview, *, trusted: bool = False
) -> Asset:
    """Opens an asset from a file path or from its bytes (cb_asset_open_file / _open_memory).

    The whole asset is validated first, as ``clothbake validate`` does (every checksum, value
    ranges, NaN/Inf, every baked table opened and cross-checked): safe on untrusted bytes, at the
    cost of one pass over the bytes and opening every table. ``trusted=True`` checks the structure
    only (magic, version, section table, sizes, offsets); the evaluator then checks the layouts and
    some values of what it reads, but no checksum: damaged bytes may shade as wrong values. Use it
    for assets you baked or verified. A file is mapped read-only (it must not be truncated while
    open); bytes are copied (the object may go after the call). The GIL is released meanwhile.

    Raises FileError (the file cannot be opened, sized or mapped), InvalidAssetError (the message
    names the first failed check, CBK-Ennn), UnsupportedError, OutOfMemoryError; TypeError for a
    source that is neither a path nor bytes.
    """
    if not isinstance(trusted, bool):
        raise TypeError(f"trusted must be a bool, got {type(trusted).__name__}")
    if isinstance(source, (bytes, bytearray, memoryview)):
        return Asset(_shading.open_memory(bytes(source), trusted), trusted)
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if not isinstance(path, str):
            raise TypeError("source must be a str path, an os.PathLike of str, or bytes")
        return Asset(_shading.open_file(path, trusted), trusted)
    kind = type(source).__name__
    raise TypeError(f"source must be a path (str, os.PathLike) or the asset's bytes, got {kind}")


class Evaluator:
    """The multi-scale evaluator over an asset (cb_evaluator_create with these cb_options).

    ``method``: "multiscale" (unbiased, control variates; the default), "multiscale-paper" (the
    paper's Eq. 8-10 as printed, biased), "brute" (Monte Carlo over the footprint, reads no tables)
    or "reference" (the exact integral, slow on wide footprints). ``spp``: samples per estimate for
    the sampling methods (>= 1). ``tables``: the Integral-Radiance tables, "auto" (compressed, else
    raw), "raw" or "compressed". ``sheen_convention``: "published" (the published sheen table) or
    "converged". ``direct_max_side``: the multi-scale methods sum footprints below this many texels
    a side exactly.

    Creating it opens the views every method needs and builds the derived footprint sums (a few MB
    for a 256**2 tile), with the GIL released. Raises InvalidArgumentError (an option out of
    range), NotFoundError (a section the evaluator or the method needs), InvalidAssetError
    (sections that disagree), UnsupportedError, OutOfMemoryError; ValueError for an unknown method,
    tables or sheen_convention name. It keeps its asset open. Thread-safe: one evaluator serves
    any number of threads at once.
    """

    __slots__ = ("_asset", "_evaluator", "_method", "_spp")

    def __init__(
        self,
        asset: Asset,
        *,
        method: Method = "multiscale",
        spp: int = 1,
        tables: TableChoice = "auto",
        sheen_convention: SheenConvention = "published",
        direct_max_side: float = 1.0,
    ) -> None:
        if not isinstance(asset, Asset):
            raise TypeError(f"asset must be a clothbake.Asset, got {type(asset).__name__}")
        method_id = _choice("method", method, _METHODS)
        tables_id = _choice("tables", tables, _TABLES)
        sheen_id = _choice("sheen_convention", sheen_convention, _SHEEN)
        if isinstance(spp, bool) or not isinstance(spp, int):
            raise TypeError(f"spp must be an int, got {type(spp).__name__}")
        if not 1 <= spp < (1 << 32):
            raise ValueError(f"spp must be in [1, 2**32), got {spp}")
        if isinstance(direct_max_side, bool) or not isinstance(direct_max_side, (int, float)):
            kind = type(direct_max_side).__name__
            raise TypeError(f"direct_max_side must be a number, got {kind}")
        self._asset = asset
        self._method: Method = method
        self._spp = spp
        self._evaluator = _shading.Evaluator(
            asset._asset, method_id, tables_id, sheen_id, spp, float(direct_max_side)
        )

    @property
    def asset(self) -> Asset:
        """The asset it shades."""
        return self._asset

    @property
    def method(self) -> Method:
        """Its method's name."""
        return self._method

    @property
    def spp(self) -> int:
        """Samples per estimate of the sampling methods."""
        return self._spp

    def estimate(
        self,
        footprints: ArrayLike,
        wi: ArrayLike,
        wo: ArrayLike,
        *,
        lobes: int = Lobe.ALL,
        seed: int = 1,
        threads: int | None = None,
    ) -> NDArray[np.float64]:
        """One estimate per row of footprints for the light/view pair of the same row: (n, 3) RGB.

        Each row is cb_estimate (capi/clothbake.h): the footprint average of the BSDF times
        abs(cos wi), the visibility and the parallax included, over the lobes of ``lobes`` (a
        non-zero subset of Lobe.ALL). Finite; >= 0 for brute and reference, while one estimate of
        the control-variate methods can be slightly negative (not clamped: clamping would bias the
        mean). The estimates of multiscale and brute are unbiased: average several calls with
        different seeds for less noise.

        Randomness: rows are split into chunks of CHUNK_SIZE; chunk c draws from its own SplitMix64
        generator seeded chunk_seed(seed, c), row after row. The result depends on the seed and the
        rows only, never on ``threads`` (bit for bit); row 0 equals ``clothbake eval --seed SEED``
        for the same footprint (in texels: times info.resolution), directions, method and spp.

        Raises ValueError/TypeError for bad shapes and dtypes (naming the argument),
        InvalidArgumentError (a bad footprint, direction or lobe mask), NotFoundError (tables the
        method needs), OutOfPlanError, UnsupportedError (an allocation failed), InvalidAssetError
        (values that overflow the evaluator's sums), for the lowest failing row. Allocates inside
        the library on a view bin's or parallax direction's first use (docs/integration.md).
        """
        f = _footprints(footprints)
        n = f.shape[0]
        wi_rows = _rows("wi", wi, n)
        wo_rows = _rows("wo", wo, n)
        mask = _check_lobes(lobes)
        out = np.empty((n, 3), dtype=np.float64)
        self._evaluator.estimate(
            f, wi_rows, wo_rows, mask, _check_uint64("seed", seed), _threads(threads), out
        )
        return out

    def sample(
        self,
        footprints: ArrayLike,
        wo: ArrayLike,
        u: ArrayLike,
        *,
        threads: int | None = None,
    ) -> DirectionSamples:
        """A light direction per row, sampled for the view wo from the lobe mixture at the
        footprint's representative texel (its centre shifted by the mean parallax offset; for a
        footprint with area mixed 3:1 with that texel's half in a gap, so that every lobe the
        footprint covers can be drawn), with its density (cb_sample_direction).

        ``u``: (n, 3) uniform random numbers in [0, 1). The result does not depend on ``threads``.
        Dividing estimate()'s value at wi by pdf gives unbiased estimates. Raises as estimate()
        (InvalidArgumentError for a non-finite u); allocates on a parallax direction's
        first use.
        """
        f = _footprints(footprints)
        n = f.shape[0]
        wo_rows = _rows("wo", wo, n)
        u_rows = _rows("u", u, n, broadcast=False)
        wi_out = np.empty((n, 3), dtype=np.float64)
        pdf_out = np.empty(n, dtype=np.float64)
        valid = np.empty(n, dtype=np.bool_)
        delta = np.empty(n, dtype=np.bool_)
        self._evaluator.sample(f, wo_rows, u_rows, _threads(threads), wi_out, pdf_out, valid, delta)
        return DirectionSamples(wi_out, pdf_out, valid, delta)

    def pdf(
        self,
        footprints: ArrayLike,
        wi: ArrayLike,
        wo: ArrayLike,
        *,
        threads: int | None = None,
    ) -> NDArray[np.float64]:
        """The density sample()'s continuous techniques give wi for the view wo, per row: (n,).

        (cb_direction_pdf: it integrates to 1 - P(delta) over the sphere), for multiple importance
        sampling; sample()'s pdf of a continuous sample equals this at its wi to rounding (a few
        units in the last place). Raises and allocates as sample().
        """
        f = _footprints(footprints)
        n = f.shape[0]
        wi_rows = _rows("wi", wi, n)
        wo_rows = _rows("wo", wo, n)
        out = np.empty(n, dtype=np.float64)
        self._evaluator.pdf(f, wi_rows, wo_rows, _threads(threads), out)
        return out

    def __repr__(self) -> str:
        return f"<clothbake.Evaluator {self._method} spp={self._spp} over {self._asset.source!r}>"


@dataclass(frozen=True)
class BakeResult:
    """What bake() wrote."""

    path: str
    """The asset's path."""
    size_bytes: int
    content_hash: str
    """The header checksum, 16 hex digits (equal bytes, equal hash)."""
    unchanged: bool
    """The file already held these exact bytes and was left untouched, mtime included."""
    wall_seconds: float
    threads: int
    """The bake's effective parallelism."""
    stages: tuple[tuple[str, float], ...]
    """(stage name, wall seconds) in run order."""
    warnings: tuple[str, ...]
    """The library's warnings (not printed)."""


def bake(
    fabric: str | os.PathLike[str],
    output: str | os.PathLike[str],
    *,
    progress: Callable[[str, float], object] | None = None,
    resolution: int | None = None,
    threads: int | None = None,
    force: bool = False,
    max_memory: int | None = None,
) -> BakeResult:
    """Bakes the fabric description ``fabric`` (a TOML file, docs/fabric-format.md) into the asset
    ``output``, through the library ``clothbake bake`` uses (pipeline::bake over every stage: the
    compressed tables, the fabric's [bake] settings), not the executable.

    ``resolution``: texels per tile side of a weave's generated maps (default: the fabric's
    [bake] resolution; image maps must already have it). ``threads``: worker threads (default:
    every core; the asset is byte-identical for any count). ``force``: replace an existing output
    that is not an asset (an asset is always replaceable). ``max_memory``: refuse, before any map
    is loaded, a bake whose estimated peak memory is above this many bytes (default: the machine's
    memory).

    ``progress``: called as progress(stage, fraction) on the calling thread, with the GIL held,
    while the bake runs on other threads without it: for each stage in run order (load_fabric,
    fabric_records, feature_maps, parallax, visibility, cluster, tables, compress, write) first
    with 0.0, then with increasing fractions (steps of at least 0.01), last with 1.0. If it
    raises, the bake is cancelled at its next progress report and the same exception is raised
    once the bake has stopped; nothing is written (a previous file at ``output`` is untouched).
    Ctrl-C (KeyboardInterrupt) cancels a bake the same way, with or without a callback.

    The asset is written to a temporary file beside ``output`` and renamed into place at the end
    (atomic: a failed or cancelled bake leaves no partial file). The library's messages are not
    printed: its warnings are in the result. Raises BakeError (``code`` "input": a bad fabric or
    map, an unwritable output, a bake above max_memory; "usage"; "internal"), with nothing written.
    """
    from . import _bake  # the bake libraries (OpenImageIO among them) load on the first bake

    if progress is not None and not callable(progress):
        raise TypeError("progress must be a callable(stage: str, fraction: float) or None")
    summary = _bake.bake(
        _path("fabric", fabric),
        _path("output", output),
        progress,
        _positive_or_default("resolution", resolution),
        _threads(threads),
        bool(force),
        _positive_or_default("max_memory", max_memory),
    )
    return BakeResult(
        path=str(summary["path"]),
        size_bytes=int(summary["size_bytes"]),
        content_hash=str(summary["content_hash"]),
        unchanged=bool(summary["unchanged"]),
        wall_seconds=float(summary["wall_seconds"]),
        threads=int(summary["threads"]),
        stages=tuple((str(name), float(seconds)) for name, seconds in summary["stages"]),
        warnings=tuple(str(w) for w in summary["warnings"]),
    )


def _choice(name: str, value: str, choices: dict[str, int]) -> int:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(choices)}; got {value!r}")
    return choices[value]


def _check_uint64(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    if not 0 <= int(value) < _UINT64:
        raise ValueError(f"{name} must be in [0, 2**64), got {value}")
    return int(value)


def _check_lobes(lobes: int) -> int:
    if isinstance(lobes, bool) or not isinstance(lobes, (int, np.integer)):
        raise TypeError(f"lobes must be an int or a Lobe, got {type(lobes).__name__}")
    if not 0 <= int(lobes) < (1 << 32):
        raise ValueError(f"lobes must be a mask of Lobe flags, got {lobes}")
    return int(lobes)  # 0 or unknown bits: the library's InvalidArgumentError


def _threads(threads: int | None) -> int:
    if threads is None:
        return 0
    if isinstance(threads, bool) or not isinstance(threads, int):
        raise TypeError(f"threads must be an int or None, got {type(threads).__name__}")
    if threads < 1:
        raise ValueError(f"threads must be >= 1 (None: one per core), got {threads}")
    return threads


def _positive_or_default(name: str, value: int | None) -> int:
    if value is None:
        return 0
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{name} must be an int or None, got {type(value).__name__}")
    if value < 1:
        raise ValueError(f"{name} must be >= 1 (None: the default), got {value}")
    return value


def _path(name: str, value: str | os.PathLike[str]) -> str:
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} must be a path (str or os.PathLike), got {type(value).__name__}")
    path = os.fspath(value)
    if not isinstance(path, str):
        raise TypeError(f"{name} must be a str path, got bytes")
    return path


def _real_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    array = np.asarray(value)
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{name} must hold real numbers (float or int dtype), got dtype {array.dtype}"
        )
    return np.ascontiguousarray(array, dtype=np.float64)


def _footprints(value: ArrayLike) -> NDArray[np.float64]:
    array = _real_array("footprints", value)
    if array.ndim != 2 or array.shape[1] != 4:
        raise ValueError(
            f"footprints must have shape (n, 4), rows (u0, v0, u1, v1) in tile units; "
            f"got shape {array.shape}"
        )
    return array


def _rows(
    name: str, value: ArrayLike, n: int, broadcast: bool = True, against: str = "footprints"
) -> NDArray[np.float64]:
    array = _real_array(name, value)
    if broadcast and array.shape == (3,):
        return np.ascontiguousarray(np.broadcast_to(array, (n, 3)))
    if array.ndim != 2 or array.shape[1] != 3:
        shapes = "(n, 3) or (3,)" if broadcast else "(n, 3)"
        raise ValueError(f"{name} must have shape {shapes}, got shape {array.shape}")
    if array.shape[0] != n:
        raise ValueError(f"{name} has {array.shape[0]} rows, {against} has {n}")
    return array
