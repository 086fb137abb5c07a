"""Scripts from Python (the same runs as the interpreter's), and motion synthesis: batched
trials equal single ones on any thread count, annealing reproducible from its seed."""
import re

import numpy as np
import pytest

import wobble
from conftest import bounding_table


def test_a_script_run_equals_the_world_from_python(data, table):
    interp = wobble.Interpreter()
    interp.run(f"load_obj table.obj\nload_def table_modes.def\nset dt 0.01\nset_vec q 0 50 0 0 0 0 0\nsimul 2\n", dir=str(data))
    assert interp.time == pytest.approx(2.0)
    world = wobble.World(interp.world_options)
    world.add_body(interp.body)
    world.set_state(0, [0, 50, 0, 0, 0, 0, 0])
    world.step(200)
    np.testing.assert_array_equal(interp.q, world.q(0))
    run = interp.last_run
    assert len(run) > 2
    np.testing.assert_array_equal(run.q()[-1], world.q(0))


def test_trials_in_a_batch_equal_single_trials(data):
    interp = bounding_table(data)
    problem = interp.synthesis_problem()
    graph = interp.pose_graph
    rng = np.random.default_rng(2)
    poses = graph.poses[None] + rng.normal(0, 0.1, (8,) + graph.poses.shape)
    batch = wobble.run_trials(problem, poses, graph.durations, threads=2)
    serial = wobble.run_trials(problem, poses, graph.durations, threads=1)
    np.testing.assert_array_equal(batch.cost, serial.cost)
    graphs = [wobble.PoseGraph(p, graph.durations) for p in poses]
    listed = wobble.run_trials(problem, graphs)
    np.testing.assert_array_equal(listed.cost, batch.cost)
    for i in (0, 5):
        one = problem.run(graphs[i])
        assert one.cost == batch.cost[i] and one.distance == batch.distance[i]
    with pytest.raises(wobble.InputError, match="durations"):
        wobble.run_trials(problem, poses)
    with pytest.raises(wobble.InputError, match="active modes"):
        wobble.run_trials(problem, poses[:, :, :1], graph.durations)


def test_anneal_is_reproducible_and_never_worse_than_its_start(data):
    interp = bounding_table(data)
    problem = interp.synthesis_problem()
    problem.steps = 300  # a short trial: this is about the binding, not the gait
    a = wobble.anneal(problem, interp.pose_graph, seed=7, iterations=4, batch=2, threads=2)
    b = wobble.anneal(problem, interp.pose_graph, seed=7, iterations=4, batch=2, threads=1)
    assert a.best_outcome.cost == b.best_outcome.cost
    np.testing.assert_array_equal(a.best.poses, b.best.poses)
    assert a.best_outcome.cost <= a.initial_outcome.cost
    assert a.history.shape == (5, 7) and a.trials == 9


@pytest.mark.skipif(not hasattr(wobble, "cmaes"), reason="built without pagmo2")
def test_cmaes_is_reproducible_and_never_worse_than_its_start(data):
    interp = bounding_table(data)
    problem = interp.synthesis_problem()
    problem.steps = 300
    a = wobble.cmaes(problem, interp.pose_graph, seed=3, generations=3, population=6)
    b = wobble.cmaes(problem, interp.pose_graph, seed=3, generations=3, population=6)
    assert a.best_outcome.cost == b.best_outcome.cost
    assert a.best_outcome.cost <= a.initial_outcome.cost
    with pytest.raises(wobble.InputError, match="cmaes"):
        wobble.cmaes(problem, interp.pose_graph, population=0)
    with pytest.raises(wobble.LimitExceeded, match="max_steps"):
        wobble.cmaes(problem, interp.pose_graph, generations=100, population=6, max_steps=1000)


def test_a_witkin_welch_scene_runs_and_its_record_reads_back(data, tmp_path):
    # Fig. 3: the sky hook grabs the pyramid's tip and lifts it (data/fig3_sky_hook.wob, its
    # render line replaced by one into tmp_path)
    lines = [l for l in (data / "fig3_sky_hook.wob").read_text().splitlines() if not l.startswith("render")]
    interp = wobble.Interpreter()
    interp.run("\n".join(lines), dir=str(data))
    rec = interp.scene_record
    assert rec is not None and rec.num_bodies >= 2
    assert len(rec) == pytest.approx(6 * 30 + 1, abs=2)  # 6 s at 30 frames a second
    assert np.all(np.isfinite(rec.array))
    assert rec.column("violation").max() < 0.05  # the nails and grabs hold
    if hasattr(wobble, "render"):  # built with the VTK pipelines: the script's render draws
        interp.run(f"render {tmp_path}/fig3 vtp", dir=str(data))
        assert (tmp_path / "fig3" / "vtp").is_dir() and any((tmp_path / "fig3" / "vtp").glob("*.pvd"))
        assert "recorded frames" in interp.take_output()
        with pytest.raises(wobble.ParseError, match="render"):
            interp.run(f"render {tmp_path}/fig3 gif", dir=str(data))
    else:
        with pytest.raises(wobble.ParseError, match="render"):
            interp.run(f"render {tmp_path}/fig3", dir=str(data))


def test_a_script_renders_its_object_runs_from_python(data, tmp_path):
    # `render DIR vtp,disp` of a 3D character's run: the mesh object read by VTK, its .pvd and
    # displacement volumes written as `wobble run` writes them
    if not hasattr(wobble, "render"):
        pytest.skip("built without the VTK pipelines")
    interp = wobble.Interpreter()
    interp.run(f"load_obj pot3.obj\nload_def pot3_modes.def3\nset dt 0.002\nset_vec q 0 50 0 0.2 0 0 0.3 0 0\n"
               f"simul 0.1\nrender {tmp_path}/pot3 vtp,disp\n", dir=str(data))
    written = interp.take_output()
    assert "disp.pvd" in written and (tmp_path / "pot3" / "vti" / "disp.pvd").exists()
    assert any((tmp_path / "pot3" / "vtp").glob("*.pvd"))
    with pytest.raises(wobble.ParseError, match="render: 'gif' is not one of"):
        interp.run(f"render {tmp_path}/pot3 gif", dir=str(data))
    # the NAME=VALUE options are wobble run's, applied the same way (scene/render_options.h):
    # fps=10 over the 0.1 s run writes frames at 0 and 0.1 s where the default 30 writes four
    def frames_in(folder):  # the .pvd's distinct times (a frame has a dataset per part)
        return len({m for p in (folder / "vtp").glob("*.pvd") for m in re.findall(r'timestep="([^"]+)"', p.read_text())})
    assert frames_in(tmp_path / "pot3") == 4
    interp.run(f"render {tmp_path}/pot3_10fps vtp style=clean fps=10", dir=str(data))
    assert frames_in(tmp_path / "pot3_10fps") == 2
    with pytest.raises(wobble.ParseError, match="fps=: must be > 0"):
        interp.run(f"render {tmp_path}/pot3 vtp fps=-1", dir=str(data))
