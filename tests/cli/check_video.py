"""`wobble render --what mp4`, checked with FFmpeg's own programs (ffprobe, ffmpeg), which
wobble does not contain: the file is H.264 High in yuv420p with BT.709 tags, its index comes
first (faststart), it has one frame per PNG frame at the run's fps (duration frames / fps),
an odd frame size is padded to even, and every decoded frame shows its PNG frame: the same
picture (PSNR) at the same time (frame k is nearer PNG k than PNG k + 1 while the body moves).
The animated WebP of the same frames is read by Pillow (its own libwebp binding): one frame per
PNG frame at its time (milliseconds), looping, the odd size kept, each frame its PNG frame.
Then Chromium (when installed) plays the MP4: the duration it reports, and its picture after a
seek is the PNG frame of that time. Last, a failed write keeps the earlier video, and names it.

usage: check_video.py WOBBLE DATA_DIR   (exit 77, skipped, without an X display: frames are rendered)
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
import headless_chromium  # noqa: E402

WOBBLE, DATA = sys.argv[1], sys.argv[2]
WIDTH, HEIGHT, FPS, DURATION = 321, 241, 30, 2.0  # odd on purpose: the video is 322 x 242
# H.264 at wobble's CRF 18 with 4:2:0 chroma: the thin saturated lines (the lattice's red dots)
# lose most. Measured worst frame: 37.7 dB at 640x480, 34.2 dB at this small size (denser lines);
# FFmpeg's own pipeline (ffmpeg -vf scale=out_color_matrix=bt709 -c:v libx264 -crf 18) measures
# the same. Wrong range (full read as limited) measures 22.8 dB; a frame shifted by one while
# the table falls, 27.3 dB. (A BT.601/BT.709 mix-up costs under 1 dB on these near-grey
# pictures: the tags are checked above instead.)
MIN_PSNR_DB = 32.0

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, **kw)


def render(out):
    return run([WOBBLE, "render", "--object", f"{DATA}/table.obj", "--modes", f"{DATA}/table_modes.def",
                "--q", "0 50 0 0 0 0 0", "--dt", "0.01", "--duration", str(DURATION), "--ground-slope", "-5",
                "--size", f"{WIDTH}x{HEIGHT}", "--fps", str(FPS), "--what", "frames,mp4,webp", "--out", out])


def rgb_frames(args, width, height):
    """Frames decoded by ffmpeg as 8-bit RGB, cropped to width x height."""
    raw = subprocess.run(["ffmpeg", "-v", "error"] + args +
                         ["-vf", f"format=rgb24,crop={width}:{height}:0:0", "-f", "rawvideo", "-"],
                         capture_output=True, check=True).stdout
    return np.frombuffer(raw, np.uint8).reshape(-1, height, width, 3).astype(np.float64)


def psnr(a, b):
    mse = np.mean((a - b) ** 2)
    return 99.0 if mse == 0 else 10.0 * np.log10(255.0 ** 2 / mse)


if not os.environ.get("DISPLAY"):
    print("no DISPLAY: skipped (run under xvfb-run)")
    sys.exit(77)
for tool in ("ffprobe", "ffmpeg"):
    if shutil.which(tool) is None:
        sys.exit(f"{tool} is missing: `make deps` installs Debian's ffmpeg package")

with tempfile.TemporaryDirectory() as out:
    r = render(out)
    check(r.returncode == 0, f"render --what frames,mp4,webp exits 0 (stderr: {r.stderr.strip()[-300:]})")
    video = os.path.join(out, "table.mp4")
    check(video in r.stdout, "the report names the video")
    pngs = sorted(f for f in os.listdir(os.path.join(out, "frames")) if f.endswith(".png"))
    expected_frames = int(round(DURATION * FPS)) + 1  # t = 0, 1/30, ..., 2
    check(len(pngs) == expected_frames, f"{len(pngs)} PNG frames, {expected_frames} expected")

    probe = json.loads(run(["ffprobe", "-v", "error", "-count_frames", "-print_format", "json", "-show_streams",
                            "-show_format", video]).stdout)
    stream = probe["streams"][0]
    check(stream["codec_name"] == "h264" and stream["profile"] == "High", f"H.264 High: {stream['codec_name']} {stream['profile']}")
    check(stream["pix_fmt"] == "yuv420p", f"pix_fmt {stream['pix_fmt']}")
    check((stream["width"], stream["height"]) == (WIDTH + 1, HEIGHT + 1), f"even size {stream['width']}x{stream['height']}")
    check(stream.get("color_space") == "bt709" and stream.get("color_range") == "tv" and
          stream.get("color_primaries") == "bt709" and stream.get("color_transfer") == "bt709", "tagged BT.709, limited range")
    check(stream["r_frame_rate"] == f"{FPS}/1", f"frame rate {stream['r_frame_rate']}")
    check(int(stream["nb_read_frames"]) == len(pngs), f"{stream['nb_read_frames']} decoded frames, one per PNG frame")
    duration = float(stream["duration"])
    check(abs(duration - len(pngs) / FPS) < 1e-3, f"stream duration {duration} s = {len(pngs)} / {FPS}")

    # faststart: the moov box (the index) before mdat, in the order ffprobe's trace reads them
    trace = run(["ffprobe", "-v", "trace", video]).stderr
    top = [line.split("type:'")[1][:4] for line in trace.splitlines() if "type:'moov'" in line or "type:'mdat'" in line]
    check(top[:2] == ["moov", "mdat"], f"faststart: top-level boxes in order {top[:2]}")

    decoded = rgb_frames(["-i", video], WIDTH, HEIGHT)
    drawn = rgb_frames(["-framerate", str(FPS), "-i", os.path.join(out, "frames", "frame_%04d.png")], WIDTH, HEIGHT)
    check(decoded.shape == drawn.shape, f"decoded {decoded.shape[0]} frames, {drawn.shape[0]} PNG frames")
    same = [psnr(decoded[k], drawn[k]) for k in range(len(drawn))]
    check(min(same) >= MIN_PSNR_DB, f"every frame shows its PNG: PSNR {min(same):.1f} to {max(same):.1f} dB (at least {MIN_PSNR_DB})")
    # while the table falls (the first second) consecutive frames differ: frame k must be its own
    falling = range(0, FPS - 1)
    shifted = [psnr(decoded[k], drawn[k + 1]) for k in falling]
    check(all(same[k] > shifted[k - falling.start] for k in falling),
          f"frame k is PNG k, not k + 1: {np.mean([same[k] for k in falling]):.1f} dB against {np.mean(shifted):.1f} dB")

    # the animated WebP, read by Pillow. Lossy VP8 (4:2:0 as well) at quality 75: measured 35.2 to
    # 36.4 dB at this size, 45.7 to 48.1 dB on the 640x480 table in the clean style
    from PIL import Image
    webp = Image.open(os.path.join(out, "table.webp"))
    check(webp.format == "WEBP" and webp.size == (WIDTH, HEIGHT) and webp.info.get("loop") == 0,
          f"WebP {webp.size}, loop {webp.info.get('loop')} (0: forever)")
    check(webp.n_frames == len(pngs), f"{webp.n_frames} WebP frames, one per PNG frame")
    stamps, webp_psnr, webp_shifted = [], [], []
    for k in range(webp.n_frames):
        webp.seek(k)
        webp.load()
        stamps.append(webp.info["timestamp"])
        pixels = np.asarray(webp.convert("RGB"), np.float64)
        webp_psnr.append(psnr(pixels, drawn[k]))
        if k in falling:
            webp_shifted.append(psnr(pixels, drawn[k + 1]))
    check(all(abs(stamps[k] - 1000.0 * k / FPS) <= 1.0 for k in range(len(stamps))),
          f"WebP frame k at k/{FPS} s to the millisecond: {stamps[:4]} ...")
    check(min(webp_psnr) >= MIN_PSNR_DB, f"every WebP frame shows its PNG: PSNR {min(webp_psnr):.1f} to {max(webp_psnr):.1f} dB")
    check(all(webp_psnr[k] > webp_shifted[k - falling.start] for k in falling),
          f"WebP frame k is PNG k, not k + 1: {np.mean([webp_psnr[k] for k in falling]):.1f} dB against "
          f"{np.mean(webp_shifted):.1f} dB")

    # a real browser: Chromium plays the file from the disk, seeks, and shows the frame of that time
    try:
        browser = headless_chromium.Chromium()
    except headless_chromium.Unavailable as e:
        print(f"skip  in a browser: {e}")
        browser = None
    if browser:
        with open(os.path.join(out, "play.html"), "w") as page:
            page.write('<!doctype html><body style="margin:0"><video id="v" src="table.mp4" muted preload="auto"></video>')
        with browser:
            tab = browser.open("file://" + os.path.join(out, "play.html"))
            seek_frame = 15  # t = 0.5 s, the table still falling
            shown = browser.evaluate(tab, """new Promise((done, fail) => {
                const v = document.getElementById('v');
                v.addEventListener('error', () => fail('video error ' + (v.error && v.error.message)));
                const seek = () => {
                  v.addEventListener('seeked', () => done({duration: v.duration, width: v.videoWidth, height: v.videoHeight}),
                                     {once: true});
                  v.currentTime = %d / %d; };
                if (v.readyState >= 2) seek(); else v.addEventListener('loadeddata', seek, {once: true}); })"""
                                     % (seek_frame, FPS))
            check(abs(shown["duration"] - len(pngs) / FPS) < 1e-3 and (shown["width"], shown["height"]) == (WIDTH + 1, HEIGHT + 1),
                  f"Chromium plays it: {shown}")
            shot = os.path.join(out, "shot.png")
            browser.screenshot(tab, shot)
            seen = rgb_frames(["-i", shot], WIDTH, HEIGHT)[0]
            near = {k: psnr(seen, drawn[k]) for k in (seek_frame - 1, seek_frame, seek_frame + 1)}
            check(near[seek_frame] >= MIN_PSNR_DB and near[seek_frame] == max(near.values()),
                  "Chromium shows frame %d after seeking to %d/%d s: PSNR against PNG frames 14, 15, 16: %s dB"
                  % (seek_frame, seek_frame, FPS, ", ".join(f"{v:.1f}" for v in near.values())))
            errors = browser.console_errors(tab)
            check(not errors, f"no console error in Chromium: {errors}")

    # a failed write: the earlier video is kept and the error names it
    before = open(video, "rb").read()
    os.mkdir(video + ".tmp")  # its temporary file cannot be opened
    r = render(out)
    check(r.returncode != 0 and video in r.stderr, f"a failed write exits {r.returncode} naming the file: {r.stderr.strip()[-200:]}")
    check(open(video, "rb").read() == before, "the earlier video is left as it was")

# a Witkin & Welch scene's `render DIR WHAT` (Fig. 3's sky hook), each word alone: the video at
# the `record` rate, one frame per recorded frame, and the glTF (its bodies' morph targets R_i_j)
with tempfile.TemporaryDirectory() as out:
    script = open(os.path.join(DATA, "fig3_sky_hook.wob")).read().replace("render out/fig3", f"render {out} mp4\nrender {out} gltf")
    path = os.path.join(out, "fig3_sky_hook.wob")
    with open(path, "w") as f:
        f.write(script)
    r = run([WOBBLE, "run", path])
    recorded = [line for line in r.stdout.splitlines() if line.startswith("render: ")]
    check(r.returncode == 0 and recorded, f"the scene's render mp4 and render gltf exit 0: {r.stderr.strip()[-300:]}")
    frames = int(recorded[0].split()[1]) if recorded else -1
    video = os.path.join(out, "fig3_sky_hook.mp4")
    probe = run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                 "stream=nb_read_frames,r_frame_rate,duration", "-of", "csv=p=0", video]).stdout.strip().split(",")
    check(len(probe) == 3 and probe[0] == "30/1" and int(probe[2]) == frames and abs(float(probe[1]) - frames / 30) < 1e-3,
          f"the scene's video: {frames} recorded frames at 30 per second, ffprobe: {probe}")
    glb = open(os.path.join(out, "fig3_sky_hook.glb"), "rb").read()
    gltf = json.loads(glb[20:20 + int.from_bytes(glb[12:16], "little")])
    names = [n for m in gltf["meshes"] for n in m.get("extras", {}).get("targetNames", [])]
    check(len(gltf["meshes"]) >= 2 and "R_0_0" in names, f"the scene's glTF: {len(gltf['meshes'])} bodies, targets {names[:3]} ...")

if failures:
    sys.exit(f"{len(failures)} check(s) failed")
print("video: all checks passed")
