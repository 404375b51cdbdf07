#!/usr/bin/python3
"""tools/check_layers.py on a small tree: an include within the rules passes, one that
points up a layer fails naming the file, the line and what its layer may include, and
two modules that include each other fail naming both.

    /usr/bin/python3 tests/tools/check_layers_test.py
"""
import os
import pathlib
import subprocess
import sys
import tempfile
import unittest

CHECK = pathlib.Path(__file__).resolve().parents[2] / "tools" / "check_layers.py"


class CheckLayersTest(unittest.TestCase):
    def tree(self, files):
        root = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_layers_"))
        for path, text in files.items():
            (root / path).parent.mkdir(parents=True, exist_ok=True)
            (root / path).write_text(text)
        rules = root / "layers.txt"
        rules.write_text("worker/pipeline/voxel=worker/pipeline/volume\n"
                         "worker/pipeline/volume=\n"
                         "worker/pipeline/run/parameter=worker/pipeline/voxel\n"
                         "worker/pipeline/run=worker/pipeline/run/parameter,worker/pipeline/voxel\n")
        return subprocess.run(["/usr/bin/python3", str(CHECK), str(rules), str(root)],
                              capture_output=True, text=True)

    def test_includes_within_the_rules_pass(self):
        r = self.tree({
            "worker/pipeline/volume/raw.h": '#include <vector>\n#include "absl/status/status.h"\n',
            "worker/pipeline/voxel/set.h": '#include "worker/pipeline/volume/raw.h"\n#include "common/types.h"\n',
            "worker/pipeline/run/parameters.h": '#include "worker/pipeline/voxel/set.h"\n',
            "worker/pipeline/run/pipeline.cc": '#include "worker/pipeline/run/parameters.h"\n',
        })
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("every include within its rules", r.stdout)

    def test_an_include_up_a_layer_fails_naming_it(self):
        r = self.tree({
            "worker/pipeline/volume/raw.cc": '\n#include "worker/pipeline/voxel/set.h"\n',
            "worker/pipeline/voxel/set.h": "",
            # The schema may not include the workflow (a pseudo-folder by file-name prefix).
            "worker/pipeline/run/parameter_table.cc": '#include "worker/pipeline/run/pipeline.h"\n',
            "worker/pipeline/run/pipeline.h": "",
        })
        self.assertEqual(r.returncode, 1)
        self.assertIn("worker/pipeline/volume/raw.cc:2", r.stderr)
        self.assertIn("(layer worker/pipeline/voxel), which it may not", r.stderr)
        self.assertIn("worker/pipeline/run/parameter_table.cc:1", r.stderr)
        self.assertIn("2 includes point where their layer may not", r.stderr)

    def test_modules_that_include_each_other_fail(self):
        # builder.cc needs parts.h, and parts.h needs builder.h: one cycle, named.
        r = self.tree({
            "worker/pipeline/voxel/builder.h": "",
            "worker/pipeline/voxel/builder.cc": '#include "worker/pipeline/voxel/builder.h"\n'
                                                '#include "worker/pipeline/voxel/parts.h"\n',
            "worker/pipeline/voxel/parts.h": '#include "worker/pipeline/voxel/builder.h"\n',
        })
        self.assertEqual(r.returncode, 1)
        self.assertIn("modules that include each other: worker/pipeline/voxel/builder <-> "
                      "worker/pipeline/voxel/parts", r.stderr)


if __name__ == "__main__":
    unittest.main()
