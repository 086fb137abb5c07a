#!/usr/bin/env python3
"""`wobble view` of a synthesis script (issue 19): the viewer does not anneal again unless asked.
With the result an earlier `wobble run` saved (the script's `save FILE` after its anneal) it
opens that and plays exactly what viewing the saved script plays; without one it skips the
anneal and that `save`, and says so; --anneal searches here. Exit 77 without an X display."""
import os, re, subprocess, sys

wobble, data, out = sys.argv[1:4]
if not os.environ.get("DISPLAY"):
    print("no DISPLAY: skipped (run under xvfb-run)")
    sys.exit(77)
os.makedirs(out, exist_ok=True)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


saved = os.path.join(out, "best.wob")
if os.path.exists(saved):
    os.remove(saved)
script = os.path.join(out, "gait.wob")
with open(script, "w") as f:
    f.write(f"load_obj {data}/table.obj\nload_def {data}/table_modes.def\n"
            "assign bend 40000000 4000000\nassign shear 40000000 4000000\nset integrator thesis\nset dt 0.01\n"
            "set grconst 45000\nset grdam 3000\nset frconst 3000\nset frsin 0.5\nset_vec q 0 0 0 0 0 0 0\n"
            "pose 0.1 0 0.4\npose 0 -0.1 0.4\npose -0.1 0 0.4\npose 0 0.1 0.4\n"
            "set trial_steps 300\nset seed 4\nset batch 2\n"
            f"anneal 3\nsave {saved}\nsimul 2\n")


def view(path, *extra):
    return subprocess.run([wobble, "view", path, "--frames", "10", "--fixed-frame-time", "--no-charts", *extra],
                          capture_output=True, text=True, cwd=out)


def final_q(r):
    m = re.search(r"^t = .*$", r.stdout, re.M)
    return m.group(0) if m else None


r = view(script)
check(r.returncode == 0 and "anneal skipped, the pose graph as written" in r.stdout and not os.path.exists(saved),
      "no saved result: the anneal and its save are skipped, nothing is written: " + r.stdout[:300] + r.stderr)
as_written = final_q(r)
r = subprocess.run([wobble, "run", script], capture_output=True, text=True, cwd=out)
check(r.returncode == 0 and os.path.exists(saved), "wobble run anneals and saves the result: " + r.stderr)
r = view(script)
check(r.returncode == 0 and "opens the result an earlier run saved" in r.stdout,
      "with the saved result the viewer opens it: " + r.stdout[:300] + r.stderr)
r_saved = view(saved)
check(final_q(r) is not None and final_q(r) == final_q(r_saved),
      f"it plays what viewing the saved script plays: {final_q(r)} vs {final_q(r_saved)}")
r = view(script, "--anneal")
check(r.returncode == 0 and "anneal:" in r.stdout and "opens the result" not in r.stdout,
      "--anneal searches in the viewer: " + r.stdout[-300:] + r.stderr)
print("as written:", as_written)
sys.exit(1 if failures else 0)
