#!/usr/bin/env python3
"""`wobble view` end to end, headless: play recorded events (a click on the bend slider, timer
ticks) into the viewer with --play-events, write the session with --save-session and a
screenshot, then replay the session with `wobble run` and compare the final q the two print.
Exit 77 (skipped) without an X display."""
import os, re, subprocess, sys

wobble, data, out = sys.argv[1:4]
if not os.environ.get("DISPLAY"):
    print("no DISPLAY: skipped (run under xvfb-run)")
    sys.exit(77)
os.makedirs(out, exist_ok=True)
events = os.path.join(out, "events.txt")
# window 800x500: the bend slider (first of four) spans x in [0.03, 0.24] of the width at
# y = 0.15 of the height; a click at its 3/4 point sets the target to about +0.25
x, y = round((0.03 + 0.75 * 0.21) * 800), round(0.15 * 500)
with open(events, "w") as f:
    f.write("# StreamVersion 1.1\n")
    for _ in range(10):
        f.write(f"TimerEvent {x} {y} 0 0 0 0 0\n")
    f.write(f"MouseMoveEvent {x} {y} 0 0 0 0 0\nLeftButtonPressEvent {x} {y} 0 0 0 0 0\n"
            f"LeftButtonReleaseEvent {x} {y} 0 0 0 0 0\n")
    for _ in range(30):
        f.write(f"TimerEvent {x} {y} 0 0 0 0 0\n")
session = os.path.join(out, "session.wob")
shot = os.path.join(out, "view.png")
view = subprocess.run([wobble, "view", os.path.join(data, "table.obj"), "--modes", os.path.join(data, "table_modes.def"),
                       "--size", "800x500", "--fixed-frame-time", "--play-events", events,
                       "--save-session", session, "--screenshot", shot],
                      capture_output=True, text=True)
print(view.stdout, view.stderr)
assert view.returncode == 0, view.returncode
assert os.path.getsize(shot) > 1000
q_view = [float(v) for v in re.search(r"^t = [^,]*, q = (.*)$", view.stdout, re.M).group(1).split()]
assert abs(q_view[3]) > 0.05, f"the bend did not follow the slider: {q_view}"
run = subprocess.run([wobble, "run", session], capture_output=True, text=True)
print(run.stdout, run.stderr)
assert run.returncode == 0, run.returncode
q_run = [float(v) for v in re.search(r"q = \[([^\]]*)\]", run.stdout).group(1).split()]
worst = max(abs(a - b) for a, b in zip(q_view, q_run))
print("largest difference in q between the viewer and the replay:", worst)
assert len(q_view) == len(q_run) and worst < 1e-9, (q_view, q_run)
