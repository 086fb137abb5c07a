"""Pictures into numpy and files (pipelines/, VTK under X), and controllers from Python."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

import wobble
from conftest import bounding_table, no_ground

# Skipped only when there is no display to use (DISPLAY unset) or no VTK in the module; with
# DISPLAY set and no X server answering, the render calls raise and the test fails.
needs_display = pytest.mark.skipif(not hasattr(wobble, "render") or not os.environ.get("DISPLAY"),
                                   reason="rendering needs wobble's VTK pipelines and an X display (xvfb-run)")


def dropped(table, seconds=1.0):
    options = wobble.WorldOptions(dt=0.01)
    world = wobble.World(options)
    world.add_body(table)
    world.set_state(0, [0, 30, 0.1, 0.2, 0, 0, 0])
    return world, options, wobble.simulate(world, seconds)


@needs_display
def test_render_world_draws_what_it_is_asked(table):
    world, _, _ = dropped(table)
    image = wobble.render_world(world, width=320, height=200)
    assert image.shape == (200, 320, 3) and image.dtype == np.uint8
    assert image.std() > 5  # not a blank frame
    bare = wobble.render_world(world, width=320, height=200, lattice=False, points=False, overlay=False)
    assert (np.abs(image.astype(int) - bare).sum(axis=2) > 0).mean() > 0.005  # the lattice and points show
    with pytest.raises(wobble.InputError, match="frame"):
        wobble.render_world(world, frame=(0, 0, -1, 1))


@needs_display
def test_render_writes_frames_filmstrip_and_paraview_series(table, tmp_path):
    _, options, run = dropped(table, 1.0)
    files = wobble.render(run, options, str(tmp_path), name="drop", what=["frames", "filmstrip", "vtp"], fps=10,
                          width=320, height=240)
    written = sorted(p.name for p in tmp_path.rglob("*") if p.is_file())
    assert sum(n.endswith(".png") and n.startswith("frame") for n in written) == 11  # 0, 0.1, ..., 1.0 s
    assert any(n.endswith(".pvd") for n in written) and any("filmstrip" in n for n in written)
    assert len(files) >= 3
    with pytest.raises(wobble.InputError, match="what"):
        wobble.render(run, options, str(tmp_path), what=["gif"])


@needs_display
def test_render_writes_a_video_ffprobe_reads(table, tmp_path):
    _, options, run = dropped(table, 1.0)
    files = wobble.render(run, options, str(tmp_path), name="drop", what=["mp4"], fps=10, width=320, height=240)
    video = tmp_path / "drop.mp4"
    assert any(str(video) in f for f in files)
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                            "stream=codec_name,nb_read_frames,width,height", "-of", "csv=p=0", str(video)],
                           capture_output=True, text=True, check=True).stdout.strip()
    assert probe == "h264,320,240,11"  # 0, 0.1, ..., 1.0 s


def test_render_writes_a_gltf_without_a_display(table, tmp_path):
    # issue 48: "gltf" needs no display; the .glb holds the table (a 2D FFD body) keyed per frame
    _, options, run = dropped(table, 1.0)
    files = wobble.render(run, options, str(tmp_path), name="drop", what=["gltf"], fps=10)
    assert files == [str(tmp_path / "drop.glb")]
    raw = (tmp_path / "drop.glb").read_bytes()
    assert raw[:4] == b"glTF" and int.from_bytes(raw[8:12], "little") == len(raw)


def test_render_writes_a_web_preview_without_a_display(table, tmp_path):
    # issue 48: "web" (the page in folder/web/) needs no display, and brings the .glb with it
    _, options, run = dropped(table, 1.0)
    files = wobble.render(run, options, str(tmp_path), name="drop", what=["web"], fps=10)
    assert files == [str(tmp_path / "drop.glb"), str(tmp_path / "web") + "/"]
    web = tmp_path / "web"
    assert (web / "drop.glb").read_bytes() == (tmp_path / "drop.glb").read_bytes()
    assert "three/GLTFLoader.js" in (web / "index.html").read_text()
    assert (web / "model.js").read_text().startswith("window.wobbleGlbBase64")


def test_a_pose_graph_controller_drives_the_active_modes(data):
    interp = bounding_table(data)
    problem, graph = interp.synthesis_problem(), interp.pose_graph
    world = wobble.World(problem.options)
    world.add_body(problem.body)
    world.set_state(0, problem.q0, problem.qd0)
    masses = problem.body.masses

    def centre_x():  # the direct per-point sum Σ m_k x_k / m, not the mass moments
        return float(masses @ world.point_positions(0)[:, 0] / masses.sum())

    x0 = centre_x()
    controller = wobble.PoseGraphController(world, 0, graph)
    world.add_controller(controller)
    world.step(problem.steps)
    # the same trial as the synthesis' own: the same travel of the centre of mass
    outcome = problem.run(graph)
    assert outcome.ok
    assert centre_x() - x0 == pytest.approx(outcome.distance, rel=1e-9, abs=1e-9)
    assert controller.steps == problem.steps and 0 <= controller.pose < len(graph.durations)
    with pytest.raises(wobble.InputError, match="pose graph"):
        wobble.PoseGraphController(world, 0, wobble.PoseGraph(np.zeros((2, 1)), [0.5, 0.5]))


def test_keyframes_hold_a_foot_and_hand_over_to_the_simulation(table):
    world = wobble.World(wobble.WorldOptions(dt=0.01))
    world.add_body(table)
    world.set_state(0, [0, 0, 0, 0, 0, 0, 0])
    foot = world.point_positions(0)[5].copy()  # mass point 5: the left foot, lattice (0, 0)
    keys = wobble.KeyframeController(world, 0, [0.0, 0.5, 1.0], [[0, 0, 0, 0], [0, 0, 0.4, 0], [0, 0, 0, 0]],
                                     hold=[0.0, 0.0])
    world.add_controller(keys)
    world.step(25)  # halfway up the squash: γ_vsquash = 0.2, the foot where it was
    assert world.q(0)[5] == pytest.approx(0.2, abs=1e-12)
    np.testing.assert_allclose(world.point_positions(0)[5], foot, atol=1e-9)
    world.step(75)
    assert keys.finished()
    keys.release(world)
    world.remove_controller(keys)
    world.step(10)  # simulated again
    with pytest.raises(wobble.InputError, match="keyframes"):
        wobble.KeyframeController(world, 0, [0.0, 0.5], [[0, 0, 0, 0]])


def test_a_controller_written_in_python_runs_around_every_step(table):
    # a PD target that follows a sine, set before every step by Python: the same run as setting
    # it by hand between single steps; after_step sees every accepted step's time
    def target(t):
        return np.array([0.3 * np.sin(4 * t), 0, 0, 0])

    class Sine(wobble.Controller):
        def __init__(self):
            super().__init__()
            self.times = []

        def before_step(self, world):
            world.set_mode_targets(0, target(world.time))

        def after_step(self, world):
            self.times.append(world.time)

    def start():
        world = wobble.World(no_ground("thesis", 0.005))
        world.add_body(table)
        world.set_state(0, [0, 100, 0.1, 0, 0, 0, 0])
        return world

    driven, by_hand = start(), start()
    sine = Sine()
    driven.add_controller(sine)
    driven.step(200)
    for _ in range(200):
        by_hand.set_mode_targets(0, target(by_hand.time))
        by_hand.step(1)
    assert np.array_equal(driven.q(0), by_hand.q(0)) and np.array_equal(driven.qd(0), by_hand.qd(0))
    assert sine.times == pytest.approx([0.005 * (k + 1) for k in range(200)], abs=1e-12)
    assert abs(driven.q(0)[3]) > 1e-3  # the bend was driven

    class Broken(wobble.Controller):
        def before_step(self, world):
            raise KeyError("from Python")

    driven.add_controller(Broken())
    with pytest.raises(KeyError, match="from Python"):
        driven.step(1)
