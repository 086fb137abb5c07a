"""A glTF 2.0 binary (.glb) and VTK XML (.vtp) reader of the tests' own (json, struct, numpy; no
wobble code), shared by check_gltf_export.py and check_gltf_blender.py."""
import json
import re
import struct

import numpy as np


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


# ---------------------------------------------------------------- a glTF viewer
def node_vertices(doc, binary, node_index, t, weight_range=None):
    """Every vertex of node `node_index`'s mesh at time t, evaluated as a glTF viewer does, and
    the interpolations of the node's samplers (a set). weight_range (lo, hi) per target: the
    morph weights clamped to it (what a viewer clamping them would show)."""
    interpolations = set()
    node = doc["nodes"][node_index]
    prim = doc["meshes"][node["mesh"]]["primitives"][0]
    base = accessor(doc, binary, prim["attributes"]["POSITION"]).astype(np.float64)
    targets = [accessor(doc, binary, tg["POSITION"]).astype(np.float64) for tg in prim.get("targets", [])]
    translation = np.array(node.get("translation", [0, 0, 0]), dtype=np.float64)
    rotation = np.array(node.get("rotation", [0, 0, 0, 1]), dtype=np.float64)
    weights = np.array(node.get("weights", [0] * len(targets)), dtype=np.float64)
    for animation in doc.get("animations", []):
        for ch in animation["channels"]:
            if ch["target"]["node"] != node_index:
                continue
            s = animation["samplers"][ch["sampler"]]
            interpolations.add(s.get("interpolation", "LINEAR"))
            times = accessor(doc, binary, s["input"])[:, 0].astype(np.float64)
            values = accessor(doc, binary, s["output"])
            path = ch["target"]["path"]
            if path == "weights":
                values = values.reshape(len(times), -1)
            value = sample(times, values, t, path)
            if path == "translation":
                translation = value
            elif path == "rotation":
                rotation = value
            else:
                weights = value
    if weight_range is not None:
        weights = np.clip(weights, [lo for lo, _ in weight_range], [hi for _, hi in weight_range])
    local = base + sum(w * target for w, target in zip(weights, targets))
    return local @ rotation_matrix(rotation).T + translation, interpolations
