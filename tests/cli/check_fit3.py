#!/usr/bin/env python3
"""`wobble fit` on a 3D object (issue 15): the q that made data/pot3_squashed.tgt and
data/pot3_scan.ply (their headers), a 3D simulation as the reference of kinematic and dynamic
fits, and bad 3D input.
Usage: check_fit3.py WOBBLE DATA_DIR WORK_DIR"""
import csv, json, math, os, subprocess, sys

wobble, data, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
body = ["--object", f"{data}/pot3.obj", "--modes", f"{data}/pot3_modes.def3"]
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def run(*args):
    return subprocess.run([wobble, *args], capture_output=True, text=True)


def rotation(r):
    """The matrix of rotation vector r (Rodrigues)."""
    a = math.sqrt(sum(x * x for x in r))
    if a == 0:
        return [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    k = [x / a for x in r]
    K = [[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]]
    K2 = [[sum(K[i][m] * K[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    return [[(1.0 if i == j else 0.0) + math.sin(a) * K[i][j] + (1 - math.cos(a)) * K2[i][j] for j in range(3)]
            for i in range(3)]


def turn_between(ra, rb):
    """The angle of Raᵀ Rb."""
    A, B = rotation(ra), rotation(rb)
    trace = sum(A[m][i] * B[m][i] for i in range(3) for m in range(3))
    return math.acos(max(-1.0, min(1.0, (trace - 1) / 2)))


def q_of_header(path):
    for line in open(path):
        if "q = [" in line:
            return [float(x) for x in line.split("q = [")[1].split("]")[0].split()]
    raise ValueError("no q in " + path)


# correspondences with noise 0.3 and one outlier, robust loss (data/pot3_squashed.tgt)
r = run("fit", "pose", *body, "--targets", f"{data}/pot3_squashed.tgt", "--loss", "cauchy", "--loss-scale", "2",
        "--out", f"{work}/pose.json", "--costs", f"{work}/pose_costs.csv")
check(r.returncode == 0, "fit pose (3D correspondences) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/pose.json"))
truth = q_of_header(f"{data}/pot3_squashed.tgt")
check(j["dimension"] == 3 and j["coordinates"] == ["tx", "ty", "tz", "rx", "ry", "rz", "squash", "sway", "twist"],
      "3D coordinates named")
t_err = math.dist(j["q"][:3], truth[:3])
angle = turn_between(j["q"][3:6], truth[3:6])
g_err = max(abs(a - b) for a, b in zip(j["q"][6:], truth[6:]))
# noise 0.3 on 16 points of a pot 200 wide: a few tenths in t, ~1e-2 rad, a few 1e-2 in γ
check(t_err < 0.5 and angle < 0.01 and g_err < 0.05,
      f"pose near the generating q: |dt| {t_err:.3g}, turn {angle:.3g} rad, max |dγ| {g_err:.3g}")
check(max(j["point_residuals"]) > 45, "the outlier keeps its residual")
check(j["conditioning"]["undetermined"] == [], "no undetermined mode")
check(len(j["overlay"]["fitted"]) == 16 and len(j["overlay"]["fitted"][0]) == 3, "overlay: 16 fitted 3D points")

# a scan without correspondences: the mesh of data/pot3_scan.ply
r = run("fit", "pose", *body, "--targets", f"{data}/pot3_scan.tgt", "--out", f"{work}/scan.json")
check(r.returncode == 0, "fit pose (3D surface) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/scan.json"))
truth = q_of_header(f"{data}/pot3_scan.ply")
check(j["kind"] == "surface" and j["rms_residual"] < 1e-4, f"the pot lies on the scan: rms {j['rms_residual']:.3g}")
check(math.dist(j["q"][:3], truth[:3]) < 1e-3, f"translation {j['q'][:3]} is the scan's {truth[:3]}")
# the pot is round: either the scan's own pose, or that pose turned by π about the pot's axis
# with the sway's sign flipped (the same surface)
flip = [truth[6], -truth[7], truth[8]]
same = max(abs(a - b) for a, b in zip(j["q"][6:], truth[6:])) < 1e-3
flipped = max(abs(a - b) for a, b in zip(j["q"][6:], flip)) < 1e-3
turn = turn_between(j["q"][3:6], truth[3:6])
check((same and turn < 1e-3) or (flipped and abs(turn - math.pi) < 1e-3),
      f"modes {j['q'][6:]} and turn {turn:.4g} rad are the scan's or its mirror about the axis")

# a 3D simulation as the reference
sim = f"{work}/throw.csv"
r = run("simulate", *body, "--q", "0 150 0 0.3 0.2 0.1 0.2 -0.1 0.1", "--qdot", "20 40 0 1 2 -1 0 0 0",
        "--no-ground", "--dt", "0.005", "--duration", "0.3", "--out", sim)
check(r.returncode == 0, "simulate the 3D reference: " + r.stderr.strip())
r = run("fit", "trajectory", *body, "--reference", sim, "--every", "5", "--smoothness", "0", "--out", f"{work}/kin.json")
check(r.returncode == 0, "fit trajectory (3D kinematic) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/kin.json"))
rows = [[float(x) for x in row] for row in list(csv.reader(open(sim)))[1:]][::5]
worst = 0.0
for q, row in zip(j["q"], rows):
    w, x, y, z = row[4:8]  # the CSV's quaternion: its rotation vector
    s = math.sqrt(x * x + y * y + z * z)
    rv = [2 * math.atan2(s, w) / s * c for c in (x, y, z)]
    worst = max(worst, math.dist(q[:3], row[1:4]), turn_between(q[3:6], rv), *(abs(a - b) for a, b in zip(q[6:], row[8:11])))
check(len(j["q"]) == len(rows) and worst < 1e-6, f"kinematic q(t) is the simulation's (max error {worst:.2g})")
# dynamic: from other mode constants (3e6, 1e4 in place of 2e6, 2e4), every 50th mass point
start = f"{work}/start.def3"
open(start, "w").write(open(f"{data}/pot3_modes.def3").read().replace("stiffness 2000000 damping 20000",
                                                                      "stiffness 3000000 damping 10000"))
r = run("fit", "trajectory", "--object", f"{data}/pot3.obj", "--modes", start, "--reference", sim, "--every", "5",
        "--points", ",".join(str(k) for k in range(0, 627, 50)), "--dynamic", "--dt", "0.005", "--no-ground",
        "--out", f"{work}/dyn.json")
check(r.returncode == 0, "fit trajectory --dynamic (3D) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/dyn.json"))
k_err = max(abs(k / 2e6 - 1) for k in j["stiffness"])
c_err = max(abs(c / 2e4 - 1) for c in j["damping"])
v_err = max(abs(a - b) for a, b in zip(j["qdot0"], [20, 40, 0, 1, 2, -1, 0, 0, 0]))
check(k_err < 1e-6 and c_err < 1e-5 and v_err < 1e-6,
      f"stiffness, damping and q-dot0 recovered (relative {k_err:.2g}, {c_err:.2g}; |dv| {v_err:.2g})")
# the same fit on the 3D adjoint gradient (BFGS): the same numbers
r = run("fit", "trajectory", "--object", f"{data}/pot3.obj", "--modes", start, "--reference", sim, "--every", "5",
        "--points", ",".join(str(k) for k in range(0, 627, 50)), "--dynamic", "--dt", "0.005", "--no-ground",
        "--gradient", "adjoint", "--max-iterations", "2000", "--out", f"{work}/dyn_adjoint.json")
check(r.returncode == 0, "fit trajectory --dynamic --gradient adjoint (3D) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/dyn_adjoint.json"))
k_err = max(abs(k / 2e6 - 1) for k in j["stiffness"])
c_err = max(abs(c / 2e4 - 1) for c in j["damping"])
v_err = max(abs(a - b) for a, b in zip(j["qdot0"], [20, 40, 0, 1, 2, -1, 0, 0, 0]))
check(j["gradient"] == "adjoint" and k_err < 1e-6 and c_err < 1e-5 and v_err < 1e-6,
      f"the adjoint fit recovers the same (relative {k_err:.2g}, {c_err:.2g}; |dv| {v_err:.2g})")

# bad 3D input: exit 2, file and line, nothing written
out = f"{work}/never.json"
r = run("fit", "pose", *body, "--targets", f"{data}/table_pose.tgt", "--out", out)
check(r.returncode == 2 and "table_pose.tgt:6: the object is 3D: its target file starts with 'dimension 3'" in r.stderr,
      "a 2D target file for a 3D object: " + r.stderr.strip())
r = run("fit", "pose", "--object", f"{data}/table.obj", "--modes", f"{data}/table_modes.def", "--targets",
        f"{data}/pot3_squashed.tgt", "--out", out)
check(r.returncode == 2 and "pot3_squashed.tgt:7: a 3D target file for a 2D object" in r.stderr,
      "a 3D target file for a 2D object: " + r.stderr.strip())
bad = f"{work}/bad.tgt"
open(bad, "w").write("dimension 3\n# a scan\nmesh missing.ply\n")
r = run("fit", "pose", *body, "--targets", bad, "--out", out)
check(r.returncode == 2 and "bad.tgt:3: mesh:" in r.stderr and "missing.ply" in r.stderr, "a missing mesh: " + r.stderr.strip())
open(bad, "w").write("dimension 3\npoint 3 1 2\n")
r = run("fit", "pose", *body, "--targets", bad, "--out", out)
check(r.returncode == 2 and "bad.tgt:2: expected 4 numbers (point <k> <x> <y> <z>" in r.stderr, "a 2D point line in 3D")
open(bad, "w").write("dimension 3\npolyline 0 0 1 1\n")
r = run("fit", "pose", *body, "--targets", bad, "--out", out)
check(r.returncode == 2 and "'polyline' is for 2D target files" in r.stderr, "no polylines in 3D")
r = run("fit", "pose", *body, "--targets", f"{data}/pot3_scan.tgt", "--alternate", "--out", out)
check(r.returncode == 2 and "--alternate" in r.stderr, "--alternate is 2D only")
check(not os.path.exists(out), "nothing written for bad input")
sys.exit(1 if failures else 0)
