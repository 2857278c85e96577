"""clothbake's shading half: assets, their info, and estimate / sample / pdf over numpy arrays
against `clothbake eval` (bit for bit), across thread counts (bit for bit), and their errors."""

from __future__ import annotations

import json
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import clothbake
from conftest import Baked

WI = np.array([0.3, -0.2, 0.9])
WO = np.array([-0.1, 0.4, 0.8])


def random_footprints(n: int, seed: int = 5) -> np.ndarray:
    """n footprints in tile units: corners anywhere in [-2, 3), sides from a point to 1.5 tiles."""
    rng = np.random.default_rng(seed)
    corner = rng.uniform(-2.0, 3.0, size=(n, 2))
    side = rng.uniform(0.0, 1.5, size=(n, 2)) * (rng.uniform(size=(n, 1)) < 0.8)
    return np.concatenate([corner, corner + side], axis=1)


def random_directions(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05
    unit: np.ndarray = d / np.linalg.norm(d, axis=1, keepdims=True)
    return unit


def test_an_asset_opens_from_its_path_and_from_its_bytes_with_the_same_info(
    baked: Baked, asset: clothbake.Asset
) -> None:
    info = asset.info
    assert info.resolution == 32
    assert info.tile_size_mm is not None and info.tile_size_mm > 0
    assert info.scene_planned is False
    assert asset.source == str(baked.path) and not asset.trusted
    from_bytes = clothbake.open_asset(baked.path.read_bytes())
    assert from_bytes.info == info and from_bytes.source == "asset in memory"
    assert clothbake.open_asset(bytearray(baked.path.read_bytes()), trusted=True).info == info


def texels(value: float, resolution: int) -> str:
    return repr(value * resolution)  # repr round-trips a double, as %.17g does


def numbers(values: np.ndarray) -> str:
    return ",".join(repr(float(v)) for v in values)


@pytest.mark.parametrize(
    ("method", "spp", "seed"), [("multiscale", 1, 1), ("multiscale", 4, 9), ("brute", 2, 123456789)]
)
def test_the_first_row_equals_clothbake_eval_bit_for_bit(
    baked: Baked, asset: clothbake.Asset, clothbake_exe: str, method: str, spp: int, seed: int
) -> None:
    n = asset.info.resolution
    evaluator = clothbake.Evaluator(asset, method=method, spp=spp)  # type: ignore[arg-type]
    for footprint in ([0.25, 0.5, 0.75, 0.625], [-0.75, 2.5, 0.75, 3.75], [0.3, 0.3, 0.3, 0.3]):
        value = evaluator.estimate([footprint], WI, WO, seed=seed)[0]
        rect = ",".join(texels(v, n) for v in footprint)
        run = subprocess.run(
            [clothbake_exe, "eval", str(baked.path), "--rect", rect,
             "--wi", numbers(WI), "--wo", numbers(WO),
             "--method", method, "--spp", str(spp), "--seed", str(seed), "--json"],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        expected = json.loads(run.stdout)["value"]
        assert value.tolist() == expected, (footprint, value, expected)


def test_each_chunk_draws_from_its_own_generator_seeded_by_chunk_seed(
    asset: clothbake.Asset,
) -> None:
    evaluator = clothbake.Evaluator(asset, method="brute", spp=2)
    n = 3 * clothbake.CHUNK_SIZE + 5
    f = random_footprints(n)
    wi = random_directions(n, 1)
    all_rows = evaluator.estimate(f, wi, WO, seed=42)
    for chunk in range(4):
        row = chunk * clothbake.CHUNK_SIZE
        alone = evaluator.estimate(f[row : row + 2], wi[row : row + 2], WO,
                                   seed=clothbake.chunk_seed(42, chunk))  # fmt: skip
        assert np.array_equal(alone, all_rows[row : row + 2]), chunk
    assert clothbake.chunk_seed(42, 0) == 42
    assert len({clothbake.chunk_seed(42, c) for c in range(100)}) == 100


@pytest.mark.parametrize("method", ["multiscale", "brute"])
def test_results_do_not_depend_on_the_thread_count(asset: clothbake.Asset, method: str) -> None:
    evaluator = clothbake.Evaluator(asset, method=method)  # type: ignore[arg-type]
    n = 4 * clothbake.CHUNK_SIZE + 17
    f = random_footprints(n)
    wi, wo = random_directions(n, 2), random_directions(n, 3)
    u = np.random.default_rng(4).uniform(size=(n, 3))
    one = evaluator.estimate(f, wi, wo, seed=7, threads=1)
    two = evaluator.estimate(f, wi, wo, seed=7, threads=2)
    assert np.array_equal(one, two)
    assert np.isfinite(one).all() and one.sum() > 0
    assert not np.array_equal(one, evaluator.estimate(f, wi, wo, seed=8, threads=2))
    s1, s2 = evaluator.sample(f, wo, u, threads=1), evaluator.sample(f, wo, u, threads=2)
    for a, b in zip(s1, s2, strict=True):
        assert np.array_equal(a, b)
    assert np.array_equal(evaluator.pdf(f, wi, wo, threads=1), evaluator.pdf(f, wi, wo, threads=2))


def test_the_density_of_a_sampled_direction_is_the_samples_pdf(asset: clothbake.Asset) -> None:
    evaluator = clothbake.Evaluator(asset)
    n = 600
    f = random_footprints(n, seed=11)
    wo = random_directions(n, 12)
    s = evaluator.sample(f, wo, np.random.default_rng(13).uniform(size=(n, 3)))
    continuous = s.valid & ~s.is_delta
    assert continuous.sum() > n // 2
    assert s.is_delta.any()  # the twill has gaps: the delta lobe is sampled too
    unit_wo = wo / np.linalg.norm(wo, axis=1, keepdims=True)  # the library normalises it again
    np.testing.assert_allclose(s.wi[s.is_delta], -unit_wo[s.is_delta], rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(s.wi[continuous], axis=1), 1.0, rtol=1e-12)
    pdf = evaluator.pdf(f[continuous], s.wi[continuous], wo[continuous])
    np.testing.assert_allclose(pdf, s.pdf[continuous], rtol=1e-12)
    assert (pdf > 0).all()


def test_sampling_reaches_the_gaps_of_footprints_centred_on_yarn(asset: clothbake.Asset) -> None:
    """BSDF sampling is the only way a path tracer reaches the delta lobe, so every footprint that
    transmits through gaps must draw it: the sampling estimate of the delta weight, the mean of
    W / p(delta) over delta draws and 0 otherwise, is unbiased for the footprint's W (the
    reference's delta estimate). 4 x 4-texel footprints at every texel of the 32-texel tile, most
    of them centred on yarn (where the representative texel alone has p(delta) = 0)."""
    n, draws = 32, 2000
    evaluator = clothbake.Evaluator(asset, method="reference")
    corners = np.array([[x, y] for y in range(n) for x in range(n)], dtype=float) / n
    footprints = np.concatenate([corners, corners + 4.0 / n], axis=1)
    wo = np.array([0.2, 0.1, 0.97]) / np.linalg.norm([0.2, 0.1, 0.97])
    weight = evaluator.estimate(footprints, -wo, wo, lobes=clothbake.Lobe.DELTA_TRANSMISSION)
    u = np.random.default_rng(17).uniform(size=(n * n * draws, 3))
    s = evaluator.sample(np.repeat(footprints, draws, axis=0), wo, u)
    delta = (s.valid & s.is_delta).reshape(n * n, draws)
    p_delta = np.where(delta, s.pdf.reshape(n * n, draws), 1.0)
    terms = np.where(delta[..., None], weight[:, None, :] / p_delta[..., None], 0.0)
    estimate = terms.mean(axis=1)
    error = terms.std(axis=1, ddof=1) / np.sqrt(draws)
    transmits = weight.mean(axis=1) > 1e-6
    assert transmits.sum() > 100 and (~transmits).sum() > 100
    assert delta[transmits].any(axis=1).all(), "footprints with gaps that never draw the delta lobe"
    z = (estimate - weight)[transmits] / np.maximum(error[transmits], 1e-12)
    assert np.abs(z).max() < 5.5, np.abs(z).max()
    # Together the footprints' z-scores are a standard normal sample.
    assert abs(z.mean()) < 4 / np.sqrt(z.size), z.mean()


def test_one_direction_serves_every_row_and_any_real_dtype_is_converted(
    asset: clothbake.Asset,
) -> None:
    evaluator = clothbake.Evaluator(asset, method="reference")
    f = random_footprints(5)
    rows = evaluator.estimate(f, np.tile(WI, (5, 1)), np.tile(WO, (5, 1)))
    assert np.array_equal(evaluator.estimate(f, WI, WO), rows)
    assert np.array_equal(evaluator.estimate(f.astype(np.float32).astype(np.float64), WI, WO),
                          evaluator.estimate(f.astype(np.float32), WI.tolist(), WO))  # fmt: skip
    assert evaluator.estimate(np.zeros((0, 4)), WI, WO).shape == (0, 3)
    only_sheen = evaluator.estimate(f, WI, WO, lobes=clothbake.Lobe.SHEEN)
    assert (only_sheen < rows).all()


def test_shape_and_dtype_errors_name_the_argument(asset: clothbake.Asset) -> None:
    evaluator = clothbake.Evaluator(asset)
    f = random_footprints(4)
    with pytest.raises(ValueError, match=r"footprints must have shape \(n, 4\)"):
        evaluator.estimate(f[:, :3], WI, WO)
    with pytest.raises(ValueError, match="footprints must have shape"):
        evaluator.estimate(f[0], WI, WO)
    with pytest.raises(ValueError, match="wi has 3 rows, footprints has 4"):
        evaluator.estimate(f, np.tile(WI, (3, 1)), WO)
    with pytest.raises(ValueError, match=r"wo must have shape \(n, 3\) or \(3,\)"):
        evaluator.pdf(f, WI, [1.0, 2.0])
    with pytest.raises(ValueError, match=r"u must have shape \(n, 3\)"):
        evaluator.sample(f, WO, [0.5, 0.5, 0.5])
    with pytest.raises(TypeError, match="footprints must hold real numbers"):
        evaluator.estimate(f.astype(np.complex128), WI, WO)
    with pytest.raises(TypeError, match="wi must hold real numbers"):
        evaluator.estimate(f, ["a", "b", "c"], WO)
    with pytest.raises(TypeError, match="seed must be an int"):
        evaluator.estimate(f, WI, WO, seed=1.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="seed must be in"):
        evaluator.estimate(f, WI, WO, seed=-1)
    with pytest.raises(ValueError, match="threads must be >= 1"):
        evaluator.estimate(f, WI, WO, threads=0)
    with pytest.raises(ValueError, match="method must be one of"):
        clothbake.Evaluator(asset, method="fast")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"spp must be in \[1, 2\*\*32\)"):
        clothbake.Evaluator(asset, spp=0)
    with pytest.raises(TypeError, match="direct_max_side must be a number"):
        clothbake.Evaluator(asset, direct_max_side="1")  # type: ignore[arg-type]
    with pytest.raises(clothbake.InvalidArgumentError, match="CB_ERROR_INVALID_ARGUMENT"):
        clothbake.Evaluator(asset, direct_max_side=-1.0)


def test_library_errors_carry_the_result_name_and_the_failing_row(asset: clothbake.Asset) -> None:
    evaluator = clothbake.Evaluator(asset)
    f = random_footprints(2 * clothbake.CHUNK_SIZE)
    f[300] = [0.5, 0.5, 0.25, 0.75]  # backwards in u
    f[400] = [np.nan, 0, 1, 1]
    with pytest.raises(clothbake.InvalidArgumentError) as raised:
        evaluator.estimate(f, WI, WO, threads=2)
    assert raised.value.code == "CB_ERROR_INVALID_ARGUMENT" and raised.value.result == 1
    assert "estimate, element 300:" in str(raised.value)
    assert isinstance(raised.value, ValueError) and isinstance(raised.value, clothbake.Error)
    with pytest.raises(clothbake.InvalidArgumentError, match="element 0"):
        evaluator.estimate(f[:1], WI, WO, lobes=0)
    with pytest.raises(clothbake.InvalidArgumentError, match="pdf, element 1"):
        evaluator.pdf(f[:2], np.array([WI, [0.0, 0.0, 0.0]]), WO)
    with pytest.raises(clothbake.InvalidArgumentError, match="sample, element 0"):
        evaluator.sample(f[:1], WO, [[0.5, np.nan, 0.5]])


def test_bad_assets_are_refused_naming_the_file(baked: Baked, tmp_path: Path) -> None:
    missing = tmp_path / "missing.cbk"
    with pytest.raises(clothbake.FileError, match=r"missing\.cbk") as raised:
        clothbake.open_asset(missing)
    assert raised.value.code == "CB_ERROR_IO" and isinstance(raised.value, OSError)
    garbage = tmp_path / "garbage.cbk"
    garbage.write_bytes(b"not an asset" * 100)
    with pytest.raises(clothbake.InvalidAssetError, match=r"garbage\.cbk"):
        clothbake.open_asset(garbage)
    # One flipped byte in the last section's payload: validation refuses it (naming the check),
    # a trusted open does not look.
    data = bytearray(baked.path.read_bytes())
    data[-9] ^= 0x55
    damaged = tmp_path / "damaged.cbk"
    damaged.write_bytes(bytes(data))
    with pytest.raises(clothbake.InvalidAssetError, match=r"damaged\.cbk.*CBK-E\d{3}") as refused:
        clothbake.open_asset(damaged)
    assert refused.value.code == "CB_ERROR_INVALID_ASSET"
    with pytest.raises(clothbake.InvalidAssetError, match=r"asset in memory.*CBK-E\d{3}"):
        clothbake.open_asset(bytes(data))
    assert clothbake.open_asset(damaged, trusted=True).trusted
    with pytest.raises(TypeError, match="source must be a path"):
        clothbake.open_asset(42)  # type: ignore[arg-type]


def test_calls_release_the_gil(asset: clothbake.Asset) -> None:
    evaluator = clothbake.Evaluator(asset, method="brute", spp=64)
    n = 64 * clothbake.CHUNK_SIZE
    f = random_footprints(n)
    counted = [0]
    done = threading.Event()

    def count() -> None:
        while not done.is_set():
            counted[0] += 1
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    time.sleep(0.01)
    try:
        start_count, start = counted[0], time.perf_counter()
        evaluator.estimate(f, WI, WO, threads=1)
        seconds, during = time.perf_counter() - start, counted[0] - start_count
    finally:
        done.set()
        counter.join()
    # With the GIL held for the whole call the counter could not run at all.
    assert seconds > 0.05, f"the call took {seconds:.3f} s: too short to tell"
    assert during >= 10, f"{during} counts in {seconds:.3f} s"
