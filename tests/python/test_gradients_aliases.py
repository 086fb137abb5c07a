"""The gradient functions take either body (issue 45): the 3D-suffixed names of before stay one
release as aliases that warn (DeprecationWarning) and give what the new names give; a stage
cost of one body's dimension is refused with the other's body by name."""
import warnings

import numpy as np
import pytest

import wobble
from conftest import DATA, no_ground


@pytest.fixture(scope="module")
def pot3():
    return wobble.load_body3(str(DATA / "pot3.obj"), [str(DATA / "pot3_modes.def3")])


def problem(pot3):
    rng = np.random.default_rng(11)
    D, steps = pot3.num_modes, 12
    kw = dict(targets=0.05 * rng.standard_normal((D, steps)), options=no_ground(),
              q0=np.concatenate([[1.0, 90.0, -2.0, 0.2, -0.1, 0.3], 0.02 * rng.standard_normal(D)]),
              qd0=np.concatenate([[10.0, 5.0, -3.0, 0.4, 0.6, -0.2], 0.1 * rng.standard_normal(D)]))
    return kw, steps


def warns(fn, *args, **kwargs):
    """fn(*args, **kwargs), which must raise exactly one DeprecationWarning naming the new name."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn(*args, **kwargs)
    deprecations = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert len(deprecations) == 1, [str(w.message) for w in caught]
    assert "deprecated" in str(deprecations[0].message)
    return result


def same_gradient(a, b):
    assert a.ok and b.ok
    assert a.cost == b.cost
    for name in ["q0", "qd0", "stiffness", "damping", "targets"]:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.states_held == b.states_held


def test_each_function_alias_warns_and_gives_the_new_result(pot3):
    kw, steps = problem(pot3)
    goal = [20.0, 95.0, 0.0]
    # the stage-cost makers: the same value and gradient at a state
    q, qd = kw["q0"], kw["qd0"]
    pairs = [
        (warns(wobble.centre_of_mass_at3, pot3, 4, goal, weight=0.5, axes="xz"),
         wobble.centre_of_mass_at(pot3, 4, goal, weight=0.5, axes="xz")),
        (warns(wobble.centre_of_mass_velocity_at3, pot3, 4, goal, weight=0.5),
         wobble.centre_of_mass_velocity_at(pot3, 4, goal, weight=0.5)),
        (warns(wobble.upright_at3, 4, weight=2.0, time_scale=0.3), wobble.upright_at(4, weight=2.0, time_scale=0.3)),
        (warns(wobble.still_at3, 4, weight=0.7), wobble.still_at(4, weight=0.7)),
    ]
    for old, new in pairs:
        a, b = old(4, q, qd), new(4, q, qd, dim=3)
        assert a[0] == b[0] and a[0] > 0.0
        np.testing.assert_array_equal(a[1], b[1])
        np.testing.assert_array_equal(a[2], b[2])
    cost = wobble.centre_of_mass_at(pot3, steps, goal, weight=1e-3) + wobble.upright_at(steps, weight=5.0)
    old_cost = (warns(wobble.centre_of_mass_at3, pot3, steps, goal, weight=1e-3)
                + warns(wobble.upright_at3, steps, weight=5.0))
    # the rollouts: the same numbers, bit for bit
    same_gradient(warns(wobble.rollout_gradient3, pot3, old_cost, **kw), wobble.rollout_gradient(pot3, cost, **kw))
    assert warns(wobble.rollout_cost3, pot3, cost, **kw) == wobble.rollout_cost(pot3, cost, **kw)
    fit_kw = dict(targets=np.zeros_like(kw["targets"]), knots=4, bound=0.3, options=kw["options"], q0=kw["q0"],
                  qd0=kw["qd0"], max_iterations=3)
    a = warns(wobble.fit_spacetime3, pot3, old_cost, **fit_kw)
    b = wobble.fit_spacetime(pot3, cost, **fit_kw)
    assert a.ok and b.ok
    assert a.cost == b.cost and a.iterations == b.iterations
    np.testing.assert_array_equal(a.knots, b.knots)


def test_the_class_aliases_are_the_classes_and_warn(pot3):
    with pytest.warns(DeprecationWarning, match="StageCost3 is deprecated"):
        stage_cost3 = wobble.StageCost3
    with pytest.warns(DeprecationWarning, match="RolloutGradient3 is deprecated"):
        rollout_gradient3 = wobble.RolloutGradient3
    assert stage_cost3 is wobble.StageCost
    assert rollout_gradient3 is wobble.RolloutGradient
    kw, steps = problem(pot3)
    g = wobble.rollout_gradient(pot3, wobble.still_at(steps, weight=1.0), **kw)
    assert isinstance(g, rollout_gradient3)
    assert isinstance(stage_cost3(lambda n, q, qd: (0.0, None, None)), wobble.StageCost)


def test_one_function_takes_either_body_and_refuses_the_other_dimension_s_terms(pot3, table):
    kw_3d, steps = problem(pot3)
    rng = np.random.default_rng(2)
    kw_2d = dict(targets=0.05 * rng.standard_normal((table.num_modes, steps)), options=no_ground(),
               q0=np.concatenate([[0.0, 100.0, 0.1], np.zeros(table.num_modes)]))
    either = wobble.still_at(steps, weight=1.0) + wobble.upright_at(steps, weight=1.0)
    assert wobble.rollout_gradient(table, either, **kw_2d).ok
    assert wobble.rollout_gradient(pot3, either, **kw_3d).ok
    a_2d = wobble.centre_of_mass_at(table, steps, [0.0, 90.0])
    a_3d = wobble.centre_of_mass_at(pot3, steps, [0.0, 90.0, 0.0])
    with pytest.raises(wobble.InputError, match="2D body's"):
        wobble.rollout_cost(pot3, a_2d + either, **kw_3d)
    with pytest.raises(wobble.InputError, match="3D body's"):
        wobble.rollout_gradient(table, a_3d, **kw_2d)
    with pytest.raises(wobble.InputError, match="cannot be summed"):
        a_2d + a_3d
    # a cost that serves both is called as the 2D body's unless asked
    q, qd = np.array([0.0, 1.0, 0.5]), np.array([0.0, 0.0, 2.0])
    assert wobble.upright_at(0, weight=2.0)(0, q, qd)[0] == pytest.approx(0.25)
    with pytest.raises(wobble.InputError, match="dim"):
        wobble.upright_at(0)(0, q, qd, dim=4)
