"""Witkin & Welch bodies from Python: x = R p(u), the constant mass matrix of Eq. 5, free fall
in closed form, and constraints held by multipliers."""
import numpy as np
import pytest

import wobble
from conftest import DATA

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


def test_a_3d_block_rests_on_a_heightfield_as_on_the_plane_only_higher():
    # a level heightfield 2 high in place of the plane: the same rest, 2 higher, on its faces
    def rest(field, height):
        options = wobble.WorldOptions(dt=0.001)
        options.ground_plane.enabled = True
        options.ground_plane.normal_damping = 100
        options.ground_plane.heightfield = field
        world = wobble.World(options)
        b = world.add_linear_body(wobble.linear_box(3, [1.0, 0.5, 0.5], per_side=3, mass=6.0),
                                  rigidity=2e4, volume=2e4, damping=0.02, ground=True)
        R, _ = world.linear_state(b)
        R[1, 3] = height  # 0.5 above the surface
        world.set_linear_state(b, R)
        world.run_until(5.0)
        return world.linear_state(b)[0][1, 3], world.linear_contacts(b)

    level = wobble.Heightfield(origin=[-5, -5], spacing=[2.5, 2.5], heights=np.full((5, 5), 2.0))
    assert level.height_at(0.3, -1.2) == 2.0 and level.heights.shape == (5, 5)
    on_plane, plane_contacts = rest(None, 1.0)
    on_field, field_contacts = rest(level, 3.0)
    assert len(plane_contacts) == len(field_contacts) == 9  # the bottom face's 3 x 3 points
    assert on_field == pytest.approx(on_plane + 2.0, abs=1e-9)
    assert all(face == 0 for _, face, _ in plane_contacts)
    assert any(face > 0 for _, face, _ in field_contacts)  # triangles of the grid


def test_read_heightfield_and_its_errors(tmp_path):
    hills = wobble.read_heightfield(str(DATA / "hills.heightfield"))
    assert hills.heights.shape == (21, 31)
    x, z = -600 + 40 * 7, -400 + 40 * 3  # a node: its height as written (three decimals)
    h = 80 * (1 - np.tanh((x + 150) / 120)) + 20 * np.sin(x / 95) * np.cos(z / 120) + 0.0002 * z * z
    assert hills.height_at(x, z) == pytest.approx(h, abs=5e-4)
    bad = tmp_path / "bad.heightfield"
    bad.write_text("origin 0 0\nspacing 1 1\n1 2\n")
    with pytest.raises(wobble.ParseError, match="bad.heightfield:3: expected at least two rows"):
        wobble.read_heightfield(str(bad))
