"""clothbake.bake: the library's bake with progress reported to a Python callable, its cancellation
by the callable or Ctrl-C, and its errors."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from itertools import pairwise
from pathlib import Path

import pytest

import clothbake
from conftest import REPO, TWILL_32, Baked

STAGES = ["load_fabric", "fabric_records", "feature_maps", "parallax", "visibility", "cluster",
          "tables", "compress", "write"]  # fmt: skip


def test_progress_is_monotone_per_stage_and_the_asset_opens(baked: Baked) -> None:
    reports = baked.reports
    assert [s for s, _ in reports if _ == 0.0] == STAGES
    for stage in STAGES:
        fractions = [f for s, f in reports if s == stage]
        assert fractions[0] == 0.0 and fractions[-1] == 1.0, stage
        assert all(a < b for a, b in pairwise(fractions)), (stage, fractions)
        assert all(b - a >= 0.01 for a, b in pairwise(fractions[1:-1])), stage
    # Stages report in run order: once a stage ends, no report of it or of an earlier one follows.
    order = [STAGES.index(s) for s, _ in reports]
    assert order == sorted(order)
    assert any(0.0 < f < 1.0 for _, f in reports)  # the stages' own reports come through

    result = baked.result
    assert result.path == str(baked.path) and not result.unchanged
    assert result.size_bytes == baked.path.stat().st_size
    assert [name for name, _ in result.stages] == STAGES
    assert len(result.content_hash) == 16 and result.threads >= 1
    asset = clothbake.open_asset(baked.path)
    assert asset.info.resolution == 32
    assert sorted(baked.path.parent.iterdir()) == sorted([baked.fabric, baked.path])  # no temp


def test_an_exception_in_the_callback_cancels_the_bake_and_is_raised(
    baked: Baked, tmp_path: Path
) -> None:
    output = tmp_path / "cancelled.cbk"
    seen: list[tuple[str, float]] = []

    class Stop(Exception):
        pass

    def progress(stage: str, fraction: float) -> None:
        seen.append((stage, fraction))
        if stage == "parallax" and fraction > 0.0:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        clothbake.bake(baked.fabric, output, progress=progress)
    assert seen[-1][0] == "parallax"  # not called again after it raised
    assert list(tmp_path.iterdir()) == []  # no asset, no temporary file

    # An existing asset at the output is left as it was.
    previous = tmp_path / "previous.cbk"
    previous.write_bytes(baked.path.read_bytes())
    with pytest.raises(Stop):
        clothbake.bake(baked.fabric, previous, progress=progress)
    assert previous.read_bytes() == baked.path.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["previous.cbk"]


def test_the_same_bake_again_leaves_the_file_unchanged(baked: Baked, tmp_path: Path) -> None:
    output = tmp_path / "again.cbk"
    output.write_bytes(baked.path.read_bytes())
    result = clothbake.bake(baked.fabric, output, threads=1)
    assert result.unchanged and result.content_hash == baked.result.content_hash
    assert output.read_bytes() == baked.path.read_bytes()  # and a single thread bakes it alike


def test_bake_errors_name_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(TWILL_32.replace("roughness = 0.40", "roughness = -1"))
    with pytest.raises(clothbake.BakeError, match=r"bad\.toml") as raised:
        clothbake.bake(bad, tmp_path / "bad.cbk")
    assert raised.value.code == "input" and isinstance(raised.value, clothbake.Error)
    with pytest.raises(clothbake.BakeError, match=r"missing\.toml"):
        clothbake.bake(tmp_path / "missing.toml", tmp_path / "x.cbk")
    not_an_asset = tmp_path / "notes.txt"
    not_an_asset.write_text("keep me")
    good = tmp_path / "good.toml"
    good.write_text(TWILL_32)
    with pytest.raises(clothbake.BakeError, match=r"notes\.txt"):
        clothbake.bake(good, not_an_asset)
    assert not_an_asset.read_text() == "keep me"
    with pytest.raises(clothbake.BakeError, match="memory"):
        clothbake.bake(good, tmp_path / "big.cbk", max_memory=1000)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "good.toml", "notes.txt"]
    with pytest.raises(TypeError, match="progress must be a callable"):
        clothbake.bake(good, tmp_path / "y.cbk", progress=3)  # type: ignore[arg-type]


def test_ctrl_c_cancels_a_bake(baked: Baked, tmp_path: Path) -> None:
    # A child bakes the full-size demo twill (seconds); SIGINT once its parallax stage has started.
    script = (
        "import sys, clothbake\n"
        "def progress(stage, fraction):\n"
        "    if stage == 'parallax' and fraction == 0.0:\n"
        "        print('started', flush=True)\n"
        "try:\n"
        f"    clothbake.bake({str(REPO / 'examples/fabrics/twill.toml')!r}, 'out.cbk',\n"
        "                   progress=progress)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True)\n"
    )
    package_root = str(Path(clothbake.__file__).resolve().parents[1])  # the same module
    child = subprocess.Popen([sys.executable, "-c", script], cwd=tmp_path, text=True,
                             env={**os.environ, "PYTHONPATH": package_root},
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    assert child.stdout is not None and child.stderr is not None
    if child.stdout.readline() != "started\n":
        child.kill()
        pytest.fail(f"the child did not start baking: {child.communicate()[1]}")
    start = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=60)
    assert out == "interrupted\n", err
    assert time.monotonic() - start < 5.0
    assert list(tmp_path.iterdir()) == []  # no asset, no temporary file
