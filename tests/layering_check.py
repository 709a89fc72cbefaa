#!/usr/bin/env python3
"""ctest tests/layering: no folder's production code includes a folder above
it (docs/design.md section 1). Tests (*_test.cpp) may include anything.

Prints each include that breaks the rule, as file -> folder, and exits 1."""

import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Each folder and the folders its production code may include.
MAY_INCLUDE = {
    "core": set(),
    "drivers": {"core"},
    "sim_hw": {"core", "drivers"},
    "calibration": {"core"},
    "reconstruction": {"core"},
    "simulation": {"core"},
    "rig": {"core", "drivers", "calibration", "reconstruction", "simulation"},
    "sim_rig": {"core", "drivers", "sim_hw", "calibration", "reconstruction", "simulation", "rig"},
    "batch": {"core", "drivers", "calibration", "reconstruction", "simulation", "rig"},
    "console": {"core", "drivers", "calibration", "reconstruction", "simulation", "rig"},
}
INCLUDE = re.compile(r'#include "([a-z_]+)/')


def main():
    broken = []
    for folder, allowed in MAY_INCLUDE.items():
        for here, _, files in os.walk(os.path.join(ROOT, folder)):
            for name in files:
                if not name.endswith((".h", ".cpp")) or name.endswith("_test.cpp"):
                    continue
                path = os.path.join(here, name)
                with open(path, encoding="utf-8") as f:
                    for target in INCLUDE.findall(f.read()):
                        if target != folder and target not in allowed:
                            broken.append("%s -> %s/" % (os.path.relpath(path, ROOT), target))
    for b in broken:
        print(b)
    print("%d includes break the folders' order" % len(broken))
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
