"""Gradients through whole 3D rollouts and 3D spacetime fits from Python (issue 18; the same
functions as the 2D body's, given a 3D BodyModel): the adjoint
gradient against central differences of the plain cost in the numbers Python passes (q0 with
its rotation vector, qd0, targets, gains), stage costs written in Python, and a fit."""
import numpy as np
import pytest

import wobble
from conftest import DATA, no_ground


@pytest.fixture(scope="module")
def pot3():
    return wobble.load_body(str(DATA / "pot3.obj"), [str(DATA / "pot3_modes.def3")])


def air_problem(pot3, integrator="thesis"):
    options = no_ground(integrator=integrator)
    rng = np.random.default_rng(5)
    D, steps = pot3.num_modes, 25
    targets = 0.05 * rng.standard_normal((D, steps))
    q0 = np.concatenate([[10.0, 100.0, -5.0, 0.4, -0.3, 0.6], 0.03 * rng.standard_normal(D)])
    qd0 = np.concatenate([[30.0, 20.0, -10.0, 0.5, 1.0, -0.7], 0.2 * rng.standard_normal(D)])
    cost = (wobble.centre_of_mass_at(pot3, steps, [30.0, 110.0, 0.0], weight=1e-3)
            + wobble.upright_at(steps, weight=10.0, time_scale=0.1) + wobble.still_at(12, weight=1e-3))
    return dict(targets=targets, options=options, q0=q0, qd0=qd0), cost


def central(pot3, cost, kw, name, index, h):
    plus = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in kw.items()}
    minus = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in kw.items()}
    plus[name][index] += h
    minus[name][index] -= h
    return (wobble.rollout_cost(pot3, cost, **plus) - wobble.rollout_cost(pot3, cost, **minus)) / (2 * h)


@pytest.mark.parametrize("integrator", ["thesis", "symplectic"])
def test_rollout_gradient3_matches_central_differences(pot3, integrator):
    kw, cost = air_problem(pot3, integrator)
    g = wobble.rollout_gradient(pot3, cost, **kw)
    assert g.ok, g.message
    assert g.cost == pytest.approx(wobble.rollout_cost(pot3, cost, **kw), rel=1e-14)
    assert g.targets.shape == kw["targets"].shape
    # every start coordinate, the rotation vector's three included (q0[3:6])
    for i in range(len(kw["q0"])):
        assert g.q0[i] == pytest.approx(central(pot3, cost, kw, "q0", i, 1e-5), rel=1e-5, abs=1e-9), f"q0[{i}]"
        assert g.qd0[i] == pytest.approx(central(pot3, cost, kw, "qd0", i, 1e-5), rel=1e-5, abs=1e-9), f"qd0[{i}]"
    for d, n in [(0, 0), (1, 11), (2, 24)]:
        assert g.targets[d, n] == pytest.approx(central(pot3, cost, kw, "targets", (d, n), 1e-5), rel=1e-5, abs=1e-9)
    stiffness = np.array([2.5e6, 2.0e6, 1.5e6])  # given in place of the body's own
    kw["stiffness"] = stiffness
    g_K = wobble.rollout_gradient(pot3, cost, **kw)
    assert g_K.stiffness[1] == pytest.approx(central(pot3, cost, kw, "stiffness", 1, 1e-6 * stiffness[1]),
                                             rel=1e-4)


def test_stage_costs_written_in_python_meet_the_rotation_vector(pot3):
    kw, _ = air_problem(pot3)
    theta_goal = np.array([0.1, 0.2, -0.3])
    w = 2.0

    def turned_to(n, q, qd):  # w/2 |Θ − Θ*|² at the last step, in World.q3's rotation vector
        if n != 25:
            return 0.0, None, None
        dq = np.zeros_like(q)
        dq[3:6] = w * (q[3:6] - theta_goal)
        return 0.5 * w * (q[3:6] - theta_goal) @ (q[3:6] - theta_goal), dq, None

    cost = wobble.StageCost(turned_to)
    g = wobble.rollout_gradient(pot3, cost, **kw)
    assert g.ok, g.message
    for i in [3, 4, 5, 6]:
        assert g.q0[i] == pytest.approx(central(pot3, cost, kw, "q0", i, 1e-5), rel=1e-5), f"q0[{i}]"
    # a built-in term called from Python gives its gradient in q coordinates too
    q, qd = kw["q0"], kw["qd0"]
    value, dq, dqd = wobble.upright_at(0, weight=3.0, time_scale=0.2)(0, q, qd, dim=3)
    for i in range(3, 6):
        step = np.zeros_like(q)
        step[i] = 1e-6
        cd = (wobble.upright_at(0, weight=3.0, time_scale=0.2)(0, q + step, qd, dim=3)[0]
              - wobble.upright_at(0, weight=3.0, time_scale=0.2)(0, q - step, qd, dim=3)[0]) / 2e-6
        assert dq[i] == pytest.approx(cd, rel=1e-6)
    assert dqd[3:6] == pytest.approx(3.0 * 0.04 * qd[3:6], rel=1e-12)

    with pytest.raises(wobble.InputError, match="dq"):
        wobble.rollout_cost(pot3, wobble.StageCost(lambda n, q, qd: (1.0, np.zeros(2), None)), **kw)


def test_fit_spacetime3_reaches_a_squash_in_the_air(pot3):
    options = no_ground(integrator="symplectic", gravity=False)
    D, steps = pot3.num_modes, 60
    goal = 0.15

    def squashed(n, q, qd):
        if n != steps:
            return 0.0, None, None
        dq = np.zeros_like(q)
        dq[6] = 1e4 * (q[6] - goal)
        return 0.5e4 * (q[6] - goal) ** 2, dq, None

    r = wobble.fit_spacetime(pot3, wobble.StageCost(squashed) + wobble.still_at(steps, weight=1e2),
                              targets=np.zeros((D, steps)), knots=7, bound=0.5, control_weight=1e-3,
                              options=options, max_iterations=60)
    assert r.ok, r.message
    assert r.targets.shape == (D, steps)
    assert np.abs(r.targets).max() <= 0.5
    assert r.cost < 1e-2 * r.initial_cost
    end = {}

    def record(n, q, qd):
        if n == steps:
            end["squash"] = q[6]
        return 0.0, None, None

    wobble.rollout_cost(pot3, wobble.StageCost(record), targets=r.targets, options=options)
    assert end["squash"] == pytest.approx(goal, abs=5e-3)


def test_bad_input_names_the_problem(pot3):
    kw, cost = air_problem(pot3)
    with pytest.raises(wobble.InputError, match="targets"):
        wobble.rollout_gradient(pot3, cost, **{**kw, "targets": np.zeros((2, 5))})
    with pytest.raises(wobble.InputError, match="axes"):
        wobble.centre_of_mass_at(pot3, 1, [0, 0, 0], axes="xw")
    with pytest.raises(wobble.InputError, match="integrator"):
        wobble.rollout_gradient(pot3, cost, **{**kw, "options": no_ground(integrator="rk4")})
    with pytest.raises(wobble.InputError, match="weight"):
        wobble.still_at(3, weight=-1.0)
