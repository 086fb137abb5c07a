"""One Python class for FFD bodies of both dimensions: wobble.BodyModel (its dim 2 or 3), what
both dimensions have, what one has raising InputError on the other, the deprecated name
BodyModel3 (the same class, warning), and a body of either dimension going through the World,
rollouts, fits, gradients and scripts as the same Python object."""
import warnings

import numpy as np
import pytest

import wobble
from conftest import DATA, bounding_table, no_ground


@pytest.fixture(scope="module")
def pot3():
    return wobble.load_body(str(DATA / "pot3.obj"), [str(DATA / "pot3_modes.def3")])


def test_bodies_of_both_dimensions_are_one_class(table, pot3):
    assert type(table) is wobble.BodyModel and type(pot3) is wobble.BodyModel
    assert (table.dim, pot3.dim) == (2, 3)
    assert (table.num_q, pot3.num_q) == (3 + 4, 6 + 3)
    for body in (table, pot3):
        dim = body.dim
        assert body.mass_positions.shape == (body.num_points, dim)
        assert body.masses.shape == (body.num_points,)
        assert body.masses.sum() == pytest.approx(body.total_mass, rel=1e-12)
        assert len(body.lattice_shape) == dim
        assert body.rest_control.shape == (int(np.prod(body.lattice_shape)), dim)
        assert [m.name for m in body.modes] == body.mode_names and len(body.modes) == body.num_modes
        assert body.modes[0].displacement.shape == body.rest_control.shape
    assert table.lattice_shape == (4, 4) and pot3.lattice_shape == (4, 4, 4)
    assert repr(table).startswith("<BodyModel 'table' (2D): ") and repr(pot3).startswith("<BodyModel 'pot3' (3D): ")


def test_members_of_one_dimension_name_it_on_the_other(table, pot3):
    with pytest.raises(wobble.InputError, match="outline needs a 2D body; this BodyModel 'pot3' is 3D"):
        pot3.outline()
    for name in ["mesh_points", "mesh_triangles"]:
        with pytest.raises(wobble.InputError, match=f"{name} needs a 3D body; this BodyModel 'table' is 2D"):
            getattr(table, name)
    with pytest.raises(ValueError, match="mesh_vertices needs a 3D body; this BodyModel 'table' is 2D"):
        table.mesh_vertices()
    # what each still does on its own dimension
    assert len(table.outline()) > 0
    assert pot3.mesh_points.shape[1] == 3 and pot3.mesh_triangles.shape[1] == 3
    # a function of one dimension refuses the other by its signature, as before
    for only_2d in [wobble.condition_number, wobble.check_mode_set]:
        with pytest.raises(TypeError, match=r"body: BodyModel \(2D\)"):
            only_2d(pot3)


def test_mass_points_at_is_where_the_world_puts_them_in_both_dimensions(table, pot3):
    for body, q in [(table, [3.0, 40.0, 0.4, 0.1, -0.2, 0.05, 0.0]),
                    (pot3, [1.0, 2.0, 3.0, 0.3, -0.2, 0.5, 0.1, -0.05, 0.02])]:
        world = wobble.World(no_ground())
        world.add_body(body)
        world.set_state(0, q)
        np.testing.assert_allclose(body.mass_points_at(q), world.point_positions(0), rtol=0, atol=1e-10)
        np.testing.assert_allclose(body.mass_points_at(), body.mass_positions, rtol=0, atol=1e-10)
        with pytest.raises(wobble.InputError, match=rf"q: expected shape \({body.num_q},\)"):
            body.mass_points_at(np.zeros(body.num_q + 1))


def test_body_model3_is_a_deprecated_name_of_the_one_class(pot3):
    with pytest.warns(DeprecationWarning, match="wobble.BodyModel3 is deprecated: use wobble.BodyModel"):
        alias = wobble.BodyModel3
    assert alias is wobble.BodyModel
    with pytest.warns(DeprecationWarning):
        assert isinstance(pot3, wobble.BodyModel3)
    assert "BodyModel3" in dir(wobble)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isinstance(pot3, wobble.BodyModel)  # the new name does not warn
    with pytest.raises(AttributeError, match="no attribute 'BodyModel4'"):
        wobble.BodyModel4


def test_either_body_goes_through_the_world_and_comes_back_the_same(table, pot3):
    world = wobble.World(no_ground("rk4", 0.001))
    assert world.add_body(table) == 0 and world.add_body(pot3) == 1
    assert world.body(0) is table and world.body(1) is pot3
    assert world.body(1).dim == 3 and world.q(1).shape == (9,)
    world.step(2)
    assert world.q(1)[1] < 0  # it fell


def test_a_3d_body_goes_through_rollouts_fits_gradients_and_scripts(pot3):
    q0 = np.array([[0, 100, 0, 0.2, 0.1, 0.0, 0.1, 0, 0]])
    r = wobble.rollout(pot3, q0, steps=5, options=no_ground("thesis", 0.002))
    assert r.q.shape == (1, 6, 9) and r.status == ["ok"]
    truth = np.array([1.0, 2.0, 3.0, 0.2, -0.1, 0.3, 0.05, -0.03, 0.02])
    which = list(range(0, pot3.num_points, 40))
    fit = wobble.fit_pose(pot3, pot3.mass_points_at(truth)[which], mass_points=which)
    np.testing.assert_allclose(fit.q, truth, atol=1e-6)
    cost = wobble.centre_of_mass_at(pot3, 3, [0.0, 99.0, 0.0])
    targets = np.zeros((pot3.num_modes, 3))
    g = wobble.rollout_gradient(pot3, cost, targets=targets, options=no_ground(), q0=q0[0])
    assert g.ok and g.q0.shape == (9,)
    interp = bounding_table(DATA, "bounding_table3.wob")
    assert isinstance(interp.body, wobble.BodyModel) and interp.body.dim == 3
    assert isinstance(interp.synthesis_problem().body, wobble.BodyModel) and interp.synthesis_problem().body.dim == 3
    assert wobble.Interpreter().body is None
