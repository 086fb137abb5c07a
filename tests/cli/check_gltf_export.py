#!/usr/bin/env python3
"""`wobble export --what vtp,gltf` of the 3D pot (issue 48): the .glb read by a glTF reader of
its own (json, struct, numpy; no wobble code) must give, at every frame, the vertices wobble
draws itself. Every vertex is evaluated the glTF way (the mesh's POSITION plus the morph
targets weighted by the animated weights, then the node's translation and rotation sampled
from the animation at the frame's time) and compared with the mesh part of the same run's
shape .vtp of that frame (ShapeSource, evaluated in double by wobble from the world's state)
to 1e-5 of the body's size (the .glb holds float32).
Usage: check_gltf_export.py WOBBLE DATA_DIR WORK_DIR"""
import json
import os
import re
import struct
import subprocess
import sys

import numpy as np

wobble, data, work = sys.argv[1:4]
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


# ---------------------------------------------------------------- a minimal GLB reader
COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
DTYPES = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}


def read_glb(path):
    """The JSON chunk and the BIN chunk of a .glb (glTF 2.0 spec, section 'Binary glTF Layout')."""
    raw = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<4sII", raw, 0)
    assert magic == b"glTF" and version == 2 and length == len(raw), (magic, version, length, len(raw))
    offset, doc, binary = 12, None, b""
    while offset < length:
        chunk_length, chunk_type = struct.unpack_from("<II", raw, offset)
        body = raw[offset + 8: offset + 8 + chunk_length]
        if chunk_type == 0x4E4F534A:  # "JSON"
            doc = json.loads(body.decode("utf-8"))
        elif chunk_type == 0x004E4942:  # "BIN\0"
            binary = body
        offset += 8 + chunk_length
    return doc, binary


def accessor(doc, binary, index):
    """Accessor `index` as a numpy array (count, components) (tightly packed views only)."""
    a = doc["accessors"][index]
    view = doc["bufferViews"][a["bufferView"]]
    assert view.get("byteStride") in (None, 0), "strided views are not read here"
    n = COMPONENTS[a["type"]]
    dtype = np.dtype(DTYPES[a["componentType"]]).newbyteorder("<")
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    values = np.frombuffer(binary, dtype=dtype, count=a["count"] * n, offset=start)
    return values.reshape(a["count"], n)


def sample(times, values, t, path):
    """An animation sampler's value at time t, LINEAR interpolation (slerp for rotations)."""
    k = int(np.searchsorted(times, t, side="right")) - 1
    if k < 0:
        return values[0]
    if k >= len(times) - 1:
        return values[-1]
    a = (t - times[k]) / (times[k + 1] - times[k])
    v0, v1 = values[k].astype(np.float64), values[k + 1].astype(np.float64)
    if path != "rotation":
        return (1 - a) * v0 + a * v1
    d = float(np.dot(v0, v1))
    if d < 0:
        v1, d = -v1, -d
    if d > 0.9995:
        q = (1 - a) * v0 + a * v1
    else:
        w = np.arccos(d)
        q = (np.sin((1 - a) * w) * v0 + np.sin(a * w) * v1) / np.sin(w)
    return q / np.linalg.norm(q)


def rotation_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


# ---------------------------------------------------------------- VTK XML (.vtp) with raw appended data
def read_vtp(path):
    """{array name: numpy array} of a .vtp written with raw appended data (exports.cc's VtpBytes);
    the Polys' connectivity is under 'Polys/connectivity'."""
    raw = open(path, "rb").read()
    start = raw.index(b"<AppendedData")
    head = raw[:start].decode("utf-8")
    data_start = raw.index(b"_", start) + 1
    header = re.search(r'header_type="(\w+)"', head).group(1)
    size_fmt, size_len = ("<Q", 8) if header == "UInt64" else ("<I", 4)
    assert 'compressor=' not in head, "compressed .vtp: not read here"
    types = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4"}
    arrays, section = {}, ""
    for line in head.splitlines():
        m = re.match(r"\s*<(Points|Polys|Lines|Verts|Strips|PointData|FieldData)>", line)
        if m:
            section = m.group(1)
        m = re.search(r'<DataArray type="(\w+)" Name="(\w+)"(?: NumberOfComponents="(\d+)")?.*offset="(\d+)"', line)
        if not m:
            continue
        kind, name, comps, offset = m.group(1), m.group(2), int(m.group(3) or 1), int(m.group(4))
        pos = data_start + offset
        nbytes = struct.unpack_from(size_fmt, raw, pos)[0]
        values = np.frombuffer(raw, dtype=types[kind], count=nbytes // np.dtype(types[kind]).itemsize, offset=pos + size_len)
        key = section + "/" + name if section in ("Polys", "Lines", "Verts", "Strips") else name
        arrays[key] = values.reshape(-1, comps) if comps > 1 else values
    return arrays


# ---------------------------------------------------------------- the run
out = os.path.join(work, "pot3_gltf")
subprocess.run(["rm", "-rf", out], check=True)
# the demo's pot (Makefile DEMO3D_ARGS), 0.5 s: it falls, spins about its axis and squashes on landing
args = [wobble, "export", "--object", os.path.join(data, "pot3.obj"), "--modes", os.path.join(data, "pot3_modes.def3"),
        "--q", "0 30 0 0.3 0 0.15 0 0 0", "--qdot", "0 -60 0 0 1.2 0 0 0 0", "--dt", "0.001", "--duration", "0.5",
        "--what", "vtp,gltf", "--out", out]
env = dict(os.environ)
env.pop("DISPLAY", None)  # the .glb (and the .vtp) need no X display
r = subprocess.run(args, capture_output=True, text=True, env=env)
print(r.stdout, r.stderr)
glb = os.path.join(out, "pot3.glb")
check(r.returncode == 0 and os.path.isfile(glb), "export --what vtp,gltf without a display writes pot3.glb")
check("pot3.glb  (glTF 2.0" in r.stdout, "the report lists the .glb with its note")
if failures:
    sys.exit(1)
check(not os.path.exists(glb + ".tmp"), "no temporary file is left")

doc, binary = read_glb(glb)
check(doc["asset"]["version"] == "2.0", "asset.version 2.0")
nodes, meshes = doc["nodes"], doc["meshes"]
check(len(nodes) == 1 and len(meshes) == 1 and nodes[0]["name"] == "pot3", "one node, one mesh: the pot")
node = nodes[0]
mesh = meshes[node["mesh"]]
prim = mesh["primitives"][0]
check(prim.get("mode", 4) == 4, "a TRIANGLES primitive")
check(mesh["extras"]["targetNames"] == ["squash", "sway", "twist"], "targetNames are the modes file's names")
check(len(prim["targets"]) == 3, "one morph target per mode")
base = accessor(doc, binary, prim["attributes"]["POSITION"]).astype(np.float64)
targets = [accessor(doc, binary, t["POSITION"]).astype(np.float64) for t in prim["targets"]]
triangles = accessor(doc, binary, prim["indices"]).reshape(-1, 3)

(animation,) = doc["animations"]
channels = {}
for ch in animation["channels"]:
    check(ch["target"]["node"] == 0, f"channel {ch['target']['path']} drives the pot's node")
    s = animation["samplers"][ch["sampler"]]
    check(s.get("interpolation", "LINEAR") == "LINEAR", f"{ch['target']['path']}: LINEAR")
    times = accessor(doc, binary, s["input"])[:, 0].astype(np.float64)
    values = accessor(doc, binary, s["output"])
    if ch["target"]["path"] == "weights":
        values = values.reshape(len(times), -1)
    channels[ch["target"]["path"]] = (times, values)
check(sorted(channels) == ["rotation", "translation", "weights"], "translation, rotation and weights animated")

# wobble's own frames: the .pvd's shape part, in time order
pvd = open(os.path.join(out, "vtp", "pot3.pvd")).read()
frames = [(float(t), f) for t, f in re.findall(r'timestep="([^"]+)"[^>]*name="pot3_shape" file="([^"]+)"', pvd)]
times = channels["translation"][0]
check(len(frames) == 16 and len(times) == len(frames), f"16 frames at 30 fps over 0.5 s in both ({len(times)} keys)")
check(all(np.float32(t) == np.float32(k) for (t, _), k in zip(frames, times)),
      "the keys are the frames' times (as float32)")

worst, size = 0.0, None
for t_frame, name in frames:
    shape = read_vtp(os.path.join(out, "vtp", name))
    reference = shape["Points"][: len(base)]  # the mesh comes first, then the drawing's polylines
    if size is None:
        size = float(np.linalg.norm(reference.max(axis=0) - reference.min(axis=0)))
        check(np.array_equal(shape["Polys/connectivity"].reshape(-1, 3), triangles.astype(np.int64)),
              "the triangles are the .vtp's")
    t = float(np.float32(t_frame))
    weights = sample(channels["weights"][0], channels["weights"][1], t, "weights")
    local = base + sum(w * target for w, target in zip(weights, targets))
    R = rotation_matrix(sample(*channels["rotation"], t, "rotation"))
    world = local @ R.T + sample(*channels["translation"], t, "translation")
    worst = max(worst, float(np.abs(world - reference).max()))
print(f"body size (diagonal of the first frame's box) {size:.6g}; worst vertex error {worst:.3g} "
      f"= {worst / size:.3g} of the size")
check(worst <= 1e-5 * size, "every vertex at every frame matches wobble's drawing to 1e-5 of the body's size")
moved = np.abs(channels["weights"][1]).max()
check(moved > 1e-3, f"the modes move (largest |γ| {moved:.3g}): the morph targets are exercised")

sys.exit(1 if failures else 0)
