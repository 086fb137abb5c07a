#!/usr/bin/env python3
"""The .glb of `--what vtp,gltf` (issue 48, item 3) read by Blender 3.4's own glTF importer:
Blender runs headless with blender_read_gltf.py, which imports the file
(bpy.ops.import_scene.gltf) and writes, at every frame of the run, the evaluated mesh of every
object (shape keys and object animation applied, world matrix applied). Here those vertices are
compared with wobble's own drawing at the same times (the same run's shape .vtp, as
check_gltf_export.py reads it) to 1e-5 of the body's size (the .glb holds float32); at
Blender's whole frames, mostly between the file's keys, with the glTF evaluation (slerp) of
gltf_files.py to the same tolerance.
  Time: the importer keys glTF second t at frame t * scene.render.fps (24 under
    --factory-startup; no offset, frame 0 is t = 0): the script sets that frame and subframe.
  Axes: the importer turns glTF's +Y up into Blender's +Z up, (x, y, z) -> (x, -z, y), on the
    vertices, shape keys and node animation; it is undone here, (x, y, z) <- (x, z, -y).
  Vertices: per primitive the importer keeps the indexed vertices (np.unique of its indices,
    sorted) and appends them: a vertex shared by the TRIANGLES and the LINES appears twice. The
    same map is built here from the file and checked on the Basis shape.
  Negative morph weights: Blender clamps a shape key's value to [slider_min, slider_max] when
    it is set, the animation's writes included, and Blender 3.4's importer widens the default
    [0, 1] only by the FIRST key's weight (io_scene_gltf2 3.4.50,
    gltf2_blender_animation_weight.py: min(coords[1:2])), so a mode amplitude going below 0
    after the first frame is drawn at 0 (KhronosGroup/glTF-Blender-IO issue 1364, open). The
    runs below have negative amplitudes: as imported, Blender must show the glTF evaluation
    with the weights clamped to its slider ranges (the limitation, measured and printed), and
    once every slider range is opened to its F-curve's values (the fix after an import,
    README) it must show wobble's drawing.
  Import: with import_shading FLAT. Debian 12's Blender 3.4.1 with its numpy 1.24 fails on
    any mesh with the default NORMALS (np.bool, removed in numpy 1.24; fixed in the importer
    of Blender 3.5, glTF-Blender-IO pull request 1831, not backported to 3.4); that default
    is tried too and its outcome printed. The import's console (its log at INFO) must show no
    warning or error.
Exit 77 (skipped) when blender is not on PATH.
Usage: check_gltf_blender.py WOBBLE DATA_DIR WORK_DIR"""
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np

from gltf_files import accessor, node_vertices, read_glb, read_vtp

blender = shutil.which("blender")
if blender is None:
    print("skipped: blender is not installed")
    sys.exit(77)

wobble, data, work = (os.path.abspath(a) for a in sys.argv[1:4])
blender_script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender_read_gltf.py")
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def gltf_axes(blender_xyz):
    """Blender's Z-up coordinates back to glTF's Y-up ones (the importer's conversion undone)."""
    v = np.asarray(blender_xyz, dtype=np.float64)
    return np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)


def importer_vertex_map(doc, binary, mesh_index):
    """The glTF vertex of every vertex Blender's importer makes of mesh `mesh_index`: per
    primitive the indexed vertices, sorted, appended (gltf2_blender_mesh.py, do_primitives)."""
    return np.concatenate([np.unique(accessor(doc, binary, p["indices"])[:, 0])
                           for p in doc["meshes"][mesh_index]["primitives"]])


def run_blender(glb, times, shading, out_json):
    r = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", blender_script,
                        "--", glb, out_json, ",".join(repr(t) for t in times), shading],
                       capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout, r.stderr)
    return r.returncode, (json.load(open(out_json)) if r.returncode == 0 and os.path.isfile(out_json) else None)


def check_run(label, command, folder, stem, body, mode_names):
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # the .glb (and the .vtp) need no X display
    subprocess.run(["rm", "-rf", folder], check=True)
    r = subprocess.run(command, capture_output=True, text=True, env=env)
    print(r.stdout, r.stderr)
    glb = os.path.join(folder, stem + ".glb")
    check(r.returncode == 0 and os.path.isfile(glb), f"{label}: {stem}.glb written")
    if not os.path.isfile(glb):
        return
    doc, binary = read_glb(glb)
    names = [n["name"] for n in doc["nodes"]]
    node_index = names.index(body)
    mesh_index = doc["nodes"][node_index]["mesh"]
    pvd = open(os.path.join(folder, "vtp", stem + ".pvd")).read()
    frames = [(float(np.float32(t)), f) for t, f in re.findall(rf'timestep="([^"]+)"[^>]*name="{body}_shape" file="([^"]+)"', pvd)]
    times = [t for t, _ in frames]
    (animation,) = doc["animations"]
    weight_sampler = next(animation["samplers"][c["sampler"]] for c in animation["channels"]
                          if c["target"]["node"] == node_index and c["target"]["path"] == "weights")
    keyed_weights = accessor(doc, binary, weight_sampler["output"]).reshape(len(times), -1).astype(np.float64)
    check(keyed_weights.min() < -0.05, f"{label}: some mode amplitudes are negative at the checked frames "
          f"(lowest {keyed_weights.min():.3g}, at t = {times[int(np.argmin(keyed_weights.min(axis=1)))]:.3g} s)")

    # Blender's default import (shading from the normals): reported, not required (see above)
    rc, default = run_blender(glb, times[:1], "NORMALS", os.path.join(folder, "blender_default.json"))
    outcome = "" if default is None else " ".join(default["import_result"])
    cause = re.findall(r"\w*Error: .*", default["import_console"]) if default else []
    print(f"{label}: Blender's default import (import_shading NORMALS): {outcome or 'blender exited ' + str(rc)} {cause[-1:]}")

    # Blender's own frames too (frame f at second f / 24), mostly between the file's keys
    between = [f / 24.0 for f in range(int(np.ceil(times[0] * 24)), int(np.floor(times[-1] * 24)) + 1)]
    rc, report = run_blender(glb, times + between, "FLAT", os.path.join(folder, "blender.json"))
    check(report is not None and report["import_result"] == ["FINISHED"], f"{label}: Blender imports {stem}.glb (import_shading FLAT)")
    if report is None or report["import_result"] != ["FINISHED"]:
        print(report and report["import_console"])
        return
    console = report["import_console"]
    print(f"{label}: the importer's console:\n  " + "\n  ".join(console.splitlines()))
    troubles = [line for line in console.splitlines() if re.search(r"WARNING|ERROR|CRITICAL|Traceback|Error", line)]
    check(not troubles, f"{label}: the import reports no warning or error {troubles}")
    fps = report["fps"]
    check(fps == 24.0, f"{label}: the scene's fps is factory startup's 24 ({fps}), seconds are keyed at t * fps")
    check(body in report["objects"] and "ground" in report["objects"], f"{label}: objects {body} and ground ({list(report['objects'])})")
    if body not in report["objects"]:
        return
    blender_body = report["objects"][body]

    # shape keys: one per mode, named as the modes, relative to the Basis
    check(blender_body["shape_keys"] == mode_names == doc["meshes"][mesh_index]["extras"]["targetNames"],
          f"{label}: the shape keys {blender_body['shape_keys']} are the modes {mode_names}")
    check(len(blender_body["shape_keys"]) == len(mode_names), f"{label}: {len(mode_names)} shape keys, one per mode")
    check(set(blender_body["relative_key"]) == {"Basis"}, f"{label}: every shape key is relative to the Basis")
    # the actions cover the run: frames t0 * fps .. tN * fps
    first, last = times[0] * fps, times[-1] * fps
    for action in ("object_action_frame_range", "shape_key_action_frame_range"):
        lo, hi = blender_body.get(action, (None, None))
        check(lo is not None and abs(lo - first) < 1e-4 and abs(hi - last) < 1e-4,
              f"{label}: the {action.replace('_frame_range', '')} spans frames {lo}..{hi} = the run's {first:g}..{last:g}")

    # the vertex map, checked on the Basis shape (exact: the axis swap is exact in float32)
    vertex_map = importer_vertex_map(doc, binary, mesh_index)
    prim = doc["meshes"][mesh_index]["primitives"][0]
    rest = accessor(doc, binary, prim["attributes"]["POSITION"]).astype(np.float64)
    check(blender_body["vertices"] == len(vertex_map), f"{label}: Blender's {blender_body['vertices']} vertices are the "
          f"primitives' indexed ones ({len(vertex_map)} of {len(rest)})")
    if blender_body["vertices"] != len(vertex_map):
        return
    check(np.array_equal(gltf_axes(blender_body["basis"]), rest[vertex_map]), f"{label}: the Basis is the file's POSITION, axes undone")

    slider_range = list(zip(blender_body["slider_min"], blender_body["slider_max"]))
    clamped_somewhere = bool(((keyed_weights < [lo for lo, _ in slider_range]) | (keyed_weights > [hi for _, hi in slider_range])).any())
    print(f"{label}: slider ranges as imported {slider_range}; keyed weights {keyed_weights.min(axis=0).round(4).tolist()} .. "
          f"{keyed_weights.max(axis=0).round(4).tolist()}; widened slider_min {blender_body['widened_slider_min']}")
    size = None
    worst = {"as_imported": 0.0, "widened": 0.0}
    worst_clamped_model, worst_weight = 0.0, 0.0
    print(f"{label}: per frame: t, Blender frame, max |Blender - wobble| (widened), (as imported), lowest weight")
    for k, (t, vtp) in enumerate(frames):
        reference = read_vtp(os.path.join(folder, "vtp", vtp))["Points"].astype(np.float64)
        if size is None:
            size = float(np.linalg.norm(reference.max(axis=0) - reference.min(axis=0)))
        reference = reference[vertex_map]
        errors = {}
        for label_pass in ("as_imported", "widened"):
            seen = blender_body["frames"][label_pass][k]
            assert seen["t"] == t
            vertices = gltf_axes(seen["vertices"])
            errors[label_pass] = float(np.abs(vertices - reference).max())
            worst[label_pass] = max(worst[label_pass], errors[label_pass])
            if label_pass == "widened":
                worst_weight = max(worst_weight, float(np.abs(np.array(seen["key_values"]) - keyed_weights[k]).max()))
            else:
                # as imported: what a glTF viewer shows with the weights clamped to the slider ranges
                clamped, _ = node_vertices(doc, binary, node_index, t, weight_range=slider_range)
                worst_clamped_model = max(worst_clamped_model, float(np.abs(vertices - clamped[vertex_map]).max()))
        print(f"  {t:.4f}  {t * fps:7.3f}  {errors['widened']:.3g}  {errors['as_imported']:.3g}  {keyed_weights[k].min():.3g}")
    print(f"{label}: {body}: size {size:.6g}; worst vertex error, slider ranges widened: {worst['widened']:.3g} = "
          f"{worst['widened'] / size:.3g} of the size; as imported: {worst['as_imported']:.3g} = {worst['as_imported'] / size:.3g}")
    # between the keys: Blender interpolates each quaternion component linearly and normalizes
    # (glTF: slerp); every other channel is linear in both
    worst_between = 0.0
    for k, t in enumerate(between):
        seen = blender_body["frames"]["widened"][len(frames) + k]
        assert seen["t"] == t
        gltf_view, _ = node_vertices(doc, binary, node_index, t)
        worst_between = max(worst_between, float(np.abs(gltf_axes(seen["vertices"]) - gltf_view[vertex_map]).max()))
    print(f"{label}: {body}: at Blender's {len(between)} whole frames (widened), worst distance to the glTF evaluation "
          f"(slerp) {worst_between:.3g} = {worst_between / size:.3g} of the size")
    check(worst_between <= 1e-5 * size, f"{label}: {body}: between the keys too, Blender shows the glTF animation to 1e-5 of the size")
    check(worst_weight <= 1e-6, f"{label}: widened, the shape keys' values at every frame are the file's weights (to {worst_weight:.3g})")
    check(worst["widened"] <= 1e-5 * size,
          f"{label}: {body}: with the slider ranges widened, every vertex at every frame is wobble's to 1e-5 of its size")
    check(worst_clamped_model <= 1e-5 * size,
          f"{label}: {body}: as imported, Blender shows the weights clamped to its slider ranges (to {worst_clamped_model:.3g})")
    if clamped_somewhere:
        print(f"{label}: BLENDER LIMITATION: as imported, the negative mode amplitudes are clamped to the slider ranges "
              f"{slider_range}: off wobble's drawing by up to {worst['as_imported']:.3g} ({worst['as_imported'] / size:.3g} of the size)")
        check(worst["as_imported"] > 1e-5 * size, f"{label}: {body}: the clamping shows (the run exercises it)")
    else:
        check(worst["as_imported"] <= 1e-5 * size, f"{label}: {body}: as imported, every vertex is wobble's to 1e-5 of its size")


os.makedirs(work, exist_ok=True)
# the demo's 3D pot (Makefile DEMO3D_ARGS), 1 s: it falls, spins about its axis and squashes on
# landing (squash down to -0.84)
check_run("3D pot", [wobble, "export", "--object", os.path.join(data, "pot3.obj"), "--modes", os.path.join(data, "pot3_modes.def3"),
                     "--q", "0 30 0 0.3 0 0.15 0 0 0", "--qdot", "0 -60 0 0 1.2 0 0 0 0", "--dt", "0.001",
                     "--duration", "1", "--what", "vtp,gltf", "--out", os.path.join(work, "pot3_blender")],
          os.path.join(work, "pot3_blender"), "pot3", "pot3", ["squash", "sway", "twist"])
# the 2D table (its outline as LINES, no fill), thrown turning at the ground: its modes move
check_run("2D table", [wobble, "export", "--object", os.path.join(data, "table.obj"), "--modes", os.path.join(data, "table_modes.def"),
                       "--q", "0 20 0.2 0 0 0 0", "--qdot", "5 -40 1 0 0 0 0", "--integrator", "thesis", "--dt", "0.01",
                       "--duration", "1", "--what", "vtp,gltf", "--out", os.path.join(work, "table_blender")],
          os.path.join(work, "table_blender"), "table", "table", ["bend", "shear", "vsquash", "hsquash"])
# the 2D pot, its closed outline filled (TRIANGLES) and drawn (LINES): the outline's vertices
# are in both primitives, Blender has them twice
check_run("2D pot", [wobble, "export", "--object", os.path.join(data, "pot.obj"), "--modes", os.path.join(data, "def_pot"),
                     "--q", "0 60 0.3 0.1 0 0", "--qdot", "20 -40 1 0 0 0", "--dt", "0.001", "--duration", "1",
                     "--what", "vtp,gltf", "--out", os.path.join(work, "pot2_blender")],
          os.path.join(work, "pot2_blender"), "pot", "pot", ["vsquash", "hsquash", "bend"])

sys.exit(1 if failures else 0)
