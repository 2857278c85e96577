#!/usr/bin/env python3
"""Proves that scripts/check_layers fails when a folder includes one it may not use.

Plants, in a throw-away tree checked against the real table of docs/architecture.md, the upward
includes the code base had before the layers were enforced (a stage in cluster/ including the
pipeline, compress/ and formats/writer including the fabric loader, verify/ including the bake's
tables) plus the rules the table adds (the reader and the model stay free of common/, fabric/
does not use OpenImageIO, every folder is in the table), and checks that each is reported with
its file and line; a clean tree passes; a table with a cycle is refused.
"""
import os
import subprocess
import sys
import tempfile
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(REPO, "scripts", "check_layers")
TABLE = os.path.join(REPO, "docs", "architecture.md")


def run_check(files, table=TABLE):
    """Writes `files` ({path: text}) into a fresh tree and runs the check on it."""
    with tempfile.TemporaryDirectory() as root:
        for path, text in files.items():
            full = os.path.join(root, path)
            os.makedirs(os.path.dirname(full), exist_ok=True)
            with open(full, "w", encoding="utf-8") as f:
                f.write(text)
        result = subprocess.run([sys.executable, CHECK, "--root", root, "--table", table],
                                capture_output=True, text=True)
        return result.returncode, result.stdout + result.stderr


CLEAN = {
    "model/asg.hpp": "#pragma once\n#include <cmath>\n",
    "formats/reader/asset.hpp": '#pragma once\n#include "model/asg.hpp"\n',
    "fabric/fabric.hpp": "#pragma once\n#include <vector>\n",
    "raycast/parallax.hpp": '#pragma once\n#include "fabric/fabric.hpp"\n#include <embree3/rtcore.h>\n',
    "bake/stages/parallax_stage.cpp": '#include "raycast/parallax.hpp"\n#include "bake/pipeline/stage.hpp"\n',
    "bake/pipeline/stage.hpp": "#pragma once\n",
    "bake/cli/main.cpp": '#include "bake/stages/stages.hpp"\n#include "verify/radiance_verify.hpp"\n',
    "tests/raycast/test_parallax.cpp": '#include "bake/cli/command.hpp"\n#include "reference.hpp"\n',
}

# The violations, and the line each one must produce.
PLANTED = {
    "cluster/cluster_stage.cpp": ('#include <vector>\n\n#include "bake/pipeline/stage.hpp"\n',
                                  "cluster/cluster_stage.cpp:3: cluster may not include "
                                  "bake/pipeline"),
    "compress/compress_settings.cpp": ('#include "compress/compress_settings.hpp"\n'
                                       '#include "bake/inputs/fabric_load.hpp"\n',
                                       "compress/compress_settings.cpp:2: compress may not "
                                       "include bake/inputs"),
    "formats/writer/fabric_sections.hpp": ('#pragma once\n#include "bake/inputs/fabric_load.hpp"\n',
                                           "formats/writer/fabric_sections.hpp:2: formats/writer "
                                           "may not include bake/inputs"),
    "verify/radiance_verify.hpp": ('#pragma once\n#include "bake/stages/stages.hpp"\n',
                                   "verify/radiance_verify.hpp:2: verify may not include "
                                   "bake/stages"),
    "formats/reader/status.hpp": ('#pragma once\n#  include "common/error.hpp"\n',
                                  "formats/reader/status.hpp:2: formats/reader may not include "
                                  "common"),
    "model/sggx.hpp": ('#pragma once\n#include <formats/reader/asset.hpp>\n',
                       "model/sggx.hpp:2: model may not include formats/reader"),
    "fabric/fabric_json.cpp": ('#include "common/image_io/image_io.hpp"\n',
                               "fabric/fabric_json.cpp:1: fabric may not include common/image_io"),
    "raycast/visibility.cpp": ('#include "bake/tables/radiance_fill.hpp"\n',
                               'raycast/visibility.cpp:1: includes "bake/tables/radiance_fill.hpp"'
                               ", which is in no folder of the layer table"),
    "newfolder/thing.cpp": ("int x;\n", "newfolder/thing.cpp: folder 'newfolder' is not in the "
                            "layer table"),
    "sheen/ltc_fit.cpp": ('#include "../bake/cli/command.hpp"\n',
                          'sheen/ltc_fit.cpp:1: "../bake/cli/command.hpp" climbs out of its folder'),
}


class CheckLayers(unittest.TestCase):
    def test_the_repository_passes(self):
        result = subprocess.run([sys.executable, CHECK, "--root", REPO], capture_output=True,
                                text=True)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)

    def test_a_clean_tree_passes(self):
        code, out = run_check(CLEAN)
        self.assertEqual(code, 0, out)

    def test_every_planted_violation_is_reported(self):
        files = dict(CLEAN)
        files.update({path: text for path, (text, _) in PLANTED.items()})
        code, out = run_check(files)
        print(out)  # shown by ctest --output-on-failure and -V: the check failing, as it prints
        self.assertEqual(code, 1, out)
        for path, (_, expected) in PLANTED.items():
            self.assertIn(expected, out, f"{path} not reported")
        self.assertEqual(len([l for l in out.splitlines() if l.startswith(tuple(PLANTED))]),
                         len(PLANTED), out)

    def test_a_table_with_a_cycle_is_refused(self):
        with tempfile.TemporaryDirectory() as d:
            table = os.path.join(d, "table.md")
            with open(table, "w", encoding="utf-8") as f:
                f.write("```layers\nmodel  formats/reader\nformats/reader  model\n```\n")
            code, out = run_check({"model/a.hpp": "\n"}, table)
        self.assertEqual(code, 2, out)
        self.assertIn("cycle", out)


if __name__ == "__main__":
    unittest.main(verbosity=2)
