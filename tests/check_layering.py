#!/usr/bin/env python3
"""The layering of wobble, checked on every `make test` (docs/ARCHITECTURE.md, "Layout").

Fails (exit 1, one line per problem, FILE:LINE: what) when
  - a lib/wobble folder includes a folder it may not (LAYERS below, the documented order);
  - lib/ includes VTK or OpenEXR, or pipelines/ includes the script interpreter;
  - a header under an `internal/` folder is included from outside its own folder tree, or by a
    public header (one not under `internal/`: it is installed, the internal ones are not);
  - a public (installed) header of lib/ or pipelines/ includes Ceres;
  - a lib/wobble/<folder> file declares a namespace other than the folder's (NAMESPACES);
  - a source file in lib/, pipelines/ or app/ is longer than MAX_LINES;
  - a function a lib/wobble/<folder> header declares is defined only outside that folder (so
    the layer would not link on its own; see misplaced_definitions).
Usage: check_layering.py [PROJECT_ROOT]
"""
import os
import re
import sys

# Each folder of lib/wobble and the folders it may include, bottom up. A folder may include
# only folders listed before it (checked below too, so the table itself cannot grow a cycle).
LAYERS = [
    ("core", []),
    ("mpi", ["core"]),
    ("body", ["core"]),
    ("dynamics", ["core", "body"]),
    ("formats", ["core", "body", "dynamics"]),  # dynamics: the heightfield a file makes
    ("world", ["core", "body", "dynamics"]),
    ("control", ["core", "body", "dynamics", "world"]),
    ("record", ["core", "body", "formats", "dynamics", "world", "control"]),
    ("scene", ["core", "body", "dynamics", "world", "control", "record", "formats"]),
    ("analysis", ["core", "body", "dynamics", "world"]),
    ("synth", ["core", "body", "dynamics", "world", "control", "record", "scene"]),
    ("fit", ["core", "body", "dynamics", "world", "control", "record", "synth"]),
    ("script", ["core", "body", "dynamics", "world", "control", "record", "formats", "scene",
                "analysis", "synth"]),
]
# The ground floor shares the namespace `wobble` (every layer uses its types, as b2World's);
# every folder above it has its own namespace.
GROUND_FLOOR = {"core", "body", "dynamics", "world"}
MAX_LINES = 800

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')
NAMESPACE = re.compile(r"^namespace\s+([\w:]+)\s*\{")


def source_files(root, top):
    for dirpath, _, names in os.walk(os.path.join(root, top)):
        for name in sorted(names):
            if name.endswith((".h", ".cc")):
                yield os.path.join(dirpath, name)


# A free function at namespace scope: a statement at column 0 (members are indented, templates
# start with `template`) naming the function just before its '('.
FUNCTION = re.compile(r"^(?!(?:return|using|typedef|friend|static_assert|template|extern)\b)"
                      r"[A-Za-z_][\w:<>,\s*&]*?[\s*&]([A-Za-z_]\w*)\(")


def column0_statements(text):
    """(line, statement) for each statement starting at column 0, comments removed, continued
    over the lines below up to its first ';' or '{'."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    lines = [re.sub(r"//.*", "", line) for line in text.split("\n")]
    i = 0
    while i < len(lines):
        if lines[i][:1].strip() and not lines[i].startswith(("#", "}")):
            statement, j = lines[i], i
            while not re.search(r"[;{]", statement) and j + 1 < len(lines):
                j += 1
                statement += " " + lines[j].strip()
            yield i + 1, statement
            i = j + 1
        else:
            i += 1


def function_kind(statement, match):
    """'declaration' or 'definition', by what follows the parameter list's closing ')'."""
    depth = 0
    for k in range(match.end() - 1, len(statement)):
        depth += {"(": 1, ")": -1}.get(statement[k], 0)
        if depth == 0:
            rest = re.search(r"[;{]", statement[k:])
            return None if not rest else ("declaration" if rest.group(0) == ";" else "definition")
    return None


def layered_sources(root):
    """(rel, top, folder, text) of every source file under lib/, pipelines/ and app/; folder is
    the lib/wobble/<folder> a library file sits in, None elsewhere."""
    for top in ("lib", "pipelines", "app"):
        for path in source_files(root, top):
            rel = os.path.relpath(path, root)
            parts = rel.split(os.sep)
            with open(path, encoding="utf-8") as f:
                yield rel, top, parts[2] if top == "lib" and len(parts) > 3 else None, f.read()


def misplaced_definitions(root):
    """Functions declared in a lib/wobble/<folder> header and defined outside that folder but
    not inside it. By name: an overload defined in the right folder hides one defined elsewhere,
    which is enough to keep a layer's declarations and definitions together."""
    declared, defined = [], {}
    for rel, top, folder, text in layered_sources(root):
        place = folder or top
        for number, statement in column0_statements(text):
            m = FUNCTION.match(statement)
            kind = function_kind(statement, m) if m else None
            if kind == "definition":
                defined.setdefault(m.group(1), set()).add(place)
            elif kind == "declaration" and top == "lib" and rel.endswith(".h"):
                declared.append((m.group(1), place, f"{rel}:{number}"))
    problems = []
    for name, place, where in declared:
        elsewhere = defined.get(name, set())
        if elsewhere and place not in elsewhere:
            problems.append(f"{where}: {name} is declared in lib/wobble/{place} but defined in "
                            f"{', '.join(sorted(elsewhere))}; define it in {place} (a .cc of its own folder)")
    return problems


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    problems = []
    order = [name for name, _ in LAYERS]
    allowed = dict(LAYERS)
    for name, deps in LAYERS:
        for d in deps:
            if d not in order or order.index(d) >= order.index(name):
                problems.append(f"tests/check_layering.py: layer '{name}' may not depend on '{d}' (not below it)")
    lib_root = os.path.join(root, "lib", "wobble")
    present = sorted(d for d in os.listdir(lib_root) if os.path.isdir(os.path.join(lib_root, d)))
    for d in present:
        if d not in allowed:
            problems.append(f"lib/wobble/{d}: a folder that is not in the documented layers")

    for rel, top, folder, text in layered_sources(root):
        parts = rel.split(os.sep)
        lines = text.split("\n")
        if len(lines) > MAX_LINES:
            problems.append(f"{rel}: {len(lines)} lines, more than {MAX_LINES}; split it by what its parts do")
        for number, line in enumerate(lines, 1):
            m = INCLUDE.match(line)
            if m:
                inc = m.group(1)
                where = f"{rel}:{number}"
                if top == "lib" and re.match(r"(vtk|Imf|Imath|OpenEXR)", inc):
                    problems.append(f"{where}: lib/ includes {inc}; VTK and OpenEXR belong in pipelines/")
                if top == "pipelines" and inc.startswith("wobble/script/"):
                    problems.append(f"{where}: pipelines/ includes the interpreter ({inc}); use wobble/scene")
                if inc.startswith("wobble/"):
                    target = inc.split("/")
                    if len(target) < 3:
                        continue
                    if "internal" in target[:-1]:
                        inner = os.path.join("lib", *target[:target.index("internal")])
                        if not rel.startswith(inner + os.sep):
                            problems.append(f"{where}: {inc} is internal to lib/{'/'.join(target[:target.index('internal')])}")
                        elif rel.endswith(".h") and "internal" not in parts:
                            problems.append(f"{where}: the public header includes {inc}, which is not "
                                            "installed; include it from the .cc files")
                    if folder and target[1] != folder and target[1] not in allowed.get(folder, []):
                        problems.append(f"{where}: lib/wobble/{folder} may not include {inc} "
                                        f"(it may include: {', '.join(allowed.get(folder, [])) or 'nothing of wobble'})")
                if top != "app" and "internal" not in parts and rel.endswith(".h") and inc.startswith("ceres/"):
                    problems.append(f"{where}: a public header includes Ceres ({inc}); move what needs it to an "
                                    "internal/ header or a .cc")
            m = NAMESPACE.match(line)
            if m and folder:
                ns = m.group(1)
                want = "wobble" if folder in GROUND_FLOOR else f"wobble::{folder}"
                upper = ns.split("::")[1] if ns.count("::") else ""
                wrong = not (ns == want or ns.startswith(want + "::"))
                if folder in GROUND_FLOOR:  # wobble or wobble::detail, never an upper layer's
                    wrong = wrong or upper in order
                if ns.startswith("wobble") and wrong:
                    problems.append(f"{rel}:{number}: namespace {ns} in lib/wobble/{folder}; expected {want}")
    problems += misplaced_definitions(root)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} layering problem(s)")
        return 1
    print("layering ok:", " < ".join(order))
    return 0


if __name__ == "__main__":
    sys.exit(main())
