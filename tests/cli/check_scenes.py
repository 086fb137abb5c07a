#!/usr/bin/env python3
"""Runs the Witkin & Welch scenes of data/ with `wobble run` and checks what they print and write.

usage: check_scenes.py WOBBLE DATA_DIR WORK_DIR

Each scene runs in WORK_DIR (its `render out/figN` goes there). From the positions that `print`
lists (one "  NAME x y [z]" line per named point after a "t = ..." line) it checks that the
physics did what the paper's figure shows; it checks that the .pvd series was written, and the
PNG frames and filmstrip when there is an X display.
"""
import math
import os
import shutil
import subprocess
import sys


def run(wobble, script, work):
    p = subprocess.run([wobble, "run", script], cwd=work, capture_output=True, text=True)
    print(p.stdout)
    print(p.stderr, file=sys.stderr)
    if p.returncode != 0:
        sys.exit(f"FAIL: {script} exited {p.returncode}")
    return p.stdout


def prints(stdout):
    """[(t, energy, violation, {name: [coords]})] for every `print` of the scene."""
    blocks = []
    for line in stdout.splitlines():
        if line.startswith("t = ") and "largest constraint violation" in line:
            w = line.split()
            blocks.append((float(w[2]), float(w[4]), float(w[8]), {}))
        elif line.startswith("  ") and blocks and not line.startswith("  t = ") and "/" not in line:
            w = line.split()
            try:
                blocks[-1][3][w[0]] = [float(x) for x in w[1:]]
            except ValueError:
                pass
    return blocks


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def outputs(work, folder, stem, frames_expected):
    check(os.path.isfile(os.path.join(work, folder, "vtp", stem + ".pvd")), f"{folder}/vtp/{stem}.pvd written")
    if os.environ.get("DISPLAY"):
        frames = os.path.join(work, folder, "frames")
        n = len([f for f in os.listdir(frames) if f.endswith(".png")]) if os.path.isdir(frames) else 0
        check(n == frames_expected, f"{folder}: {n} PNG frames (expected {frames_expected})")
        check(os.path.isfile(os.path.join(work, folder, "filmstrip.png")), f"{folder}/filmstrip.png written")
    else:
        print("no DISPLAY: frames and filmstrip not expected")


def main():
    wobble, data, work = sys.argv[1:4]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)

    # Fig. 1: the quadratic block bends towards the pull, its right corners stay nailed
    out = prints(run(wobble, os.path.join(data, "fig1_quadratic_pull.wob"), work))
    check(len(out) == 2, "fig1 printed twice")
    t, e, viol, p = out[0]
    check(abs(t - 2.0) < 1e-9, "fig1: first print at t = 2")
    check(dist(p["pull"], [-1.8, 0, 0]) < 1e-3, f"fig1: the pulled point reached its last key (-1.8, 0, 0): {p['pull']}")
    for c, want in (("c1", [1, .5, .5]), ("c2", [1, .5, -.5]), ("c3", [1, -.5, .5]), ("c4", [1, -.5, -.5])):
        check(dist(p[c], want) < 1e-3, f"fig1: corner {c} stays nailed at {want}: {p[c]}")
    bulge = p["left_top"][0] - p["pull"][0]
    check(bulge > 0.05, f"fig1: the left face bends (its corner lags the pulled middle by {bulge:.3f} > 0.05)")
    t2, _, _, p2 = out[1]
    check(p2["pull"][0] > -1.8 + 0.2, f"fig1: let go, it springs back (pull x {p2['pull'][0]:.3f} at t = {t2})")
    outputs(work, "out/fig1", "fig1_quadratic_pull", 121)

    # Fig. 2: the triple pendulum keeps its nail, its joints and its energy (0 at the start)
    out = prints(run(wobble, os.path.join(data, "fig2_triple_pendulum.wob"), work))
    check(len(out) == 2, "fig2 printed twice")
    t0, e0, _, p0 = out[0]
    t, e, viol, p = out[1]
    check(abs(e0) < 1e-12, f"fig2: starts at rest, undeformed, at y = 0: energy {e0}")
    check(dist(p["top"], [0, 0]) < 1e-4, f"fig2: the top stays nailed: {p['top']}")
    check(dist(p["elbow1"], p["elbow1b"]) < 1e-4 and dist(p["elbow2"], p["elbow2b"]) < 1e-4, "fig2: joints hold")
    check(abs(e - e0) < 0.01 * 3 * 9.81 * 1.5, f"fig2: energy {e} within 1% of m g L of the start")
    check(p["tip"][1] < -0.5, f"fig2: it swung down (tip at y = {p['tip'][1]:.3f})")
    outputs(work, "out/fig2", "fig2_triple_pendulum", 121)

    # Fig. 3: the hook hangs on the sky point, the pyramid dangles from its tip off the ground
    out = prints(run(wobble, os.path.join(data, "fig3_sky_hook.wob"), work))
    check(len(out) == 1, "fig3 printed once")
    t, e, viol, p = out[0]
    check(dist(p["hook_eye"], p["sky_point"]) < 1e-3, f"fig3: the hook's eye hangs on the sky point: {p['hook_eye']}")
    check(dist(p["hook_tip"], p["pyr_tip"]) < 1e-3, f"fig3: the pyramid's tip is held by the hook's tip")
    # the pair still swings from the sky point (nothing damps a pendulum's swing), so: the hook
    # keeps its length 0.8 and its tip, with the pyramid, is below its eye
    check(abs(dist(p["hook_eye"], p["hook_tip"]) - 0.8) < 0.05, "fig3: the hook keeps its length")
    check(p["pyr_tip"][1] < p["hook_eye"][1] - 0.3, "fig3: the pyramid hangs below the hook's eye")
    base = [p[k][1] for k in ("pyr_a", "pyr_b", "pyr_c")]
    check(min(base) > 1.0, f"fig3: the pyramid was carried off the ground (base heights {base})")
    # it swings (a double pendulum, undamped) but hangs: the base's centre, (a + b)/2 and c
    # being opposite edges' middles, and with it the centre of mass, is below the held tip
    centre = ((p["pyr_a"][1] + p["pyr_b"][1]) / 2 + p["pyr_c"][1]) / 2
    check(centre < p["pyr_tip"][1], f"fig3: and it dangles from its tip (base centre at y = {centre:.3f})")
    outputs(work, "out/fig3", "fig3_sky_hook", 181)

    if failures:
        sys.exit(f"{len(failures)} check(s) failed")


main()
