"""Runs inside Blender (bpy): imports a .glb with Blender's own glTF importer and writes what
Blender makes of it, for check_gltf_blender.py to compare with wobble's drawing.
Usage: blender -b --factory-startup --python-exit-code 1 --python blender_read_gltf.py -- GLB OUT_JSON T1,T2,... SHADING
SHADING: the importer's import_shading (NORMALS, its default, FLAT or SMOOTH).
OUT_JSON holds: the importer's console output and its return value; the scene's fps; per
imported mesh object: its shape keys (names, slider ranges as imported), its actions' frame
ranges, its Basis coordinates, and at every time T (seconds, mapped to a frame as the importer
keys it: frame = T * scene.render.fps, no offset) the evaluated mesh's vertices in world
coordinates (Blender's Z-up axes, as the importer converted them), the shape keys' animated
values and their F-curves' values. Every time is evaluated twice: "as_imported" and
"widened" (every shape key's slider range opened to its F-curve's values, see below)."""
import ctypes
import json
import math
import os
import sys
import tempfile

import bpy
import numpy as np

glb, out_json, times_arg, shading = sys.argv[sys.argv.index("--") + 1:][:4]
times = [float(t) for t in times_arg.split(",")]
libc = ctypes.CDLL(None)


def import_capturing_console(path, shading):
    """bpy.ops.import_scene.gltf with the process's stdout and stderr (C and Python: the
    operator's reports and the importer's log both go there) captured into a string."""
    bpy.app.debug_value = 3  # the importer's log level follows it: 3 = INFO (its warnings and errors shown)
    with tempfile.TemporaryFile() as log:
        sys.stdout.flush(), sys.stderr.flush(), libc.fflush(None)
        saved = os.dup(1), os.dup(2)
        os.dup2(log.fileno(), 1), os.dup2(log.fileno(), 2)
        try:
            result = bpy.ops.import_scene.gltf(filepath=path, import_shading=shading)
        finally:
            sys.stdout.flush(), sys.stderr.flush(), libc.fflush(None)
            os.dup2(saved[0], 1), os.dup2(saved[1], 2)
            os.close(saved[0]), os.close(saved[1])
        bpy.app.debug_value = 0
        log.seek(0)
        return sorted(result), log.read().decode("utf-8", "replace")


for ob in list(bpy.data.objects):  # factory startup's cube, camera and light: only the file's objects stay
    bpy.data.objects.remove(ob)
try:
    result, console = import_capturing_console(glb, shading)
except RuntimeError as error:  # the importer raised: its traceback is the operator's error
    with open(out_json, "w") as f:
        json.dump({"import_result": ["FAILED"], "import_console": str(error)}, f)
    sys.exit(0)
scene = bpy.context.scene
fps = scene.render.fps / scene.render.fps_base
report = {"import_result": result, "import_console": console, "fps": fps, "objects": {}}
meshes = [ob for ob in scene.objects if ob.type == "MESH"]


def shape_key_curves(ob):
    """{shape key name: its F-curve} of the mesh's shape-key action."""
    keys = ob.data.shape_keys
    if keys is None or keys.animation_data is None or keys.animation_data.action is None:
        return {}
    curves = {}
    for fc in keys.animation_data.action.fcurves:
        name = fc.data_path[len('key_blocks["'):-len('"].value')]
        curves[name] = fc
    return curves


for ob in meshes:
    keys = ob.data.shape_keys
    entry = {"vertices": len(ob.data.vertices), "shape_keys": [], "slider_min": [], "slider_max": []}
    basis = np.empty(3 * len(ob.data.vertices), dtype=np.float32)
    ob.data.vertices.foreach_get("co", basis)  # the mesh's own coordinates: the Basis shape
    entry["basis"] = basis.reshape(-1, 3).tolist()
    if keys is not None:
        blocks = keys.key_blocks[1:]  # [0] is "Basis"
        entry["shape_keys"] = [kb.name for kb in blocks]
        entry["slider_min"] = [kb.slider_min for kb in blocks]
        entry["slider_max"] = [kb.slider_max for kb in blocks]
        entry["relative_key"] = [kb.relative_key.name for kb in blocks]
    if ob.animation_data and ob.animation_data.action:
        entry["object_action_frame_range"] = list(ob.animation_data.action.frame_range)
    if keys is not None and keys.animation_data and keys.animation_data.action:
        entry["shape_key_action_frame_range"] = list(keys.animation_data.action.frame_range)
    entry["frames"] = {"as_imported": [], "widened": []}
    report["objects"][ob.name] = entry


def evaluate_all(label):
    for t in times:
        frame = t * fps
        whole = math.floor(frame)
        scene.frame_set(whole, subframe=frame - whole)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for ob in meshes:
            evaluated = ob.evaluated_get(depsgraph)
            mesh = evaluated.to_mesh()
            co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
            mesh.vertices.foreach_get("co", co)
            world = np.array(evaluated.matrix_world, dtype=np.float64)
            local = co.reshape(-1, 3).astype(np.float64)
            vertices = local @ world[:3, :3].T + world[:3, 3]
            evaluated.to_mesh_clear()
            curves = shape_key_curves(ob)
            keys = ob.data.shape_keys
            frame_entry = {"t": t, "frame": frame, "scene_frame": scene.frame_current_final,
                           "vertices": vertices.tolist()}
            if keys is not None:
                evaluated_keys = evaluated.data.shape_keys if evaluated.data.shape_keys is not None else keys
                frame_entry["key_values"] = [kb.value for kb in keys.key_blocks[1:]]
                frame_entry["evaluated_key_values"] = [kb.value for kb in evaluated_keys.key_blocks[1:]]
                frame_entry["curve_values"] = [curves[kb.name].evaluate(frame) if kb.name in curves else None
                                               for kb in keys.key_blocks[1:]]
            report["objects"][ob.name]["frames"][label].append(frame_entry)


evaluate_all("as_imported")
# A shape key's value is clamped to [slider_min, slider_max] when it is set, the animation's
# included; open every range to its F-curve's keyed values (the user's fix after an import)
for ob in meshes:
    for name, fc in shape_key_curves(ob).items():
        values = [k.co[1] for k in fc.keyframe_points]
        kb = ob.data.shape_keys.key_blocks[name]
        kb.slider_min = min(kb.slider_min, min(values))
        kb.slider_max = max(kb.slider_max, max(values))
    if ob.data.shape_keys is not None:
        report["objects"][ob.name]["widened_slider_min"] = [kb.slider_min for kb in ob.data.shape_keys.key_blocks[1:]]
evaluate_all("widened")

with open(out_json, "w") as f:
    json.dump(report, f)
print("blender_read_gltf: %d mesh objects, %d times, written to %s" % (len(meshes), len(times), out_json))
