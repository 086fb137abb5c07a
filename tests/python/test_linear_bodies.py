"""Witkin & Welch bodies from Python: x = R p(u), the constant mass matrix of Eq. 5, free fall
in closed form, and constraints held by multipliers."""
import numpy as np
import pytest

import wobble

G = 9.81


def test_mass_matrix_is_the_sum_over_points():
    box = wobble.linear_box(2, [1.0, 0.5], per_side=3, mass=6.0)
    p = np.hstack([box.points, np.ones((box.num_points, 1))])  # affine basis [u, 1]
    M = (np.array(box.masses)[:, None, None] * p[:, :, None] * p[:, None, :]).sum(axis=0)
    np.testing.assert_allclose(box.mass_matrix, M, rtol=1e-12, atol=1e-12 * np.abs(M).max())
    assert box.total_mass == pytest.approx(6.0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_linear_body_falls_as_the_closed_form_says(dim):
    # semi-implicit Euler, velocity first: y_n = y0 + n h v0 - g h² n(n+1)/2 (translation column)
    options = wobble.WorldOptions(dt=0.01)
    options.ground.enabled = False
    world = wobble.World(options)
    b = world.add_linear_body(wobble.linear_box(dim, [1.0] * dim, mass=2.0))
    assert world.kind(b) == "linear"
    R, _ = world.linear_state(b)
    R[1, dim] = 100.0
    R_dot = np.zeros_like(R)
    R_dot[1, dim] = 5.0
    world.set_linear_state(b, R, R_dot)
    n, h = 300, 0.01
    world.step(n)
    R, R_dot = world.linear_state(b)
    assert R[1, dim] == pytest.approx(100 + n * h * 5 - G * h * h * n * (n + 1) / 2, abs=1e-9)
    assert R_dot[1, dim] == pytest.approx(5 - G * n * h, abs=1e-10)
    np.testing.assert_allclose(R[:, :dim], np.eye(dim), atol=1e-12)  # uniform gravity does not deform it
    e = world.energies(b)
    assert e.gravity == pytest.approx(2.0 * G * R[1, dim], rel=1e-12)  # centre of mass at u = 0


def test_a_nailed_pyramid_swings_and_the_nail_holds():
    world = wobble.World(wobble.WorldOptions(dt=0.002))
    world.options = world.options  # a copy back: options round-trip
    p = world.add_linear_body(wobble.linear_pyramid(2, 1.0, 2.0), rigidity=50.0, volume=50.0)
    R, _ = world.linear_state(p)
    R[1, 2] = 5.0
    world.set_linear_state(p, R)
    corner = [-1.0, 0.0]
    where = world.point_position(p, u=corner)
    nail = world.add_nail(p, u=corner)
    world.step(1000)
    np.testing.assert_allclose(world.point_position(p, u=corner), where, atol=1e-3)
    assert world.max_violation() < 1e-3
    assert np.linalg.norm(world.constraint_error(nail)) < 1e-3
    with pytest.raises(wobble.InputError, match="exactly one"):
        world.add_nail(p)
    with pytest.raises(wobble.InputError):
        world.add_nail(p, 10**6)
    with pytest.raises(wobble.InputError, match="not an FFD body"):
        world.q(p)


def test_bad_linear_bodies_are_input_errors():
    with pytest.raises(wobble.InputError, match="dim"):
        wobble.linear_box(4, [1, 1, 1, 1])
    with pytest.raises(wobble.InputError, match="mass points"):
        wobble.linear_box(3, [1, 1, 1], per_side=1000)
    with pytest.raises(wobble.InputError):  # collinear points: M singular
        wobble.linear_body([[0, 0], [1, 0], [2, 0]], [1, 1, 1])


def test_a_linear_body_with_ground_contact_rests_on_its_bottom_row():
    # frictionless flat ground: by symmetry the three bottom points carry m g / 3 each, sinking
    # m g / (3 K); without ground=True the same block falls through
    options = wobble.WorldOptions(dt=0.001)
    options.ground.friction_cap = 0.0
    world = wobble.World(options)
    box = wobble.linear_box(2, [1.0, 0.5], per_side=3, mass=6.0)
    b = world.add_linear_body(box, rigidity=2e4, volume=2e4, damping=0.02, ground=True)
    ghost = world.add_linear_body(box, rigidity=2e4, volume=2e4, damping=0.02)
    for body in (b, ghost):
        R, _ = world.linear_state(body)
        R[1, 2] = 0.7
        world.set_linear_state(body, R)
    world.run_until(6.0)
    K = options.ground.stiffness
    contacts = world.linear_contacts(b)
    assert sorted(point for point, _, _ in contacts) == [0, 1, 2]  # u_y = -0.5: the bottom row
    for point, face, _ in contacts:
        assert face == 0
        assert world.point_position(b, point)[1] == pytest.approx(-6.0 * G / (3 * K), rel=1e-6)
    assert world.linear_contacts(ghost) == []
    assert world.linear_state(ghost)[0][1, 2] < -100  # ½ g t² below where it started
