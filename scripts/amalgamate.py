#!/usr/bin/env python3
"""Generates capi/clothbake.cpp, the single source file of the C interface (docs/integration.md,
"One source file").

Usage: amalgamate.py [--check] [--output PATH] [--count]

The file is the C interface's implementation (capi/clothbake_c.cpp) followed by every source of the
libraries it links (the reader, the raw-table reader, the validator, the evaluator), with every
project header they include pasted in once, at its first #include, in the order the sources list.
System headers stay #includes; "clothbake.h" stays an #include (a renderer keeps the two files
side by side). The sources are not edited: the generator only pastes, so a name two sources define
in their anonymous namespaces must differ in the sources themselves (the build compiles the
result, which catches a clash).

  --check   exit 1, naming the first differing line, when the checked-in file is not what the
            sources generate now (the build runs this: tests/capi/CMakeLists.txt)
  --output  write there instead of capi/clothbake.cpp
  --count   print the lines a renderer compiles: all, code (neither blank nor comment-only), and
            the code lines of table data (the sheen tables), and exit
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The translation units, in order: each library's sources as its CMakeLists.txt lists them, less
# what the single file leaves out (docs/integration.md, "One source file"): the raw-table reader
# (formats/reader_raw), the paper's biased multi-scale method (control_variates.cpp and its
# footprint sums) and the validator's metadata check (metadata_limits.cpp; shading reads no
# metadata).
SOURCES: list[str] = (
    ["capi/clothbake_c.cpp"]
    + [
        f"eval/{name}.cpp"
        for name in (
            "brute_force",
            "cv_texels",
            "eval_data",
            "evaluator",
            "exact_sum",
            "footprint_cover",
            "importance_sampling",
            "pushforward_cv",
            "pushforward_sums",
            "subperiod_sums",
            "texel_shading",
            "visibility_pilot",
        )
    ]
    + [f"formats/validate/{name}.cpp" for name in ("validate", "checksums", "xxh64")]
    + sorted(str(p.relative_to(ROOT)) for p in (ROOT / "formats/reader").glob("*.cpp"))
)

# Headers whose code is table data (not counted as code a renderer reads).
TABLE_HEADERS = {"model/sheen_table.hpp", "model/sheen_table_converged.hpp"}

SINGLE_FILE_MACRO = "CLOTHBAKE_SINGLE_FILE"
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
PRAGMA_ONCE = re.compile(r"^\s*#\s*pragma\s+once\b")


def single_file_lines(path: Path) -> list[str]:
    """The lines of `path` as the single file compiles them: CLOTHBAKE_SINGLE_FILE is defined there,
    so an `#ifndef CLOTHBAKE_SINGLE_FILE` block is left out (its #else part kept) and an `#ifdef
    CLOTHBAKE_SINGLE_FILE` block kept without its directives (its #else part left out). Other
    conditionals pass through untouched."""
    kept: list[str] = []
    # One entry per open conditional: None for one passed through, else whether its current branch
    # is kept.
    stack: list[bool | None] = []

    def keeping() -> bool:
        return all(entry is not False for entry in stack)

    for line in path.read_text(encoding="utf-8").splitlines():
        directive = re.match(r"^\s*#\s*(ifndef|ifdef|if|elif|else|endif)\b\s*(\w*)", line)
        if directive:
            word, name = directive.group(1), directive.group(2)
            if word in ("ifndef", "ifdef", "if"):
                if word != "if" and name == SINGLE_FILE_MACRO:
                    stack.append(word == "ifdef")
                    continue
                stack.append(None)
            elif word == "elif":
                if stack and stack[-1] is not None:
                    raise SystemExit(f"amalgamate.py: {path}: #elif in a {SINGLE_FILE_MACRO} block")
            elif word == "else":
                if stack and stack[-1] is not None:
                    stack[-1] = not stack[-1]
                    continue
            elif word == "endif":
                if stack and stack.pop() is not None:
                    continue
        if keeping():
            kept.append(line)
    if stack:
        raise SystemExit(f"amalgamate.py: {path}: unterminated conditional")
    return kept


def resolve(name: str, including: Path) -> Path | None:
    """The project file an #include "name" refers to, or None for clothbake.h."""
    if Path(name).name == "clothbake.h":
        return None
    for base in (ROOT, including.parent):
        candidate = (base / name).resolve()
        if candidate.is_file():
            return candidate
    raise SystemExit(f"amalgamate.py: {including.relative_to(ROOT)}: cannot find \"{name}\"")


class Amalgamation:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.seen: set[Path] = set()
        self.owner: list[str] = []  # per output line, the file it comes from (root-relative)

    def paste(self, path: Path) -> None:
        if path in self.seen:
            return
        self.seen.add(path)
        relative = str(path.relative_to(ROOT))
        self.emit(f"// ---- {relative} ----", relative)
        for line in single_file_lines(path):
            if PRAGMA_ONCE.match(line):
                continue
            match = INCLUDE.match(line)
            if match:
                target = resolve(match.group(1), path)
                if target is None:
                    self.emit('#include "clothbake.h"', relative)
                elif target not in self.seen:
                    self.paste(target)
                    self.emit(f"// ---- {relative} (continued) ----", relative)
                continue
            self.emit(line, relative)

    def emit(self, line: str, relative: str) -> None:
        self.lines.append(line)
        self.owner.append(relative)

    def text(self) -> str:
        header = [
            "// clothbake.cpp: the clothbake reader, validator and evaluator behind clothbake.h, as one",
            "// source file (docs/integration.md, \"One source file\"). GENERATED by scripts/amalgamate.py",
            "// from the sources named in the '// ---- path ----' lines below; do not edit: change those",
            "// sources and run scripts/amalgamate.py. Compiles alone as C++17, with or without",
            "// exceptions: c++ -std=c++17 -O2 -fno-exceptions -c clothbake.cpp",
            "#define CLOTHBAKE_SINGLE_FILE 1  // what the sources' CLOTHBAKE_SINGLE_FILE blocks test",
        ]
        return "\n".join(header + self.lines) + "\n"


def is_code(line: str, in_block: bool) -> tuple[bool, bool]:
    """Whether `line` holds code (not blank, not only a comment), and whether a /* */ comment is
    still open after it."""
    code = False
    i, n = 0, len(line)
    while i < n:
        if in_block:
            end = line.find("*/", i)
            if end < 0:
                return code, True
            in_block, i = False, end + 2
            continue
        rest = line[i:].lstrip()
        if not rest:
            break
        if rest.startswith("//"):
            break
        if rest.startswith("/*"):
            in_block, i = True, line.index("/*", i) + 2
            continue
        code = True
        end = line.find("/*", i)
        if end < 0:
            break
        i = end
    return code, in_block


def count(amalgamation: Amalgamation) -> None:
    code = table = 0
    in_block = False  # a file's comments close in that file: one state suffices
    for line, relative in zip(amalgamation.lines, amalgamation.owner):
        is_code_line, in_block = is_code(line, in_block)
        if is_code_line:
            if relative in TABLE_HEADERS:
                table += 1
            else:
                code += 1
    print(f"lines {len(amalgamation.text().splitlines())}")
    print(f"code lines (not blank, not comment only), table data excluded {code}")
    print(f"code lines of table data {table}")
    print(f"files pasted {len(amalgamation.seen)}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--count", action="store_true")
    parser.add_argument("--output", type=Path, default=ROOT / "capi/clothbake.cpp")
    args = parser.parse_args()

    amalgamation = Amalgamation()
    for source in SOURCES:
        amalgamation.paste((ROOT / source).resolve())
    if args.count:
        count(amalgamation)
        return 0
    text = amalgamation.text()
    if args.check:
        current = args.output.read_text(encoding="utf-8") if args.output.is_file() else ""
        if current == text:
            return 0
        old, new = current.splitlines(), text.splitlines()
        for number, (a, b) in enumerate(zip(old, new), start=1):
            if a != b:
                break
        else:
            number = min(len(old), len(new)) + 1
        print(
            f"amalgamate.py: {args.output} is not what the sources generate (first difference at line "
            f"{number}); run scripts/amalgamate.py",
            file=sys.stderr,
        )
        return 1
    args.output.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
