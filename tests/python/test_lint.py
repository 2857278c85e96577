"""The module's Python is ruff-clean and formatted, and type-checks under mypy --strict
(pyproject.toml's settings: the package with its stubs, and these tests). Skipped where the tools
are not installed (a module installed alone); scripts/setup installs both into .venv."""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import pytest

from conftest import REPO


def run(tool: str, *args: str) -> None:
    if importlib.util.find_spec(tool) is None:
        pytest.skip(f"{tool} is not installed")
    done = subprocess.run([sys.executable, "-m", tool, *args], cwd=REPO, capture_output=True,
                          text=True)  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr


def test_ruff_finds_nothing() -> None:
    run("ruff", "check", "--no-cache")
    run("ruff", "format", "--check", "--no-cache")


def test_mypy_strict_finds_nothing() -> None:
    run("mypy")  # files, strictness and paths from pyproject.toml; MYPY_CACHE_DIR from ctest
