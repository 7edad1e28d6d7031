#!/usr/bin/env python3
"""tools/check_layers.py catches an upward include in each of its forms: "talus/<layer>/...",
<talus/<layer>/...>, and a private header of src/, "<layer>/..." (a review found the last two
passed), and leaves other libraries' headers ("hwy/...", <fmt/...>) alone."""
import pathlib
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parent.parent.parent
LAYERS = ["core", "grid", "scene", "solver"]


def check(grid_cpp: str):
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "include" / "talus" / "grid").mkdir(parents=True)
        (root / "src" / "grid").mkdir(parents=True)
        (root / "src" / "grid" / "grid.cpp").write_text(grid_cpp)
        run = subprocess.run([sys.executable, str(ROOT / "tools" / "check_layers.py"), "--root", str(root),
                              "--layers", *LAYERS], capture_output=True, text=True)
        return run.returncode, run.stdout


class CheckLayers(unittest.TestCase):
    def test_every_form_of_an_upward_include_is_caught(self):
        for include in ('#include "talus/scene/scene.hpp"', "#include <talus/solver/solver.hpp>",
                        '#include "scene/scene_fields.hpp"'):
            code, out = check(f'#include "talus/core/types.hpp"\n{include}\n')
            self.assertEqual(code, 1, include)
            self.assertIn("src/grid/grid.cpp:2: layer 'grid' includes talus/", out)

    def test_own_and_lower_layers_and_other_libraries_pass(self):
        code, out = check('#include "talus/core/types.hpp"\n#include "grid/private.hpp"\n'
                          '#include <talus/grid/grid.hpp>\n#include "hwy/highway.h"\n#include <fmt/core.h>\n')
        self.assertEqual(code, 0, out)
        self.assertIn("layers ok", out)


if __name__ == "__main__":
    unittest.main()
