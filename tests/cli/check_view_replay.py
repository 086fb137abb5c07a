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
    # 1.1: EventName X Y modifiers keycode repeatCount keysym
    for _ in range(10):
        f.write(f"TimerEvent {x} {y} 0 0 0 0\n")
    f.write(f"MouseMoveEvent {x} {y} 0 0 0 0\nLeftButtonPressEvent {x} {y} 0 0 0 0\n"
            f"LeftButtonReleaseEvent {x} {y} 0 0 0 0\n")
    for _ in range(30):
        f.write(f"TimerEvent {x} {y} 0 0 0 0\n")
    # `k` records the pose: the key must reach the viewer (it goes to SESSION_poses.wob)
    f.write(f"KeyPressEvent {x} {y} 0 107 1 k\nCharEvent {x} {y} 0 107 1 k\nKeyReleaseEvent {x} {y} 0 107 1 k\n")
    f.write(f"TimerEvent {x} {y} 0 0 0 0\n")
session = os.path.join(out, "session.wob")
shot = os.path.join(out, "view.png")
view = subprocess.run([wobble, "view", os.path.join(data, "table.obj"), "--modes", os.path.join(data, "table_modes.def"),
                       "--size", "800x500", "--fixed-frame-time", "--play-events", events,
                       "--save-session", session, "--screenshot", shot],
                      capture_output=True, text=True)
print(view.stdout, view.stderr)
assert view.returncode == 0, view.returncode
assert os.path.getsize(shot) > 1000
assert os.path.exists(os.path.join(out, "session_poses.wob")), "the k key line did not reach the viewer"
q_view = [float(v) for v in re.search(r"^t = [^,]*, q = (.*)$", view.stdout, re.M).group(1).split()]
assert abs(q_view[3]) > 0.05, f"the bend did not follow the slider: {q_view}"
run = subprocess.run([wobble, "run", session], capture_output=True, text=True)
print(run.stdout, run.stderr)
assert run.returncode == 0, run.returncode
q_run = [float(v) for v in re.search(r"q = \[([^\]]*)\]", run.stdout).group(1).split()]
worst = max(abs(a - b) for a, b in zip(q_view, q_run))
print("largest difference in q between the viewer and the replay:", worst)
assert len(q_view) == len(q_run) and worst < 1e-9, (q_view, q_run)

# an events file in another layout is refused, naming the line, instead of played in part:
# 1.0's key line (ctrl shift as two values) under `# StreamVersion 1.1`, and an unknown event
for text, line, what in [("# StreamVersion 1.1\nTimerEvent 1 1 0 0 0 0\nKeyPressEvent 10 10 0 0 107 1 k\n", 3,
                          "6 values after the name"),
                         ("TimerEvent 1 1 0 0 0 0 0\nKeyPushEvent 1 1 0 0 107 1 k\n", 2, "not a VTK event")]:
    bad = os.path.join(out, "bad_events.txt")
    open(bad, "w").write(text)
    r = subprocess.run([wobble, "view", os.path.join(data, "table.obj"), "--modes", os.path.join(data, "table_modes.def"),
                        "--size", "800x500", "--fixed-frame-time", "--play-events", bad], capture_output=True, text=True)
    print(r.stderr)
    assert r.returncode == 2 and f"bad_events.txt:{line}:" in r.stderr and what in r.stderr, (r.returncode, r.stderr)
print("events files: the 1.1 layout plays keys; other layouts are refused with FILE:LINE")
