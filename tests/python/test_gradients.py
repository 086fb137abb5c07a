"""Gradients through whole rollouts and spacetime fits from Python (issue 18): the adjoint
gradient against central differences, a stage cost written in Python against the built-in one,
and a hop found by a spacetime fit, written as a schedule and played by a script."""
import numpy as np
import pytest

import wobble
from conftest import DATA


def air_problem(table):
    options = wobble.WorldOptions(dt=0.01)
    options.ground.enabled = False
    rng = np.random.default_rng(3)
    D, steps = table.num_modes, 30
    targets = 0.05 * rng.standard_normal((D, steps))
    q0 = np.concatenate([[0.0, 100.0, 0.1], 0.02 * rng.standard_normal(D)])
    qd0 = np.concatenate([[3.0, 1.0, 0.2], 0.1 * rng.standard_normal(D)])
    cost = (wobble.centre_of_mass_at(table, steps, [120.0, 80.0], weight=1e-3)
            + wobble.upright_at(steps, weight=10.0, time_scale=0.1) + wobble.still_at(15, weight=1e-4))
    return dict(targets=targets, options=options, q0=q0, qd0=qd0), cost


def test_rollout_gradient_matches_central_differences(table):
    kw, cost = air_problem(table)
    g = wobble.rollout_gradient(table, cost, **kw)
    assert g.ok and g.cost == pytest.approx(wobble.rollout_cost(table, cost, **kw), rel=1e-14)
    assert g.targets.shape == kw["targets"].shape

    def central(name, index, h):
        plus = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in kw.items()}
        minus = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in kw.items()}
        plus[name][index] += h
        minus[name][index] -= h
        return (wobble.rollout_cost(table, cost, **plus) - wobble.rollout_cost(table, cost, **minus)) / (2 * h)

    # h = 1e-4: the cost is about 6 and these derivatives 1e-5 to 1e-3, so below h = 1e-5 the
    # differences are round-off (1e-3 off at h = 1e-6); at 1e-4 the truncation error is ~1e-9
    for d, n in [(0, 0), (1, 7), (2, 29), (3, 15)]:
        assert g.targets[d, n] == pytest.approx(central("targets", (d, n), 1e-4), rel=1e-5)
    for i in [1, 2, 4]:
        assert g.q0[i] == pytest.approx(central("q0", i, 1e-4), rel=1e-5)
        assert g.qd0[i] == pytest.approx(central("qd0", i, 1e-4), rel=1e-5)


def test_a_stage_cost_written_in_python_is_the_built_in_one(table):
    kw, _ = air_problem(table)
    w = 2e-3

    def still_at_15(n, q, qd):  # w/2 |qd|² at step 15, as wobble.still_at
        if n != 15:
            return 0.0, None, None
        return 0.5 * w * qd @ qd, None, w * qd

    built_in = wobble.rollout_gradient(table, wobble.still_at(15, weight=w), **kw)
    mine = wobble.rollout_gradient(table, wobble.StageCost(still_at_15), **kw)
    assert mine.cost == pytest.approx(built_in.cost, rel=1e-13)
    np.testing.assert_allclose(mine.targets, built_in.targets, rtol=1e-10, atol=1e-14 * np.abs(built_in.targets).max())
    np.testing.assert_allclose(mine.qd0, built_in.qd0, rtol=1e-10)
    with pytest.raises(wobble.InputError, match="dqd"):
        wobble.rollout_gradient(table, wobble.StageCost(lambda n, q, qd: (0.0, None, np.zeros(2))), **kw)


def test_a_spacetime_hop_played_by_a_script(tmp_path):
    # data/hop.wob's table and ground: the centre of mass 2 above rest at 0.7 s, upright at 1 s
    body = wobble.load_body(str(DATA / "table.obj"), [str(DATA / "hop_modes.def")])
    options = wobble.WorldOptions(dt=0.01)
    g = options.ground
    g.stiffness, g.normal_damping, g.friction_damping, g.friction_cap = 45000, 3000, 3000, 0.5
    rest = np.sqrt(wobble.centre_of_mass_at(body, 0, [0, 0], weight=2.0, axes="y")(0, np.zeros(7), np.zeros(7))[0])
    task = (wobble.centre_of_mass_at(body, 70, [0, rest + 2], weight=2e3, axes="y")
            + wobble.upright_at(100, weight=2e3, time_scale=0.1))
    r = wobble.fit_spacetime(body, task, targets=np.zeros((4, 100)), knots=21, bound=0.3, options=options)
    assert r.ok and r.cost < 1e-2 * r.initial_cost, r.message
    assert r.targets.shape == (4, 100) and np.abs(r.targets).max() <= 0.3
    schedule = tmp_path / "hop.csv"
    wobble.write_target_schedule(str(schedule), [m.name for m in body.modes], 0.01, r.targets)
    np.testing.assert_array_equal(wobble.read_target_schedule(str(schedule), [m.name for m in body.modes], 0.01),
                                  r.targets)
    interp = wobble.Interpreter()
    interp.run(f"load_obj table.obj\nload_def hop_modes.def\nset integrator thesis\nset dt 0.01\nset grconst 45000\n"
               f"set grdam 3000\nset frconst 3000\nset frsin 0.5\nschedule {schedule}\nsimul 2.5\n", dir=str(DATA))
    run = interp.last_run
    t, contacts = run.array[:, run.columns.index("t")], run.array[:, run.columns.index("contacts")]
    at = lambda time: int(np.argmin(np.abs(t - time)))
    q = run.array[at(0.7), [run.columns.index(c) for c in ("tx", "ty", "theta", "bend", "shear", "vsquash", "hsquash")]]
    miss = np.sqrt(wobble.centre_of_mass_at(body, 70, [0, rest + 2], weight=2.0, axes="y")(70, q, np.zeros(7))[0])
    assert contacts[at(0.7)] == 0 and miss < 0.05  # in the air, the centre of mass where the task wants it
    assert contacts[at(2.5)] > 0                    # and down again (the task ends at 1 s; it lands at 2.45 s)


def test_multi_start_with_a_python_stage_cost_on_two_threads(table):
    # the starts run on two threads, each taking the GIL for the Python term's calls; the fit is
    # the one the built-in term gives on one thread
    kw, cost = air_problem(table)
    w = 2e-3

    def still_at_15(n, q, qd):
        if n != 15:
            return 0.0, None, None
        return 0.5 * w * qd @ qd, None, w * qd

    common = dict(knots=6, bound=0.3, max_iterations=15, starts=3, seed=7, **kw)
    mine = wobble.fit_spacetime(table, cost + wobble.StageCost(still_at_15), threads=2, **common)
    built_in = wobble.fit_spacetime(table, cost + wobble.still_at(15, weight=w), threads=1, **common)
    assert mine.ok and built_in.ok
    assert len(mine.start_costs) == 3 and mine.cost == min(mine.start_costs) == mine.start_costs[mine.best_start]
    assert mine.best_start == built_in.best_start
    np.testing.assert_allclose(mine.start_costs, built_in.start_costs, rtol=1e-8)
    np.testing.assert_allclose(mine.knots, built_in.knots, rtol=1e-6, atol=1e-9)
    with pytest.raises(wobble.InputError, match="starts"):
        wobble.fit_spacetime(table, cost, starts=0, **{k: v for k, v in common.items() if k != "starts"})
