"""`wobble render --what frames,web`: the web preview (OUT/web/, pipelines/web_preview.h) opened
in a real browser, Debian's headless Chromium, from file:// WITHOUT --allow-file-access-from-files
(as a double-click opens it, where fetch/XHR of file:// is refused). The folder holds its own
three.js (copied from libjs-three, nothing from the network) and the .glb; the page loads with no
console error, and at several frames k, window.wobbleSetTime(k / fps) shows the character where
wobble's own PNG frame k shows it: the silhouettes' intersection over union is high for the same
frame and clearly lower for a frame far away in time (so a wrong time or camera fails).
Then the 2D table (an outline of lines, an orthographic camera) the same way. Last, `--what web`
needs no display, and its page (no camera in the file) frames the motion itself.

usage: check_web_preview.py WOBBLE DATA_DIR   (exit 77, skipped, without an X display: frames are rendered)
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import headless_chromium  # noqa: E402

WOBBLE, DATA = sys.argv[1], sys.argv[2]
THREE = "/usr/share/javascript/three"
WIDTH, HEIGHT = 400, 300
# the 3D pot as the Makefile's demo (DEMO3D_ARGS) drops it, for 1 s: it falls, lands at about
# 0.45 s and tips over; --style clean fills it, as the page does
POT = ["--object", "pot3.obj", "--modes", "pot3_modes.def3", "--q", "0 30 0 0.3 0 0.15 0 0 0",
       "--qdot", "0 -60 0 0 1.2 0 0 0 0", "--duration", "1", "--dt", "0.001", "--elevation", "25"]
POT_FPS = 10
# the 2D table as check_video.py drops it, for 4 s: it falls onto the slope at about 3.9 s
TABLE = ["--object", "table.obj", "--modes", "table_modes.def", "--q", "0 50 0 0 0 0 0", "--dt", "0.01",
         "--duration", "4", "--ground-slope", "-5"]
TABLE_FPS = 5
# nine modes of the pot: more morph targets than three.js r111 blends on the GPU (8), so the page
# blends them itself; the generators of data/pot3_modes.def3 and more (an independent set)
NINE_MODES = """dimension 3
""" + "".join(f"mode {name} stiffness 2000000 damping 20000\n  {generator}\n" for name, generator in (
    ("squash", "squash y 0.4"), ("squash_x", "squash x 0.3"), ("sway", "shear y x 60"), ("sway_z", "shear y z 60"),
    ("twist", "twist y 30"), ("bend_x", "bend y x 20"), ("bend_z", "bend y z 20"), ("taper", "taper y 0.3"),
    ("slant", "shear x z 30")))

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def render(args, out, fps, what="frames,web", env=None):
    args = [a if not a.endswith((".obj", ".def", ".def3")) else os.path.join(DATA, a) for a in args]
    return subprocess.run([WOBBLE, "render"] + args + ["--style", "clean", "--size", f"{WIDTH}x{HEIGHT}",
                                                       "--fps", str(fps), "--what", what, "--out", out],
                          capture_output=True, text=True, env=env)


def rgb(png):
    """A PNG as (HEIGHT, WIDTH, 3) floats in [0, 1], decoded by ffmpeg (as check_video.py does)."""
    raw = subprocess.run(["ffmpeg", "-v", "error", "-i", png, "-vf", f"crop={WIDTH}:{HEIGHT}:0:0", "-f", "rawvideo",
                          "-pix_fmt", "rgb24", "-"], capture_output=True, check=True).stdout
    return np.frombuffer(raw, np.uint8).reshape(HEIGHT, WIDTH, 3) / 255.0


def surface_mask(image):
    """The character's filled surface: saturated pixels. wobble's surface colour (0.95, 0.75, 0.35)
    has saturation 0.63 and stays near it when shaded; the white background, the grey-sand ground
    (0.78, 0.74, 0.66: 0.15), the black text overlay and anti-aliased grey edges are below 0.3."""
    high, low = image.max(axis=2), image.min(axis=2)
    return (high > 0.1) & ((high - low) / np.maximum(high, 1e-6) > 0.3)


def line_mask(image):
    """A 2D drawing's lines: dark pixels (wobble's lines are (0.1, 0.1, 0.1); its ground (0.55, 0.47,
    0.38) and white are lighter)."""
    return image.max(axis=2) < 0.35


def without_overlay(mask):
    """wobble's text overlay (title, time, energies: 5 lines from the top left, about 0.19 of the
    height, under 0.45 of the width) left out, of both pictures alike."""
    mask = mask.copy()
    mask[:HEIGHT // 5, :WIDTH * 45 // 100] = False
    return mask


def dilate(mask, r):
    """Pixels within r (a square) of the mask."""
    out = mask.copy()
    padded = np.pad(mask, r)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= padded[r + dy:r + dy + HEIGHT, r + dx:r + dx + WIDTH]
    return out


def lines_agree(page, wobble):
    """How well two line drawings agree, in [0, 1]: WebGL draws lines 1 pixel wide, wobble's clean
    style about 5, so not an IoU but the smaller of two fractions: the page's line pixels within 2
    pixels of wobble's, and wobble's within 3 of the page's (half its width and a pixel)."""
    if not page.any() or not wobble.any():
        return 0.0
    return min(np.count_nonzero(page & dilate(wobble, 2)) / np.count_nonzero(page),
               np.count_nonzero(wobble & dilate(page, 3)) / np.count_nonzero(wobble))


def iou(a, b):
    union = np.count_nonzero(a | b)
    return np.count_nonzero(a & b) / union if union else 0.0


def rgb_of_page(browser, page, path):
    browser.screenshot(page, path)
    return rgb(path)


def open_preview(browser, folder):
    start = time.monotonic()
    page = browser.open("file://" + os.path.join(folder, "web", "index.html"))
    browser.set_viewport(page, WIDTH, HEIGHT)  # the canvas at the frames' size and aspect
    ready = browser.evaluate(page, "window.wobbleReady")
    seconds = time.monotonic() - start
    print(f"      page loaded and ready in {seconds:.2f} s: {ready}")
    return page, ready


def compare(browser, page, folder, fps, frames, mask_of, score, label, shots):
    """score(page's mask at frame k's time, wobble's frame j's mask) for k in frames, every j."""
    browser.evaluate(page, "window.wobbleBare()")  # the picture alone, no title or controls
    pngs = sorted(os.listdir(os.path.join(folder, "frames")))
    wobble_masks = [mask_of(rgb(os.path.join(folder, "frames", png))) for png in pngs]
    table = {}
    for k in frames:
        shown = browser.evaluate(page, f"window.wobbleSetTime({k / fps})")
        check(abs(shown - k / fps) < 1e-9, f"{label}: wobbleSetTime({k / fps}) shows t = {shown}")
        shot = os.path.join(shots, f"{label}_{k:02d}.png")
        browser.screenshot(page, shot)
        page_mask = mask_of(rgb(shot))
        table[k] = [score(page_mask, m) for m in wobble_masks]
        print(f"      {label} page t = {k / fps:.1f} s vs wobble's frames " +
              " ".join(f"{j}:{v:.3f}" for j, v in enumerate(table[k])) + f"  ({np.count_nonzero(page_mask)} px)")
    return table


if not os.environ.get("DISPLAY"):
    print("no DISPLAY: skipped (run under xvfb-run)")
    sys.exit(77)
if shutil.which("ffmpeg") is None:
    sys.exit("ffmpeg is missing: `make deps` installs Debian's ffmpeg package")
if not os.path.exists(os.path.join(THREE, "three.min.js")):
    sys.exit("three.js is missing: `make deps` installs Debian's libjs-three")

with tempfile.TemporaryDirectory() as work:
    shots = os.environ.get("WOBBLE_WEB_SHOTS") or work  # keep the screenshots to look at them
    pot = os.path.join(work, "pot")
    r = render(POT, pot, POT_FPS)
    check(r.returncode == 0, f"render --what frames,web exits 0 (stderr: {r.stderr.strip()[-300:]})")
    web = os.path.join(pot, "web")
    check(f"open {web}/index.html in a browser" in r.stdout, "the report says how to open the page")
    for name in ("index.html", "model.js", "pot3.glb", "three/three.min.js", "three/GLTFLoader.js", "three/OrbitControls.js"):
        check(os.path.isfile(os.path.join(web, name)), f"web/{name} written")
    check(not any(f.endswith(".tmp") for _, _, fs in os.walk(pot) for f in fs), "no temporary file left")
    glb = open(os.path.join(pot, "pot3.glb"), "rb").read()
    check(open(os.path.join(web, "pot3.glb"), "rb").read() == glb, "web asked alone writes OUT/pot3.glb, the same bytes in web/")
    import base64
    model = open(os.path.join(web, "model.js")).read()
    check(base64.b64decode(model.split('"')[1]) == glb, "model.js holds the .glb's bytes (base64)")
    for copied, original in (("three.min.js", "three.min.js"), ("GLTFLoader.js", "examples/js/loaders/GLTFLoader.js"),
                             ("OrbitControls.js", "examples/js/controls/OrbitControls.js")):
        check(open(os.path.join(web, "three", copied), "rb").read() == open(os.path.join(THREE, original), "rb").read(),
              f"three/{copied} is libjs-three's {original}")
    html = open(os.path.join(web, "index.html")).read()
    check("://" not in html.replace("file://", ""), "index.html names nothing on the network")

    # no display: the page and the .glb are written all the same (no frames, so no camera in the file)
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    headless = os.path.join(work, "headless")
    r = render(POT, headless, POT_FPS, what="web", env=env)
    check(r.returncode == 0 and os.path.isfile(os.path.join(headless, "web", "index.html")),
          f"--what web without DISPLAY writes the page (exit {r.returncode}, {r.stderr.strip()[-200:]})")

    try:
        browser = headless_chromium.Chromium(file_access=False)
    except headless_chromium.Unavailable as e:
        sys.exit(str(e) + ": `make deps` installs it")
    with browser:
        page, ready = open_preview(browser, pot)
        check(ready is not None and ready["camera"] and ready["t0"] == 0 and abs(ready["t1"] - 1.0) < 1e-6 and
              ready["cpuMorphs"] == 0,
              f"the page is ready with wobble's camera over t = 0 .. 1 ({ready})")
        # frames across the run: in the air, landing, tipping, at the end
        frames = [0, 3, 6, 10]
        table = compare(browser, page, pot, POT_FPS, frames, surface_mask, iou, "pot", shots)
        # measured (2026-12-07, Debian's Chromium with SwiftShader against VTK 9.1, 400x300): the same
        # frame 0.992 - 0.995 (anti-aliased edges differ); one frame (0.1 s) off at most 0.950, three
        # frames off 0.79 - 0.80, 1 s off 0.49. 0.97 rejects a time one frame off; the far frame must
        # lose by 0.3 (it loses by 0.36 - 0.51), and no frame of the 11 may match better
        for k in frames:
            far = max(frames, key=lambda j: abs(j - k))
            check(table[k][k] > 0.97, f"pot frame {k}: IoU {table[k][k]:.3f} > 0.97 with wobble's frame {k}")
            check(table[k][k] > table[k][far] + 0.3,
                  f"pot frame {k}: IoU {table[k][k]:.3f} well above {table[k][far]:.3f} with the far frame {far}")
            check(max(table[k]) == table[k][k], f"pot frame {k}: its own frame matches best of all {len(table[k])}")
        # what a user does: play (the time label moves on), then drag the view (the orbit controls
        # take the camera: "wobble's camera" unchecked, the picture changes)
        label = "document.getElementById('time').textContent"
        browser.evaluate(page, "window.wobbleBare(false); window.wobbleSetTime(0.1); document.getElementById('play').click()")
        played = browser.evaluate(page, f"new Promise(r => setTimeout(() => r({label}), 400))")
        check(played.startswith("t = ") and float(played.split()[2]) > 0.2, f"play runs the clock: '{played}' after 0.4 s")
        browser.evaluate(page, "window.wobbleSetTime(0.5)")
        before = rgb_of_page(browser, page, os.path.join(shots, "pot_before_drag.png"))
        for kind, x in (("mousePressed", 200), ("mouseMoved", 230), ("mouseMoved", 260), ("mouseReleased", 260)):
            browser._send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": 150, "button": "left",
                                                       "buttons": 0 if kind == "mouseReleased" else 1, "clickCount": 1}, page)
        follows = browser.evaluate(page, "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => "
                                         "r(document.getElementById('follow').checked))))")
        after = rgb_of_page(browser, page, os.path.join(shots, "pot_after_drag.png"))
        moved = iou(surface_mask(before), surface_mask(after))
        check(not follows and moved < 0.9, f"a drag orbits the view (wobble's camera off: {not follows}; IoU {moved:.3f})")

        errors = browser.console_errors(page)
        check(not errors, f"no console error in the 3D page ({errors[:3]})")

        # the same drop with nine modes: blended by the page, as close to wobble's frames (0.993 -
        # 0.995). This guards the page's own blending; it would not catch its absence: r111's GPU
        # path, which drops the smallest of the nine weights, measured the same IoU on this run
        nine_modes = os.path.join(work, "pot3_nine_modes.def3")
        with open(nine_modes, "w") as f:
            f.write(NINE_MODES)
        nine = os.path.join(work, "nine")
        args = [nine_modes if a == "pot3_modes.def3" else a for a in POT]
        args[args.index("--q") + 1] += " 0 0 0 0 0 0"
        args[args.index("--qdot") + 1] += " 0 0 0 0 0 0"
        r = render(args, nine, POT_FPS)
        check(r.returncode == 0, f"nine modes: render exits 0 (stderr: {r.stderr.strip()[-300:]})")
        page, ready = open_preview(browser, nine)
        check(ready is not None and ready["cpuMorphs"] == 1, f"nine modes: the page blends the pot's targets itself ({ready})")
        table = compare(browser, page, nine, POT_FPS, [0, 6, 10], surface_mask, iou, "nine", shots)
        for k in (0, 6, 10):
            check(table[k][k] > 0.97 and max(table[k]) == table[k][k],
                  f"nine modes frame {k}: IoU {table[k][k]:.3f} > 0.97, the best of the run's frames")
        errors = browser.console_errors(page)
        check(not errors, f"no console error in the nine-mode page ({errors[:3]})")

        table_out = os.path.join(work, "table")
        r = render(TABLE, table_out, TABLE_FPS)
        check(r.returncode == 0, f"2D: render --what frames,web exits 0 (stderr: {r.stderr.strip()[-300:]})")
        page, ready = open_preview(browser, table_out)
        frames = [0, 10, 15, 20]  # falling (the top under the overlay at first), at 2, 3 s, landed at 4 s
        table = compare(browser, page, table_out, TABLE_FPS, frames, lambda im: without_overlay(line_mask(im)),
                        lines_agree, "table", shots)
        # measured: the same frame 0.92 (landed, the legs bent by the modes) to 1.00; the table hardly
        # moves in its first 0.2 s (frame 1: 0.994) but 0.2 s off later scores 0.49 - 0.69; the far
        # frame 0.05 - 0.46. Lines drawn without their morph targets (three.js r111's LineBasicMaterial
        # ignores the morphTargets option: the page's first version) scored 0.12 on the landed frame
        for k in frames:
            far = max(frames, key=lambda j: abs(j - k))
            check(table[k][k] > 0.85, f"table frame {k}: lines agree {table[k][k]:.3f} > 0.85 with wobble's frame {k}")
            check(table[k][k] > table[k][far] + 0.3,
                  f"table frame {k}: {table[k][k]:.3f} well above {table[k][far]:.3f} with the far frame {far}")
        errors = browser.console_errors(page)
        check(not errors, f"no console error in the 2D page ({errors[:3]})")

        # the page of the run without a camera frames the motion's box itself: the pot in view,
        # whole (clear of the picture's edges), and not a speck
        page, ready = open_preview(browser, headless)
        check(ready is not None and not ready["camera"], f"without frames the file has no camera ({ready})")
        browser.evaluate(page, "window.wobbleBare(); window.wobbleSetTime(0.5)")
        shot = os.path.join(shots, "pot_own_camera.png")
        browser.screenshot(page, shot)
        mask = surface_mask(rgb(shot))
        edges = mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any()
        check(mask.mean() > 0.02 and not edges, f"own camera: the pot covers {mask.mean():.3f} of the view, edges clear")
        errors = browser.console_errors(page)
        check(not errors, f"no console error in the page without a camera ({errors[:3]})")

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
