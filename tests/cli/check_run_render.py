#!/usr/bin/env python3
# `wobble run` draws a script's runs with `render` through the same driver as `wobble render`:
# a keyframed half second and a simulated half second become 31 frames (30 fps over 1 s) of
# the ParaView series, with the keyframed and simulated states in order. Without a display only
# vtp/disp are written (with a message); with one (make test runs under Xvfb) also PNG frames.
import os, re, shutil, subprocess, sys

wobble, data, work = sys.argv[1:4]
shutil.rmtree(os.path.join(work, "pics"), ignore_errors=True)  # frames of a run with a display
os.makedirs(work, exist_ok=True)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


script = f"""load_obj {data}/table.obj
load_def {data}/bend.def {data}/shear.def
assign bend 4000000 1000000
assign shear 4000000 1000000
set_vec q 0 50 0 0 0
key 0
key 0.5 bend=0.1 shear=0.1
keyframe
simul 0.5
render pics vtp,frames
"""
path = os.path.join(work, "render.wob")
open(path, "w").write(script)
env = dict(os.environ)
has_display = bool(env.get("DISPLAY"))
r = subprocess.run([wobble, "run", path], capture_output=True, text=True, cwd=work, env=env)
check(r.returncode == 0, "wobble run with render exits 0: " + r.stderr.strip())
pvd = os.path.join(work, "pics", "vtp", "table.pvd")
check(os.path.exists(pvd), "the ParaView series is written")
if os.path.exists(pvd):
    times = sorted({float(t) for t in re.findall(r'timestep="([^"]+)"', open(pvd).read())})
    check(len(times) == 31 and abs(times[0]) < 1e-12 and abs(times[-1] - 1.0) < 1e-9,
          f"31 frames from t = 0 to 1 (keyframes, then simulation): {len(times)} from {times[:1]} to {times[-1:]}")
png = os.path.join(work, "pics", "frames", "frame_0030.png")
if has_display:
    check(os.path.exists(png), "with a display the PNG frames are written too")
else:
    check("no X display" in r.stdout and not os.path.exists(png), "without a display: a message, vtp only")
r = subprocess.run([wobble, "run", path], capture_output=True, text=True, cwd=work,
                   env={k: v for k, v in env.items() if k != "DISPLAY"})
check(r.returncode == 0 and "no X display: render draws no pictures" in r.stdout and "writing vtp only" in r.stdout,
      "without DISPLAY: the pictures are skipped with a message: " + r.stdout.strip()[-200:])
# a render option with a bad value: exit 2, the script's file and line, what was expected
bad = os.path.join(work, "bad_render.wob")
open(bad, "w").write(script.replace("render pics vtp,frames", "render pics vtp exr-terrain=maybe"))
r = subprocess.run([wobble, "run", bad], capture_output=True, text=True, cwd=work, env=env)
check(r.returncode == 2 and "bad_render.wob:10:" in r.stderr and "exr-terrain=: expected on or off" in r.stderr,
      "exr-terrain=maybe exits 2 naming the line: " + r.stderr.strip()[-200:])
# a 3D object on a heightfield (`--heightfield`): the .pvd lists the heightfield as its terrain
# part, one file of the grid's triangles; a bad heightfield file: exit 2 with its FILE:LINE
hf_out = os.path.join(work, "hills")
shutil.rmtree(hf_out, ignore_errors=True)
r = subprocess.run([wobble, "render", "--object", f"{data}/pot3.obj", "--modes", f"{data}/pot3_modes.def3",
                    "--heightfield", f"{data}/hills.heightfield", "--q", "-250 160 0 0 0 0 0 0 0", "--dt", "0.001",
                    "--ground-stiffness", "20000", "--duration", "0.2", "--what", "vtp", "--out", hf_out],
                   capture_output=True, text=True, cwd=work, env=env)
pvd = os.path.join(hf_out, "vtp", "pot3.pvd")
text = open(pvd).read() if os.path.exists(pvd) else ""
terrain_files = set(re.findall(r'name="terrain" file="([^"]*)"', text))
check(r.returncode == 0 and len(terrain_files) == 1, f"--heightfield: one terrain file in the .pvd {terrain_files} " + r.stderr)
vtp = os.path.join(hf_out, "vtp", next(iter(terrain_files))) if terrain_files else ""
body = open(vtp, "rb").read().decode("latin-1") if vtp and os.path.exists(vtp) else ""  # appended binary data
check('NumberOfPoints="651"' in body and 'NumberOfPolys="1200"' in body,
      "the terrain part is the 31 x 21 grid's 1200 triangles")
# the 3D follow camera (--camera follow): the filmstrip draws, and its panels differ from the
# whole-run camera's (the cube about the pot, not the motion's box)
if has_display:
    strips = {}
    for camera in ("whole", "follow"):
        out = os.path.join(work, "hills_" + camera)
        shutil.rmtree(out, ignore_errors=True)
        r = subprocess.run([wobble, "render", "--object", f"{data}/pot3.obj", "--modes", f"{data}/pot3_modes.def3",
                            "--heightfield", f"{data}/hills.heightfield", "--q", "-250 160 0 0 0 0 0 0 0", "--qdot",
                            "20 0 0 0 0 0 0 0 0", "--dt", "0.001", "--ground-stiffness", "20000", "--duration", "1",
                            "--camera", camera, "--what", "filmstrip", "--out", out], capture_output=True, text=True,
                           cwd=work, env=env)
        png = os.path.join(out, "filmstrip.png")
        strips[camera] = open(png, "rb").read() if r.returncode == 0 and os.path.exists(png) else b""
    check(strips["whole"] and strips["follow"] and strips["whole"] != strips["follow"],
          "--camera follow in 3D draws its own framing")
bad_field = os.path.join(work, "bad.heightfield")
open(bad_field, "w").write("origin 0 0\nspacing 1 1\n1,2,3\n1,x,3\n")
r = subprocess.run([wobble, "render", "--object", f"{data}/pot3.obj", "--modes", f"{data}/pot3_modes.def3",
                    "--heightfield", bad_field, "--duration", "0.1", "--what", "vtp", "--out", hf_out],
                   capture_output=True, text=True, cwd=work, env=env)
check(r.returncode == 2 and "bad.heightfield:4: expected a height, got 'x'" in r.stderr,
      "a bad heightfield file: exit 2 naming its line: " + r.stderr.strip())
# --terrain-face: a segment's own constant is that constant on that face. The table slides on
# segment 1 only, so "1 frsin 0.05" runs bit for bit as --friction-cap 0.05 everywhere, and
# an override of segment 2 (never touched) changes nothing; bad specs exit 2 saying why
def slide(*flags):
    out = os.path.join(work, "slide.csv")
    r = subprocess.run([wobble, "simulate", "--object", f"{data}/table.obj", "--modes", f"{data}/bend.def",
                        "--terrain", "-400 0 0 0 400 -231", "--q", "-250 0.2 0 0", "--qdot", "20 0 0 0",
                        "--duration", "3", "--out", out, *flags], capture_output=True, text=True, cwd=work)
    return r, (open(out).read() if r.returncode == 0 else "")
_, icy_face = slide("--friction-cap", "1", "--terrain-face", "1 frsin 0.05")
_, icy_all = slide("--friction-cap", "0.05")
_, grippy = slide("--friction-cap", "1")
_, other_face = slide("--friction-cap", "1", "--terrain-face", "2 frsin 0.05 grdam 10")
check(icy_face and icy_face == icy_all and grippy == other_face and grippy != icy_face,
      "--terrain-face: segment 1's own cap is that cap on segment 1; segment 2's changes nothing there")
for spec, why in [("5 frsin 0.05", "expected a segment from 1 to 2, got '5'"),
                  ("1 frsn 0.05", "expected grconst, grdam, frconst or frsin, got 'frsn'"),
                  ("1 frsin -1", "expected a number >= 0 for frsin, got '-1'"), ("1 frsin", "expected SEGMENT NAME VALUE")]:
    r, _ = slide("--terrain-face", spec)
    check(r.returncode == 2 and why in r.stderr, f"--terrain-face \"{spec}\": exit 2, {why}: " + r.stderr.strip())
sys.exit(1 if failures else 0)
