#!/usr/bin/env python3
"""The installed wobble, used as a stranger would (issue 16).

Installs the build tree into a fresh prefix (cmake --install), checks the layout and that only
public headers are installed (no internal/ folder, no Ceres include, nothing left out that an
installed header includes; issue 45), configures
examples/cpp against the *installed* package (find_package(wobble)), builds and runs it, and
imports the installed Python package: both must drop the table to the same resting height.

Usage: check_install.py CMAKE BUILD_DIR SOURCE_DIR WORK_DIR PYTHON
"""
import os
import re
import shutil
import subprocess
import sys


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"FAILED ({r.returncode}): {' '.join(cmd)}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    return r.stdout


INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def check_public_headers(include_dir):
    """Only public headers are installed (issue 45): nothing under an internal/ folder, no
    header that includes Ceres, and every wobble or pipelines header an installed one includes
    is installed too (so no public header leans on one left out)."""
    problems = []
    headers = 0
    for root, dirs, files in os.walk(include_dir):
        rel_root = os.path.relpath(root, include_dir)
        if "internal" in rel_root.split(os.sep):
            problems.append(f"{rel_root}: an internal folder is installed")
        for name in files:
            path = os.path.join(root, name)
            rel = os.path.relpath(path, include_dir)
            headers += 1
            with open(path, encoding="utf-8") as f:
                for number, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    quote, inc = m.groups()
                    where = f"{rel}:{number}"
                    if inc.startswith("ceres/"):
                        problems.append(f"{where}: includes Ceres ({inc})")
                    if "internal/" in inc:
                        problems.append(f"{where}: includes an internal header ({inc})")
                    # every quoted include is one of ours (wobble/..., pipelines/...)
                    if quote == '"' or inc.startswith(("wobble/", "pipelines/")):
                        found = os.path.exists(os.path.join(include_dir, inc)) or \
                            (quote == '"' and os.path.exists(os.path.join(root, inc)))
                        if not found:
                            problems.append(f"{where}: includes {inc}, which is not installed")
    if headers < 50:
        problems.append(f"only {headers} headers installed under {include_dir}")
    return problems


def main():
    cmake, build, source, work, python = sys.argv[1:6]
    shutil.rmtree(work, ignore_errors=True)
    prefix = os.path.join(work, "prefix")
    run([cmake, "--install", build, "--prefix", prefix])

    expected = ["include/wobble/world/world.h", "include/wobble/fit/pose_fit.h", "include/pipelines/trajectory_render.h",
                "lib/libwobble.a", "lib/libwobble_fit.a", "lib/libwobble_pipelines.a",
                "lib/cmake/wobble/wobbleConfig.cmake", "lib/cmake/wobble/wobbleTargets.cmake", "bin/wobble"]
    missing = [f for f in expected if not os.path.exists(os.path.join(prefix, f))]
    site = [os.path.join(root) for root, dirs, files in os.walk(prefix) if "__init__.pyi" in files]
    if missing or len(site) != 1:
        sys.exit(f"FAILED: the install lacks {missing}; Python packages found: {site}")
    problems = check_public_headers(os.path.join(prefix, "include"))
    if problems:
        sys.exit("FAILED: the installed headers are not the public ones:\n  " + "\n  ".join(problems))

    # the consumer project, against the installed tree only
    hello_build = os.path.join(work, "hello")
    run([cmake, "-S", os.path.join(source, "examples", "cpp"), "-B", hello_build, f"-DCMAKE_PREFIX_PATH={prefix}",
         "-DCMAKE_BUILD_TYPE=Release"])
    run([cmake, "--build", hello_build])
    out = run([os.path.join(hello_build, "hello_wobble"), os.path.join(source, "data")])
    m = re.search(r"at rest at y = (-?[0-9.]+) after (\d+) steps", out)
    if not m:
        sys.exit(f"FAILED: hello_wobble printed no resting height:\n{out}")
    print(out, end="")

    # the installed Python package (not the build tree's) drops the same table
    env = dict(os.environ, PYTHONPATH=os.path.dirname(site[0]))
    code = ("import wobble, sys\n"
            f"assert wobble.__file__.startswith({prefix!r}), wobble.__file__\n"
            f"d = {os.path.join(source, 'data')!r}\n"
            "t = wobble.load_body(d + '/table.obj', [d + '/table_modes.def'])\n"
            "w = wobble.World(wobble.WorldOptions(dt=0.01)); w.add_body(t)\n"
            "w.set_state(0, [0, 50, 0, 0, 0, 0, 0])\n"
            "calm = 0\n"
            "for second in range(1, 121):\n"
            "    w.run_until(second)\n"
            "    calm = calm + 1 if w.energies(0).kinetic < 1.0 else 0\n"
            "    if calm == 3: break\n"
            "print(f'{w.q(0)[1]:.3f} {w.steps}')\n")
    py = run([python, "-c", code], env=env).split()
    if py != [m.group(1), m.group(2)]:
        sys.exit(f"FAILED: the C++ consumer rests at y = {m.group(1)} after {m.group(2)} steps, Python at {py}")
    print(f"installed C++ and Python agree: rest at y = {py[0]} after {py[1]} steps")


if __name__ == "__main__":
    main()
