"""The hand-written stubs of the two extensions (python/clothbake/_shading.pyi, _bake.pyi) name
the same functions, classes and parameters as the extensions themselves (nanobind's stubgen reads
those from the built module)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest
from nanobind.stubgen import StubGen  # type: ignore[import-untyped]

import clothbake

PACKAGE = Path(clothbake.__file__).parent


def signatures(source: str) -> dict[str, list[str]]:
    """{qualified name: parameter names} of every def; {name: []} of every class and constant."""
    found: dict[str, list[str]] = {}

    def visit(body: list[ast.stmt], prefix: str) -> None:
        for node in body:
            if isinstance(node, ast.FunctionDef):
                found[prefix + node.name] = [a.arg for a in node.args.args]
            elif isinstance(node, ast.ClassDef):
                found[prefix + node.name] = []
                visit(node.body, prefix + node.name + ".")
            elif isinstance(node, (ast.AnnAssign, ast.Assign)):
                target = node.target if isinstance(node, ast.AnnAssign) else node.targets[0]
                if isinstance(target, ast.Name):
                    found[prefix + target.id] = []

    visit(ast.parse(source).body, "")
    return found


@pytest.mark.parametrize("name", ["_shading", "_bake"])
def test_the_stubs_match_the_extension(name: str) -> None:
    generator = StubGen(importlib.import_module(f"clothbake.{name}"))
    generator.put(importlib.import_module(f"clothbake.{name}"))
    generated = signatures(generator.get())
    written = signatures((PACKAGE / f"{name}.pyi").read_text())
    assert generated and written == generated
