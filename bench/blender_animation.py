"""Run inside Blender (bench/gltf_animation_bench.sh): imports a hairrig .glb
whose simulation is either encoding (`hairrig export --animation-encoding
nodes|morph`) with Blender's own glTF importer, then steps through the
animation as playback does and prints one JSON line: the import time, the
actions and shape keys made, the scene evaluation time per frame (what
playback costs Blender), and how far the animated strands' vertices are from
frame 0 at the last frame (0 would mean the animation does not play).

  blender -b --factory-startup -P bench/blender_animation.py -- FILE.glb NAME

NAME is the animated node (the simulation folder's name, e.g. head-shake).
"""
import json
import sys
import time

import bpy
import numpy

# Debian 12's Blender 3.4 importer uses numpy.bool, which NumPy 1.24 removed
# (see bench/blender_import.py).
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def shown_vertices(root, depsgraph):
    """World positions of the animated strands as evaluated: the object itself
    (morph targets: its shape keys applied) or its child not scaled to 0
    (frame nodes)."""
    candidates = [root] + list(root.children)
    for obj in candidates:
        if obj.type != "MESH":
            continue
        if obj is not root and min(obj.matrix_world.to_scale()) <= 0:
            continue
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        coords = numpy.empty(3 * len(mesh.vertices))
        mesh.vertices.foreach_get("co", coords)
        evaluated.to_mesh_clear()
        points = coords.reshape(-1, 3)
        matrix = numpy.array(obj.matrix_world)
        return points @ matrix[:3, :3].T + matrix[:3, 3]
    return None


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    path, name = args[0], args[1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.monotonic()
    bpy.ops.import_scene.gltf(filepath=path)
    import_s = time.monotonic() - started
    root = bpy.data.objects.get(name)
    if root is None:
        raise SystemExit("blender_animation: %s has no object named %r" % (path, name))
    scene = bpy.context.scene
    end = max((a.frame_range[1] for a in bpy.data.actions), default=scene.frame_start)
    frames = list(range(int(scene.frame_start), int(end) + 1))
    depsgraph = bpy.context.evaluated_depsgraph_get()
    scene.frame_set(frames[0])
    first = shown_vertices(root, depsgraph)
    started = time.monotonic()
    for f in frames:
        scene.frame_set(f)
    per_frame_s = (time.monotonic() - started) / len(frames)
    scene.frame_set(frames[-1])
    last = shown_vertices(root, depsgraph)
    moved = None
    if first is not None and last is not None and first.shape == last.shape:
        moved = float(numpy.linalg.norm(last - first, axis=1).max())
    shape_keys = sum(len(m.shape_keys.key_blocks) - 1 for m in bpy.data.meshes
                     if m.shape_keys is not None)
    print(json.dumps({
        "file": path,
        "import_s": import_s,
        "objects": len(bpy.data.objects),
        "actions": len(bpy.data.actions),
        "shape_keys": shape_keys,
        "frames": len(frames),
        "frame_s": per_frame_s,
        "vertices_shown": 0 if first is None else int(first.shape[0]),
        "largest_move_m": moved,
    }))


main()
