"""docs/python.md's ten-line example, run verbatim."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def test_the_ten_line_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                   capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    page = (REPO / "docs" / "python.md").read_text()
    blocks = re.findall(r"^```python\n(.*?)^```$", page, flags=re.S | re.M)
    assert blocks, "docs/python.md has no python block"
    example = blocks[0]
    assert len([line for line in example.splitlines() if line.strip()]) <= 10
    (tmp_path / "examples").symlink_to(REPO / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(example, "docs/python.md", "exec"), {"__name__": "__example__"})
    out = capsys.readouterr().out
    assert "write" in out and "100%" in out and "AssetInfo(resolution=32" in out
    assert (tmp_path / "twill.cbk").stat().st_size > 0
    assert sorted(os.listdir(tmp_path)) == ["examples", "twill.cbk"]  # no temporary file left
