#!/usr/bin/env python3
"""The help of the subcommands that start a body says what their parser takes (issue 45).

The integrator names come from the parser itself: the message of a refused --integrator lists
IntegratorNames(), and each of those names must then run. Every one must appear in the
--integrator help of simulate (and of render, export and view when built with VTK), and the
--q / --qdot help must give the 3D layout (rotation vector, body-frame angular velocity) as well
as the 2D one.

Usage: check_help.py WOBBLE DATA_DIR OUT_DIR
"""
import os
import re
import subprocess
import sys


def run(cmd):
    env = dict(os.environ)
    env.pop("DISPLAY", None)  # help and these short runs need no display
    return subprocess.run(cmd, capture_output=True, text=True, env=env)


def option_help(text, flag):
    """The help of one option: its line and the continuation lines below it."""
    lines = text.split("\n")
    for i, line in enumerate(lines):
        if re.match(rf"\s+{re.escape(flag)}\b(?![-\w])", line):
            more = [l for l in lines[i + 1:i + 3] if re.match(r"\s{20,}\S", l)]
            return " ".join([line] + more)
    return None


def main():
    wobble, data, out = sys.argv[1:4]
    os.makedirs(out, exist_ok=True)
    table = ["--object", os.path.join(data, "table.obj"), "--modes", os.path.join(data, "table_modes.def")]
    problems = []

    r = run([wobble, "simulate", *table, "--integrator", "no-such-integrator", "--out", os.path.join(out, "x.csv")])
    m = re.search(r"is not one of (.+)", r.stdout + r.stderr)
    if r.returncode != 2 or not m:
        sys.exit(f"FAILED: a bad --integrator did not exit 2 listing the names (exit {r.returncode}):\n{r.stderr}")
    names = [n.strip() for n in m.group(1).split(",")]
    if len(names) < 5 or "variational" not in names:
        sys.exit(f"FAILED: the parser lists too few integrators: {names}")
    for name in names:
        r = run([wobble, "simulate", *table, "--integrator", name, "--duration", "0.05",
                 "--out", os.path.join(out, f"{name}.csv")])
        if r.returncode != 0:
            problems.append(f"--integrator {name} (listed by the parser) does not run: {r.stderr.strip()}")

    commands = ["simulate"]
    top = run([wobble, "--help"]).stdout
    commands += [c for c in ("render", "export", "view") if re.search(rf"^\s+{c}\b", top, re.M)]
    for command in commands:
        r = run([wobble, command, "--help"])
        if r.returncode != 0:
            problems.append(f"{command} --help exits {r.returncode}")
            continue
        integrator = option_help(r.stdout, "--integrator") or ""
        for name in names:
            if not re.search(rf"\b{re.escape(name)}\b", integrator):
                problems.append(f"{command} --help: --integrator does not name '{name}': {integrator.strip()}")
        q = option_help(r.stdout, "--q") or ""
        for part in ("tx ty theta g1", "tx ty tz rx ry rz g1", "rotation vector"):
            if part not in q:
                problems.append(f"{command} --help: --q does not say '{part}': {q.strip()}")
        qdot = option_help(r.stdout, "--qdot") or ""
        for part in ("vx vy vz wx wy wz dg1", "body frame"):
            if part not in qdot:
                problems.append(f"{command} --help: --qdot does not say '{part}': {qdot.strip()}")

    for p in problems:
        print("FAILED:", p)
    if problems:
        sys.exit(1)
    print(f"help of {', '.join(commands)}: every integrator ({', '.join(names)}) and the 2D and 3D layouts")


if __name__ == "__main__":
    main()
