#!/usr/bin/env python3
"""`wobble fit`: checks the JSON and CSV it writes against the q that generated the targets
(data/*.tgt headers) and a simulated reference, and its handling of bad input.
Usage: check_fit.py WOBBLE DATA_DIR CLI_DIR WORK_DIR"""
import csv, json, os, subprocess, sys

wobble, data, cli, work = sys.argv[1:5]
os.makedirs(work, exist_ok=True)
body = ["--object", f"{data}/table.obj", "--modes", f"{data}/table_modes.def"]
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def run(*args):
    return subprocess.run([wobble, *args], capture_output=True, text=True)


# pose with correspondences and an outlier: the generating q (data/table_pose.tgt header)
r = run("fit", "pose", *body, "--targets", f"{data}/table_pose.tgt", "--loss", "cauchy", "--loss-scale", "5",
        "--out", f"{work}/pose.json", "--costs", f"{work}/pose_costs.csv")
check(r.returncode == 0, "fit pose exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/pose.json"))
truth = [120, 40, 0.2, 0.3, -0.15, 0.2, 0.1]
tol = [1, 1, 5e-3, 0.02, 0.02, 0.02, 0.02]
check(all(abs(a - b) <= t for a, b, t in zip(j["q"], truth, tol)), f"pose q {j['q']} near {truth}")
check(j["point_residuals"][7] > 50, "the outlier (mass point 7) keeps its residual")
check(j["conditioning"]["undetermined"] == [], "no undetermined mode")
rows = list(csv.reader(open(f"{work}/pose_costs.csv")))
check(rows[0] == ["iteration", "cost"], "costs CSV header")
check(abs(float(rows[-1][1]) - j["report"]["final_cost"]) <= 1e-9 * j["report"]["final_cost"], "last cost = final cost")
check(len(j["overlay"]["fitted"]) == len(j["overlay"]["targets"]), "overlay pairs fitted points with targets")

# curve without correspondences (data/table_curve.tgt header)
r = run("fit", "pose", *body, "--targets", f"{data}/table_curve.tgt", "--out", f"{work}/curve.json")
check(r.returncode == 0, "fit pose (curve) exits 0")
j = json.load(open(f"{work}/curve.json"))
truth = [-40, 10, -0.1, 0.4, 0.1, -0.2, 0.15]
tol = [1.5, 1.5, 5e-3, 0.03, 0.03, 0.03, 0.03]
check(all(abs(a - b) <= t for a, b, t in zip(j["q"], truth, tol)), f"curve q {j['q']} near {truth}")

# a recorded simulation as the reference: kinematic and dynamic fits
sim = f"{work}/throw.csv"
r = run("simulate", *body, "--q", "0 100 0.1 0.1 0 0 0", "--qdot", "20 40 0.5 0.3 0 0 0", "--no-ground",
        "--dt", "0.01", "--duration", "0.5", "--out", sim)
check(r.returncode == 0, "simulate the reference")
r = run("fit", "trajectory", *body, "--reference", sim, "--smoothness", "0", "--out", f"{work}/kin.json")
check(r.returncode == 0, "fit trajectory (kinematic) exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/kin.json"))
ref = [[float(x) for x in row[1:8]] for row in list(csv.reader(open(sim)))[1:]]
err = max(abs(a - b) for qa, qb in zip(j["q"], ref) for a, b in zip(qa, qb))
check(len(j["q"]) == len(ref) and err < 1e-6, f"kinematic q matches the simulation (max error {err:.2g})")
# the fit starts from other modes: K = 2e6, c = 5e5 in place of data/table_modes.def's 4e6, 1e6
start_modes = f"{work}/start_modes.def"
with open(start_modes, "w") as f:
    f.write(open(f"{data}/table_modes.def").read().replace("stiffness 4000000 damping 1000000",
                                                         "stiffness 2000000 damping 500000"))
start_body = ["--object", f"{data}/table.obj", "--modes", start_modes]
r = run("fit", "trajectory", *start_body, "--reference", sim, "--dynamic", "--no-ground", "--dt", "0.01", "--every", "5",
        "--fit", "stiffness,damping", "--q0", "0 100 0.1 0.1 0 0 0", "--qdot0", "20 40 0.5 0.3 0 0 0",
        "--out", f"{work}/dyn.json")
check(r.returncode == 0, "fit trajectory --dynamic exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/dyn.json"))
check(abs(j["stiffness"][0] / 4e6 - 1) < 1e-4 and abs(j["damping"][0] / 1e6 - 1) < 1e-3,
      f"dynamic fit from K = 2e6, c = 5e5 finds the bend's K = 4e6, c = 1e6 of the reference: "
      f"{j['stiffness'][0]}, {j['damping'][0]}")

# a pose-graph controller (issue 6): data/pose_graph_reference.wob records 3 s of the table
# driven by three poses (smoothed switches); the poses and times come back from a start 0.05 off
# in every target and 10-25% off in every time, with annealing on the same budget beside it
r = subprocess.run([wobble, "run", f"{data}/pose_graph_reference.wob"], capture_output=True, text=True, cwd=work)
check(r.returncode == 0, "wobble run data/pose_graph_reference.wob exits 0: " + r.stderr.strip())
ground = ["--ground-stiffness", "45000", "--ground-damping", "3000", "--friction-damping", "3000", "--friction-cap", "0.5"]
r = run("fit", "trajectory", "--object", f"{data}/table.obj", "--modes", f"{data}/bounding_modes.def",
        "--reference", f"{work}/out/pose_graph.csv", "--dynamic", "--dt", "0.01", "--every", "2", "--fit", "poses,times",
        "--q0", "0 0 0 0 0 0 0", "--qdot0", "0 0 0 0 0 0 0", *ground,
        "--poses", "0.25 -0.05 0.45; -0.05 0.2 0.25; 0.1 0.1 0.55", "--anneal", "--out", f"{work}/graph.json")
check(r.returncode == 0, "fit trajectory --fit poses,times exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/graph.json"))
g = j["pose_graph"]
truth_poses, truth_times = [[0.2, -0.1], [-0.1, 0.15], [0.05, 0.1]], [0.4, 0.3, 0.5]
err = max(max(abs(a - b) for pa, pb in zip(g["poses"], truth_poses) for a, b in zip(pa, pb)),
          max(abs(a - b) for a, b in zip(g["durations"], truth_times)))
check(err < 1e-6 and g["active"] == ["bend", "shear"] and g["cyclic"],
      f"the pose graph of the reference is recovered (max error {err:.2g})")
check(j["annealing"]["simulations"] == j["simulations"] and j["annealing"]["cost"] > 1e3 * j["report"]["final_cost"],
      f"annealing with the same {j['simulations']} simulations ends higher: {j['annealing']['cost']} vs "
      f"{j['report']['final_cost']}")
# the same fit by the adjoint gradient (issue 18): the same graph
r = run("fit", "trajectory", "--object", f"{data}/table.obj", "--modes", f"{data}/bounding_modes.def",
        "--reference", f"{work}/out/pose_graph.csv", "--dynamic", "--dt", "0.01", "--every", "2", "--fit", "poses,times",
        "--q0", "0 0 0 0 0 0 0", "--qdot0", "0 0 0 0 0 0 0", *ground, "--gradient", "adjoint",
        "--poses", "0.25 -0.05 0.45; -0.05 0.2 0.25; 0.1 0.1 0.55", "--out", f"{work}/graph_adjoint.json")
check(r.returncode == 0, "fit trajectory --gradient adjoint exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/graph_adjoint.json"))
g = j["pose_graph"]
err = max(max(abs(a - b) for pa, pb in zip(g["poses"], truth_poses) for a, b in zip(pa, pb)),
          max(abs(a - b) for a, b in zip(g["durations"], truth_times)))
check(err < 1e-6 and j["gradient"] == "adjoint", f"the adjoint fit recovers the same pose graph (max error {err:.2g})")
r = run("fit", "trajectory", "--object", f"{data}/table.obj", "--modes", f"{data}/bounding_modes.def",
        "--reference", f"{work}/out/pose_graph.csv", "--dynamic", "--gradient", "reverse")
check(r.returncode == 2 and "--gradient" in r.stderr, "an unknown --gradient: exit 2 " + r.stderr.strip())
r = run("fit", "trajectory", "--object", f"{data}/table.obj", "--modes", f"{data}/bounding_modes.def",
        "--reference", f"{work}/out/pose_graph.csv", "--dynamic", "--fit", "poses", "--poses", "0.2 0.4; 0.1 0.1 0.3")
check(r.returncode == 2 and "--poses: a pose needs 2 targets" in r.stderr, "a pose of the wrong size: exit 2 " + r.stderr.strip())
r = run("fit", "trajectory", "--object", f"{data}/table.obj", "--modes", f"{data}/bounding_modes.def",
        "--reference", f"{work}/out/pose_graph.csv", "--dynamic", "--fit", "times", "--switch-width", "0",
        "--poses", "0.2 0.1 0.4")
check(r.returncode == 2 and "--switch-width > 0" in r.stderr, "times with a hard switch: exit 2 " + r.stderr.strip())

# a spacetime fit (issue 18): a hop from a standing start, whose targets a script plays with
# `schedule` (data/hop.wob's setup); the table is off the ground at 0.7 s and back by 1.5 s
hop = ["--object", f"{data}/table.obj", "--modes", f"{data}/hop_modes.def", "--ground-stiffness", "45000",
       "--ground-damping", "3000", "--friction-damping", "3000", "--friction-cap", "0.5"]
r = run("fit", "spacetime", *hop, "--duration", "1", "--knots", "21", "--rise", "2 0.7", "--upright",
        "--targets", f"{work}/hop_targets.csv", "--out", f"{work}/hop_fit.json")
check(r.returncode == 0, "fit spacetime exits 0: " + r.stderr.strip())
j = json.load(open(f"{work}/hop_fit.json"))
check(j["ok"] and j["cost"] < 1e-2 * j["initial_cost"] and len(j["knots"]) == 21,
      f"the spacetime fit lowers the cost from {j['initial_cost']} to {j['cost']}")
rows = list(csv.reader(open(f"{work}/hop_targets.csv")))
check(rows[0] == ["t", "bend", "shear", "vsquash", "hsquash"] and len(rows) == 101, "the schedule: a row per step")
with open(f"{work}/hop.wob", "w") as f:
    f.write(f"load_obj {data}/table.obj\nload_def {data}/hop_modes.def\nset integrator thesis\nset dt 0.01\n"
            f"set grconst 45000\n"
            f"set grdam 3000\nset frconst 3000\nset frsin 0.5\nschedule {work}/hop_targets.csv\n"
            f"output {work}/hop.csv\nsimul 1.5\n")
r = subprocess.run([wobble, "run", f"{work}/hop.wob"], capture_output=True, text=True, cwd=work)
check(r.returncode == 0 and "schedule: 100 steps" in r.stdout, "a script plays the schedule: " + r.stderr.strip())
run_rows = list(csv.DictReader(open(f"{work}/hop.csv")))
at = {round(float(x["t"]), 2): x for x in run_rows}
check(int(float(at[0.7]["contacts"])) == 0 and float(at[0.7]["ty"]) > 1.0 and int(float(at[1.5]["contacts"])) > 0,
      f"in the air at 0.7 s (feet at {at[0.7]['ty']}), down again at 1.5 s")
# `save` writes the schedule beside the script; the saved script replays the same motion
with open(f"{work}/hop_save.wob", "w") as f:
    f.write(open(f"{work}/hop.wob").read().replace(f"output {work}/hop.csv\nsimul 1.5\n", "")
            + f"set end 1.5\nsave {work}/hop_saved.wob\n")
r = subprocess.run([wobble, "run", f"{work}/hop_save.wob"], capture_output=True, text=True, cwd=work)
saved = open(f"{work}/hop_saved.wob").read() if os.path.exists(f"{work}/hop_saved.wob") else ""
check(r.returncode == 0 and f"schedule {work}/hop_saved.schedule.csv" in saved
      and list(csv.reader(open(f"{work}/hop_saved.schedule.csv"))) == rows,
      "save writes the schedule beside the script, the same rows: " + r.stderr.strip())
with open(f"{work}/hop_saved.wob", "w") as f:
    f.write(saved.replace("simul\nprint\n", f"output {work}/hop_replay.csv\nsimul\nprint\n"))
r = subprocess.run([wobble, "run", f"{work}/hop_saved.wob"], capture_output=True, text=True, cwd=work)
replay = {round(float(x["t"]), 2): x for x in csv.DictReader(open(f"{work}/hop_replay.csv"))} if r.returncode == 0 else {}
check(r.returncode == 0 and replay.get(1.5, {}).get("ty") == at[1.5]["ty"] and replay.get(0.7, {}).get("ty") == at[0.7]["ty"],
      "the saved script replays the hop digit for digit: " + r.stderr.strip())
with open(f"{work}/bad_schedule.csv", "w") as f:
    f.write("t,bend,shear\n0,0,0\n")
with open(f"{work}/bad_schedule.wob", "w") as f:
    f.write(f"load_obj {data}/table.obj\nload_def {data}/hop_modes.def\nschedule {work}/bad_schedule.csv\n")
r = subprocess.run([wobble, "run", f"{work}/bad_schedule.wob"], capture_output=True, text=True, cwd=work)
check(r.returncode == 2 and "bad_schedule.wob:3: schedule: " in r.stderr and "bad_schedule.csv:1: expected the header"
      in r.stderr, "a schedule without the object's modes: exit 2 with both files and lines: " + r.stderr.strip())
# --start: a fit from the last one's targets begins near where that one ended
r = run("fit", "spacetime", *hop, "--duration", "1", "--knots", "21", "--rise", "2 0.7", "--upright",
        "--start", f"{work}/hop_targets.csv", "--max-iterations", "5", "--out", f"{work}/hop_again.json")
again = json.load(open(f"{work}/hop_again.json")) if r.returncode == 0 else {"initial_cost": float("inf")}
check(r.returncode == 0 and again["initial_cost"] < 1e-3 * j["initial_cost"],
      f"--start: the fit starts at cost {again['initial_cost']} (from zero targets: {j['initial_cost']})")
r = run("fit", "spacetime", *hop, "--duration", "1", "--upright", "--start", f"{work}/bad_schedule.csv")
check(r.returncode == 2 and "bad_schedule.csv:1: expected the header" in r.stderr, "a bad --start file: exit 2 " + r.stderr.strip())
r = run("fit", "spacetime", *hop, "--duration", "1", "--upright", "--knots", "1")
check(r.returncode == 2 and "--knots" in r.stderr, "one knot: exit 2 " + r.stderr.strip())
r = run("fit", "spacetime", *hop, "--duration", "1")
check(r.returncode == 2 and "no task" in r.stderr, "no task: exit 2 " + r.stderr.strip())
r = run("fit", "spacetime", *hop, "--duration", "1", "--rise", "2 0.705")
check(r.returncode == 2 and "--rise" in r.stderr, "a time between steps: exit 2 " + r.stderr.strip())

# the same for a 3D object (FitSpacetime3): the 3D table on the same ground, its schedule played
# by a script; 40 iterations of one start lower the cost (the full hop needs --starts, data/hop3.wob)
hop3 = ["--object", f"{data}/table3.obj", "--modes", f"{data}/hop3_modes.def3", *hop[4:]]
r = run("fit", "spacetime", *hop3, "--duration", "1", "--knots", "11", "--rise", "2 0.7", "--upright",
        "--max-iterations", "40", "--targets", f"{work}/hop3_targets.csv", "--out", f"{work}/hop3_fit.json")
check(r.returncode == 0, "fit spacetime of a 3D object exits 0: " + r.stderr.strip())
j3 = json.load(open(f"{work}/hop3_fit.json")) if r.returncode == 0 else {}
check(j3.get("ok") and j3["cost"] < 0.1 * j3["initial_cost"] and len(j3["knots"]) == 11 and j3["body"] == "table3",
      f"the 3D spacetime fit lowers the cost from {j3.get('initial_cost')} to {j3.get('cost')}")
rows3 = list(csv.reader(open(f"{work}/hop3_targets.csv"))) if r.returncode == 0 else []
check(rows3 and rows3[0] == ["t", "bend", "shear", "squash", "twist"] and len(rows3) == 101,
      "the 3D schedule: a row per step of every mode")
with open(f"{work}/hop3.wob", "w") as f:
    f.write(f"load_obj {data}/table3.obj\nload_def {data}/hop3_modes.def3\nset integrator thesis\nset dt 0.01\n"
            f"set grconst 45000\nset grdam 3000\nset frconst 3000\nset frsin 0.5\n"
            f"schedule {work}/hop3_targets.csv\noutput {work}/hop3.csv\nsimul 1\n")
r = subprocess.run([wobble, "run", f"{work}/hop3.wob"], capture_output=True, text=True, cwd=work)
played = list(csv.DictReader(open(f"{work}/hop3.csv"))) if r.returncode == 0 else []
# the row at t = 0.5 is the state after step 49, which ran with the file's step 49 (its row 50)
check(r.returncode == 0 and "schedule: 100 steps" in r.stdout and len(played) == 101
      and all(float(played[k]["target_squash"]) == float(rows3[k][3]) for k in (1, 50, 100)),
      "a script plays the 3D schedule, each step with the file's targets: " + r.stderr.strip())
r = run("fit", "spacetime", *hop3, "--duration", "1", "--reach", "1 2 0.5")
check(r.returncode == 2 and "X Y Z T" in r.stderr, "a 3D --reach needs four numbers: exit 2 " + r.stderr.strip())

# multi-start (--starts): start 0 is the plain fit, the rest perturb it with a seeded generator,
# so a fit repeats exactly on any number of threads and keeps the lowest cost of its starts
multi = ["fit", "spacetime", *hop, "--duration", "1", "--knots", "21", "--rise", "2 0.7", "--upright",
         "--max-iterations", "40", "--starts", "4"]
r1 = run(*multi, "--threads", "1", "--out", f"{work}/multi1.json")
r2 = run(*multi, "--threads", "2", "--out", f"{work}/multi2.json")
r0 = run(*multi[:-2], "--out", f"{work}/multi0.json")
m1, m2, m0 = (json.load(open(f"{work}/multi{k}.json")) if r.returncode == 0 else {}
              for k, r in ((1, r1), (2, r2), (0, r0)))
check(m1 and m2 and m0 and m1 == m2, "multi-start: one thread and two give the same fit " + r1.stderr + r2.stderr)
costs = m1.get("starts", {}).get("costs", [])
check(len(costs) == 4 and costs[0] == m0.get("cost") and m1["cost"] == min(costs) == costs[m1["starts"]["best"]],
      f"multi-start: start 0 is the plain fit ({m0.get('cost')}), the best of {costs} wins ({m1.get('cost')})")
r = run(*multi, "--start-spread", "-1")
check(r.returncode == 2, "a negative --start-spread: exit 2 " + r.stderr.strip())
r = run(*multi[:-1], "0")
check(r.returncode == 2, "--starts 0: exit 2 " + r.stderr.strip())

# data/hop_high.wob plays the shipped multi-start hop: off the ground from 0.1 s until it lands
# after 5 s, its feet above 25 at the top (2.5 s), upright when it lands
# (its paths made this run's; the render left out)
script = open(f"{data}/hop_high.wob").read().replace("load_obj table.obj", f"load_obj {data}/table.obj")
script = script.replace("load_def hop_modes.def", f"load_def {data}/hop_modes.def")
script = script.replace("schedule data/", f"schedule {data}/").replace("output out/", f"output {work}/")
script = "\n".join(line for line in script.splitlines() if not line.startswith("render "))
with open(f"{work}/hop_high.wob", "w") as f:
    f.write(script + "\n")
r = subprocess.run([wobble, "run", f"{work}/hop_high.wob"], capture_output=True, text=True, cwd=work)
high = list(csv.DictReader(open(f"{work}/hop_high.csv"))) if r.returncode == 0 else []
flight = [x for x in high if 0.1 <= float(x["t"]) <= 5.0]
top = [x for x in high if abs(float(x["t"]) - 2.5) < 1e-9]
landed = [x for x in high if 5.0 < float(x["t"]) <= 5.2 and int(float(x["contacts"])) > 0]
check(r.returncode == 0 and len(flight) == 491 and all(int(float(x["contacts"])) == 0 for x in flight)
      and top and float(top[0]["ty"]) > 25.0 and landed and abs(float(landed[0]["theta"])) < 0.05,
      "data/hop_high.wob: in the air from 0.1 s to 5 s, feet above 25 at 2.5 s, lands upright: " + r.stderr.strip())
# bad input: file and line, exit 2, nothing written
out = f"{work}/never.json"
r = run("fit", "pose", *body, "--targets", f"{cli}/bad_target.tgt", "--out", out)
check(r.returncode == 2 and "bad_target.tgt:2: expected a number for y, got 'forty'" in r.stderr,
      "malformed target: exit 2 with file:line: " + r.stderr.strip())
check(not os.path.exists(out), "nothing written for bad input")
r = run("fit", "trajectory", *body, "--reference", f"{data}/table_pose.tgt")
check(r.returncode == 2 and "table_pose.tgt:0: no 'frame' lines" in r.stderr, "a pose file is not a trajectory")
r = run("fit", "pose", *body, "--targets", f"{data}/table_pose.tgt", "--loss", "quadratic")
check(r.returncode == 2 and "--loss" in r.stderr, "unknown loss: exit 2")
sys.exit(1 if failures else 0)
