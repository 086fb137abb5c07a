"""Batched rollouts: equal, bit for bit, to the same trials stepped one World at a time, on
any number of threads; PD targets held or per step; stopped trials named, not silent."""
import numpy as np
import pytest

import wobble
from conftest import no_ground


def random_states(n, seed=3):
    rng = np.random.default_rng(seed)
    q0 = np.zeros((n, 7))
    q0[:, 0] = rng.uniform(-50, 50, n)
    q0[:, 1] = rng.uniform(120, 220, n)  # clear of the ground at any tilt
    q0[:, 2] = rng.uniform(-0.3, 0.3, n)
    q0[:, 3:] = rng.uniform(-0.05, 0.05, (n, 4))
    qd0 = rng.normal(0, 1, (n, 7)) * np.array([20, 20, 0.5, 0.2, 0.2, 0.2, 0.2])
    return q0, qd0


def stepped_alone(body, options, q0, qd0, steps, every, targets=None):
    world = wobble.World(options)
    world.add_body(body)
    world.set_state(0, q0, qd0)
    qs = [world.q(0)]
    if targets is not None and targets.ndim == 1:
        world.set_mode_targets(0, targets)
    for k in range(steps):
        if targets is not None and targets.ndim == 2:
            world.set_mode_targets(0, targets[k])
        world.step()
        if (k + 1) % every == 0:
            qs.append(world.q(0))
    return np.array(qs)


@pytest.mark.parametrize("integrator", ["thesis", "variational"])
def test_rollout_equals_sequential_worlds_on_any_thread_count(table, integrator):
    options = wobble.WorldOptions(dt=0.01, integrator=integrator)
    q0, qd0 = random_states(6)
    steps, every = 300, 7
    one = wobble.rollout(table, q0, qd0, steps, options=options, every=every, threads=1)
    two = wobble.rollout(table, q0, qd0, steps, options=options, every=every, threads=2)
    assert one.status == ["ok"] * 6
    np.testing.assert_array_equal(one.q, two.q)
    np.testing.assert_array_equal(one.qd, two.qd)
    assert one.q.shape == (6, steps // every + 1, 7)
    np.testing.assert_allclose(one.time, np.arange(steps // every + 1) * every * 0.01, rtol=1e-15)
    for i in range(6):
        np.testing.assert_array_equal(one.q[i], stepped_alone(table, options, q0[i], qd0[i], steps, every))


def test_mode_targets_held_or_per_step(table):
    options = wobble.WorldOptions(dt=0.01)
    q0, qd0 = random_states(3, seed=5)
    held = np.array([[0.1, 0, 0, 0], [0, 0.1, 0, 0], [0, 0, 0.1, -0.1]])
    r = wobble.rollout(table, q0, qd0, 100, options=options, mode_targets=held, threads=2)
    for i in range(3):
        np.testing.assert_array_equal(r.q[i], stepped_alone(table, options, q0[i], qd0[i], 100, 1, held[i]))
    per_step = np.random.default_rng(1).uniform(-0.1, 0.1, (3, 100, 4))
    r = wobble.rollout(table, q0, qd0, 100, options=options, mode_targets=per_step, threads=2)
    for i in range(3):
        np.testing.assert_array_equal(r.q[i], stepped_alone(table, options, q0[i], qd0[i], 100, 1, per_step[i]))


def test_energies_are_the_worlds(table):
    options = no_ground(dt=0.005)
    q0, qd0 = random_states(2)
    r = wobble.rollout(table, q0, qd0, 40, options=options, every=20, energies=True)
    for i in range(2):
        world = wobble.World(options)
        world.add_body(table)
        world.set_state(0, q0[i], qd0[i])
        for k in range(3):
            assert r.energy[i, k] == world.energies(0).total()
            world.step(20)


def test_a_stopped_trial_is_named_and_its_later_samples_are_nan(table):
    q0, qd0 = random_states(2)
    qd0[1, 1] = -1e7  # into the ground at 10⁷ per second: runaway penetration
    r = wobble.rollout(table, q0, qd0, 50, options=wobble.WorldOptions(dt=0.01))
    assert r.status[0] == "ok" and r.steps_taken[0] == 50
    assert r.status[1] != "ok" and r.steps_taken[1] < 50
    assert "step" in r.messages[1]
    k = r.steps_taken[1] + 1
    assert np.all(np.isfinite(r.q[1, :k])) and np.all(np.isnan(r.q[1, k:]))


def test_bad_shapes_and_states_are_input_errors(table):
    with pytest.raises(wobble.InputError, match=r"q0.*\(N, 7\)"):
        wobble.rollout(table, np.zeros((3, 6)), steps=2)
    with pytest.raises(wobble.InputError, match="qd0"):
        wobble.rollout(table, np.zeros((3, 7)), np.zeros((2, 7)), steps=2)
    with pytest.raises(wobble.InputError, match="mode_targets"):
        wobble.rollout(table, np.zeros((3, 7)), steps=2, mode_targets=np.zeros((3, 3)))
    bad = np.zeros((2, 7))
    bad[1, 0] = np.nan
    with pytest.raises(wobble.InputError, match="trial 1.*finite"):
        wobble.rollout(table, bad, steps=2)
    with pytest.raises(wobble.LimitExceeded, match="max_steps"):
        wobble.rollout(table, np.zeros((10, 7)), steps=1000, max_steps=5000)
    one = wobble.rollout(table, np.zeros(7), steps=3)  # one state: N = 1
    assert one.q.shape == (1, 4, 7)
