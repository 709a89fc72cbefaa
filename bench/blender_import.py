"""Run inside Blender (bench/blender_import_bench.sh): imports a hairrig .glb
with Blender's own glTF importer, converts the node "strands" (a mesh of
edges) to curves as an artist would, and prints one JSON line: the splines
(one per strand), their points, the strands' size in metres (Blender is +z
up: the importer turns glTF's +y up into +z), whether the head came in, and
the animation's frame range.

  blender -b --factory-startup -P bench/blender_import.py -- FILE.glb
"""
import json
import sys
import time

import bpy
import numpy

# Debian 12's Blender 3.4 glTF importer still uses numpy.bool, an alias
# NumPy 1.24 (Debian 12's) removed: without it every mesh import fails with
# "module 'numpy' has no attribute 'bool'". The alias meant the builtin bool.
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def main():
    path = sys.argv[sys.argv.index("--") + 1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.monotonic()
    bpy.ops.import_scene.gltf(filepath=path)
    imported_s = time.monotonic() - started
    strands = bpy.data.objects.get("strands")
    if strands is None:
        raise SystemExit("blender_import: %s has no object named 'strands'" % path)
    size = list(strands.dimensions)
    lowest = min((strands.matrix_world @ v.co).z for v in strands.data.vertices)
    highest = max((strands.matrix_world @ v.co).z for v in strands.data.vertices)
    bpy.ops.object.select_all(action="DESELECT")
    bpy.context.view_layer.objects.active = strands
    strands.select_set(True)
    started = time.monotonic()
    bpy.ops.object.convert(target="CURVE")
    converted_s = time.monotonic() - started
    curve = strands.data
    actions = [a for a in bpy.data.actions]
    frame_range = [list(a.frame_range) for a in actions]
    print(json.dumps({
        "file": path,
        "splines": len(curve.splines),
        "spline_points": sum(len(s.points) for s in curve.splines),
        "size_m": size,
        "z_m": [lowest, highest],
        "head": bpy.data.objects.get("head") is not None,
        "actions": len(actions),
        "frame_range": frame_range,
        "import_s": imported_s,
        "convert_s": converted_s,
    }))


main()
