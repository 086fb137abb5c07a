#!/usr/bin/env python3
"""The .glb of `--what vtp,gltf` (issue 48) read by a glTF reader of its own (json, struct,
numpy; no wobble code) must give, at every frame, the vertices wobble draws itself. Every
vertex is evaluated the glTF way (the mesh's POSITION plus the morph targets weighted by the
animated weights, then the node's translation and rotation sampled from the animation at the
frame's time) and compared with the same run's shape .vtp of that frame (ShapeSource,
evaluated in double by wobble from the world's state: a 3D mesh, a 2D outline resampled, a
Witkin & Welch drawing) to 1e-5 of the body's size (the .glb holds float32). Runs: the demo's
3D pot (`export`), the 2D pot with its closed outline (`export`) and the 3D pot on its pose
graph (a script's `render` line). Linear bodies are checked by pipelines_gltf_test (a script's
scene `render` takes frames, filmstrip, vtp only).
Usage: check_gltf_export.py WOBBLE DATA_DIR WORK_DIR"""
import os
import re
import subprocess
import sys

import numpy as np

import gltf_files
from gltf_files import accessor, read_glb, read_vtp

wobble, data, work = (os.path.abspath(a) for a in sys.argv[1:4])
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


# ---------------------------------------------------------------- the runs
def node_vertices(doc, binary, node_index, t):
    """Every vertex of node `node_index`'s mesh at time t, evaluated as a glTF viewer does."""
    vertices, interpolations = gltf_files.node_vertices(doc, binary, node_index, t)
    check(interpolations == {"LINEAR"}, f"{doc['nodes'][node_index]['name']}: LINEAR samplers ({interpolations})")
    return vertices


def check_run(label, command, cwd, folder, stem, bodies, target_names, frames_expected):
    """Runs `command` (no X display), then checks folder/stem.glb against folder/vtp/stem.pvd's
    shape parts for every body in `bodies` (their node names)."""
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # the .glb (and the .vtp) need no X display
    subprocess.run(["rm", "-rf", folder], check=True)
    r = subprocess.run(command, capture_output=True, text=True, env=env, cwd=cwd)
    print(r.stdout, r.stderr)
    glb = os.path.join(folder, stem + ".glb")
    check(r.returncode == 0 and os.path.isfile(glb), f"{label}: {stem}.glb written without a display")
    if not os.path.isfile(glb):
        return
    check(f"{stem}.glb  (glTF 2.0" in r.stdout, f"{label}: the report lists the .glb with its note")
    check(not os.path.exists(glb + ".tmp"), f"{label}: no temporary file is left")
    doc, binary = read_glb(glb)
    check(doc["asset"]["version"] == "2.0", f"{label}: asset.version 2.0")
    names = [n["name"] for n in doc["nodes"]]
    check(all(b in names for b in bodies), f"{label}: a node per body {bodies} (nodes {names})")
    (animation,) = doc["animations"]
    pvd = open(os.path.join(folder, "vtp", stem + ".pvd")).read()
    for body in bodies:
        node_index = names.index(body)
        mesh = doc["meshes"][doc["nodes"][node_index]["mesh"]]
        check(mesh["extras"]["targetNames"] == target_names[body],
              f"{label}: {body}'s targetNames {mesh['extras']['targetNames'][:4]}... are {target_names[body][:4]}...")
        frames = [(float(t), f) for t, f in re.findall(rf'timestep="([^"]+)"[^>]*name="{body}_shape" file="([^"]+)"', pvd)]
        keys = accessor(doc, binary, animation["samplers"][0]["input"])[:, 0]
        check(len(frames) == frames_expected and len(keys) == len(frames), f"{label}: {len(frames)} frames, {len(keys)} keys")
        check(all(np.float32(t) == k for (t, _), k in zip(frames, keys)), f"{label}: the keys are the frames' times (float32)")
        worst, size, moved = 0.0, None, 0.0
        for t_frame, name in frames:
            reference = read_vtp(os.path.join(folder, "vtp", name))["Points"]
            t = float(np.float32(t_frame))
            vertices = node_vertices(doc, binary, node_index, t)
            if size is None:
                size = float(np.linalg.norm(reference.max(axis=0) - reference.min(axis=0)))
                check(vertices.shape == reference.shape, f"{label}: {body}: as many vertices as the .vtp's shape ({vertices.shape})")
                first = vertices
            worst = max(worst, float(np.abs(vertices - reference).max()))
            moved = max(moved, float(np.abs(vertices - first).max()))
        print(f"{label}: {body}: size {size:.6g}; worst vertex error {worst:.3g} = {worst / size:.3g} of the size; "
              f"largest motion {moved:.3g}")
        check(worst <= 1e-5 * size, f"{label}: {body}: every vertex at every frame matches wobble's drawing to 1e-5 of its size")
        check(moved > 0.05 * size, f"{label}: {body}: it moves (the animation is exercised)")


os.makedirs(work, exist_ok=True)
pot3 = os.path.join(work, "pot3_gltf")
# the demo's pot (Makefile DEMO3D_ARGS), 0.5 s: it falls, spins about its axis and squashes on landing
check_run("3D pot", [wobble, "export", "--object", os.path.join(data, "pot3.obj"), "--modes", os.path.join(data, "pot3_modes.def3"),
                     "--q", "0 30 0 0.3 0 0.15 0 0 0", "--qdot", "0 -60 0 0 1.2 0 0 0 0", "--dt", "0.001",
                     "--duration", "0.5", "--what", "vtp,gltf", "--out", pot3],
          work, pot3, "pot3", ["pot3"], {"pot3": ["squash", "sway", "twist"]}, 16)
# the 3D pot's modes move: the morph weights are not all 0
doc, binary = read_glb(os.path.join(pot3, "pot3.glb"))
weights = [accessor(doc, binary, s["output"]) for a in doc["animations"] for c, s in zip(a["channels"], a["samplers"])
           if c["target"]["path"] == "weights"]
check(len(weights) == 1 and np.abs(weights[0]).max() > 0.1, "3D pot: its modes move (largest |γ| > 0.1)")

pot2 = os.path.join(work, "pot2_gltf")
# the 2D pot with its closed outline (filled in the .glb), thrown turning onto the ground
check_run("2D pot", [wobble, "export", "--object", os.path.join(data, "pot.obj"), "--modes", os.path.join(data, "def_pot"),
                     "--q", "0 60 0.3 0.1 0 0", "--qdot", "20 -40 1 0 0 0", "--dt", "0.001", "--duration", "0.5",
                     "--what", "vtp,gltf", "--out", pot2],
          work, pot2, "pot", ["pot"], {"pot": ["vsquash", "hsquash", "bend"]}, 16)

doc, binary = read_glb(os.path.join(pot2, "pot.glb"))
names = [n["name"] for n in doc["nodes"]]
modes = [p.get("mode", 4) for p in doc["meshes"][doc["nodes"][names.index("pot")]["mesh"]]["primitives"]]
check(modes == [4, 1], f"2D pot: its closed outline filled (TRIANGLES) and its polylines (LINES): modes {modes}")
check("ground" in names and all(c["target"]["node"] != names.index("ground") for c in doc["animations"][0]["channels"]),
      "2D pot: the ground is a static node")

# a script's `render` line: the 3D pot squashing on its pose graph (data/pot3_squash.wob), 0.5 s
script = open(os.path.join(data, "pot3_squash.wob")).read()
script = script.replace("load_obj pot3.obj", "load_obj " + os.path.join(data, "pot3.obj"))
script = script.replace("load_def pot3_modes.def3", "load_def " + os.path.join(data, "pot3_modes.def3"))
script = re.sub(r"output .*\n", "", script).replace("simul 4", "simul 0.5")
script = re.sub(r"render .*\n", "render out/squash vtp,gltf\n", script)
open(os.path.join(work, "squash.wob"), "w").write(script)
check_run("script render", [wobble, "run", "squash.wob"], work, os.path.join(work, "out", "squash"), "pot3", ["pot3"],
          {"pot3": ["squash", "sway", "twist"]}, 16)

sys.exit(1 if failures else 0)
