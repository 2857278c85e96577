"""Fixtures of the Python module's tests: one small fabric baked once per session through
clothbake.bake (the progress reports kept for test_bake), opened validated."""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

import clothbake

REPO = Path(__file__).resolve().parents[2]

# A twill at 32^2 with coarse direction grids: a bake of about a second that still has every
# section the evaluator reads (parallax, visibility clusters, compressed Integral-Radiance tables,
# sheen) and gaps between the yarns (the delta transmission lobe).
TWILL_32 = """name = "twill 32"
[weave]
name = "twill3/1"
[weave.warp]
spacing_mm = 0.30
width = 0.75
height_mm = 0.16
twist_deg = 25
[weave.weft]
spacing_mm = 0.30
width = 0.7
height_mm = 0.14
twist_deg = 20
[[yarn]]
name = "warp"
roughness = 0.40
color = [0.05, 0.09, 0.26]
[[yarn]]
name = "weft"
roughness = 0.45
color = [0.78, 0.74, 0.64]
[sheen]
color = 0.25
roughness = 0.45
[bake]
resolution = 32
parallax_dirs = 16
visibility_dirs = 12
radiance_dirs = 16
clusters = 4
"""


@dataclass(frozen=True)
class Baked:
    fabric: Path
    path: Path
    result: clothbake.BakeResult
    reports: list[tuple[str, float]]


@pytest.fixture(scope="session")
def baked(tmp_path_factory: pytest.TempPathFactory) -> Baked:
    folder = tmp_path_factory.mktemp("baked")
    fabric = folder / "twill32.toml"
    fabric.write_text(TWILL_32)
    reports: list[tuple[str, float]] = []
    output = folder / "twill32.cbk"
    result = clothbake.bake(fabric, output, progress=lambda s, f: reports.append((s, f)))
    return Baked(fabric, output, result, reports)


@pytest.fixture(scope="session")
def asset(baked: Baked) -> clothbake.Asset:
    return clothbake.open_asset(baked.path)


@pytest.fixture(scope="session")
def clothbake_exe() -> str:
    """The clothbake executable of the same build: $CLOTHBAKE_EXE (the ctest entry sets it), else
    one on PATH; the tests that compare against it are skipped without one (a pip-installed module
    tested alone)."""
    exe = os.environ.get("CLOTHBAKE_EXE") or shutil.which("clothbake")
    if not exe:
        pytest.skip("no clothbake executable (set CLOTHBAKE_EXE)")
    assert os.access(exe, os.X_OK), f"CLOTHBAKE_EXE={exe} is not an executable"
    return exe
