"""3D characters with their own meshes from Python (issue 15): loading a mesh object, the
state convention q = [t, rotation vector, modes], free fall against the closed form, the
recorder's 3D columns, and errors that name FILE:LINE."""
import numpy as np
import pytest

import wobble
from conftest import DATA, no_ground

G = 9.81


@pytest.fixture(scope="module")
def pot3():
    return wobble.load_body(str(DATA / "pot3.obj"), [str(DATA / "pot3_modes.def3")])


def test_the_mesh_pot_loads_with_its_mass_and_mesh(pot3):
    assert pot3.num_q == 6 + 3
    assert pot3.mode_names == ["squash", "sway", "twist"]
    assert pot3.total_mass == pytest.approx(750, rel=1e-12)
    assert pot3.mesh_triangles.shape == (384, 3)
    # at q = 0 every vertex is where the mesh puts it (the FFD's linear precision)
    assert np.abs(pot3.mesh_vertices() - pot3.mesh_points).max() < 1e-9 * 200


def test_a_turned_state_reads_back_and_moves_the_mesh_rigidly(pot3):
    world = wobble.World(no_ground("rk4", 0.001))
    world.add_body(pot3)
    q = np.array([5.0, 100.0, -3.0, 0.1, 0.7, -0.2, 0.0, 0.0, 0.0])
    world.set_state(0, q)
    assert world.q(0) == pytest.approx(q, abs=1e-14)
    # the mesh at a rigid q: rotated by the rotation vector's turn (Rodrigues) and moved by t
    r = q[3:6]
    angle = np.linalg.norm(r)
    k = r / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
    expected = pot3.mesh_points @ R.T + q[:3]
    assert np.abs(pot3.mesh_vertices(q) - expected).max() < 1e-9 * 200


def test_free_fall_follows_the_parabola_and_is_recorded(pot3):
    # uniform gravity neither turns nor deforms a body: t_y(t) = y0 + v t - g t²/2 (RK4 is exact)
    world = wobble.World(no_ground("rk4", 0.01))
    world.add_body(pot3)
    world.set_state(0, [0, 500, 0, 0.2, 0, 0.1, 0, 0, 0], [1, 20, 0, 0, 0, 0, 0, 0, 0])
    run = wobble.simulate(world, 2.0, every=10)
    t = 2.0
    q = world.q(0)
    assert q[1] == pytest.approx(500 + 20 * t - 0.5 * G * t * t, abs=1e-9 * 500)
    assert q[0] == pytest.approx(t, abs=1e-9 * 500)
    assert q[3:6] == pytest.approx([0.2, 0, 0.1], abs=1e-12)
    assert np.all(np.abs(q[6:]) < 1e-12)
    # the record: t, quaternion and modes; velocities ṫ, body ω and mode rates
    assert run.q(0).shape == (21, 7 + 3)
    assert run.qd(0).shape == (21, 6 + 3)
    assert run.column("ty")[-1] == pytest.approx(q[1], abs=1e-12)
    assert np.allclose(np.linalg.norm(run.q(0)[:, 3:7], axis=1), 1.0, atol=1e-14)


def test_one_loader_and_one_world_api_for_both_dimensions(pot3):
    assert isinstance(wobble.load_body(str(DATA / "table.obj")), wobble.BodyModel)
    assert isinstance(pot3, wobble.BodyModel) and pot3.dim == 3
    world = wobble.World(no_ground("rk4", 0.001))
    assert world.add_body(wobble.load_body(str(DATA / "table.obj"))) == 0
    assert world.add_body(pot3) == 1
    assert isinstance(world.body(0), wobble.BodyModel) and isinstance(world.body(1), wobble.BodyModel)
    assert world.q(0).shape == (3,) and world.q(1).shape == (9,)
    assert world.point_positions(0).shape[1] == 2 and world.point_positions(1).shape[1] == 3
    assert world.forces(1)["total"].shape == (9,)


def test_the_old_3d_names_warn_and_do_the_same(pot3):
    q = [1.0, 2.0, 3.0, 0.1, -0.2, 0.3, 0.01, 0.0, -0.02]
    with pytest.warns(DeprecationWarning, match="load_body3 is deprecated: use wobble.load_body"):
        old_pot = wobble.load_body3(str(DATA / "pot3.obj"), [str(DATA / "pot3_modes.def3")])
    assert old_pot.num_q == pot3.num_q and old_pot.total_mass == pot3.total_mass
    world = wobble.World()
    with pytest.warns(DeprecationWarning, match="World.add_body3"):
        body = world.add_body3(pot3)
    with pytest.warns(DeprecationWarning, match="World.set_state3"):
        world.set_state3(body, q)
    with pytest.warns(DeprecationWarning, match="World.q3"):
        assert np.array_equal(world.q3(body), world.q(body))
    with pytest.warns(DeprecationWarning, match="World.qd3"):
        assert np.array_equal(world.qd3(body), world.qd(body))
    with pytest.warns(DeprecationWarning, match="World.body3"):
        assert world.body3(body).num_q == pot3.num_q
    assert world.q(body) == pytest.approx(q, abs=1e-14)


def test_errors_name_the_file_and_line(tmp_path):
    bad = tmp_path / "bad3.obj"
    bad.write_text("dimension 3\n# a mesh that is not there\nmesh missing.stl\nsample volume 10 1\n")
    with pytest.raises(wobble.ParseError, match=r"bad3.obj:3: mesh: .*missing.stl"):
        wobble.load_body(str(bad))
    world = wobble.World()
    with pytest.raises(wobble.InputError, match="body 0: the world has 0 bodies"):
        world.q(0)


def test_batched_rollout_of_the_3d_pot_equals_worlds_stepped_alone(pot3):
    # three trials on two threads, with PD targets, equal bit for bit to each World stepped alone
    options = no_ground("thesis", 0.002)
    q0 = np.array([[0, 100, 0, 0.2, 0.1, 0.0, 0.1, 0, 0],
                   [5, 80, -3, 0.0, 1.2, 0.3, 0, 0.2, 0],
                   [-5, 120, 2, 2.5, 0.0, -1.0, 0, 0, 0.3]])
    qd0 = np.array([[1, 2, 3, 0.5, -1, 2, 0, 0, 0]] * 3)
    targets = np.array([[0.3, 0, 0], [0, -0.2, 0.1], [0.1, 0.1, -0.2]])
    r = wobble.rollout(pot3, q0, qd0, 300, options=options, mode_targets=targets, every=100, threads=2, energies=True)
    assert r.q.shape == (3, 4, 9) and r.status == ["ok"] * 3
    for i in range(3):
        world = wobble.World(options)
        world.add_body(pot3)
        world.set_state(0, q0[i], qd0[i])
        world.set_mode_targets(0, targets[i])
        assert np.array_equal(r.q[i, 0], world.q(0))
        for k in range(1, 4):
            world.step(100)
            assert np.array_equal(r.q[i, k], world.q(0)) and np.array_equal(r.qd[i, k], world.qd(0))
    # the modes were driven: γ moved toward the targets
    assert np.abs(r.q[:, -1, 6:] - q0[:, 6:]).max() > 1e-3


def test_synthesis_of_the_3d_bounding_table_from_python():
    # data/bounding_table3.wob up to its anneal: the 3D problem, its trials in a batch on two
    # threads equal to one at a time, and annealing that lowers the cost
    from conftest import bounding_table
    problem = bounding_table(DATA, "bounding_table3.wob").synthesis_problem()
    assert isinstance(problem.body, wobble.BodyModel) and problem.body.dim == 3 and problem.body.num_q == 6 + 4 and problem.num_active == 2
    with pytest.warns(DeprecationWarning, match="SynthesisProblem.body3 is deprecated: use SynthesisProblem.body"):
        assert problem.body3.num_q == 6 + 4
    problem.steps = 300
    poses = np.array([[[0.1, 0], [0, -0.1], [-0.1, 0], [0, 0.1]],
                      [[0.2, 0], [0, -0.2], [-0.2, 0], [0, 0.2]],
                      [[0.05, 0.05], [0.05, -0.05], [-0.05, -0.05], [-0.05, 0.05]]])
    durations = [0.4, 0.4, 0.4, 0.4]
    batch = wobble.run_trials(problem, poses, durations, threads=2)
    for i in range(3):
        one = problem.run(wobble.PoseGraph(poses[i], durations))
        assert one.ok and batch.ok[i]
        assert batch.cost[i] == one.cost and batch.distance[i] == one.distance
    assert len(set(batch.distance)) == 3  # the controllers move the table differently
    start = wobble.PoseGraph(poses[0], durations)
    result = wobble.anneal(problem, start, seed=3, iterations=4, batch=2, threads=2)
    assert result.trials == 1 + 4 * 2
    assert result.best_outcome.cost <= result.initial_outcome.cost


def test_contacts_and_penetration_of_a_3d_body_on_the_ground(pot3):
    # the pot dropped onto the ground plane: its contacts are mass points below the plane, each
    # with a 3D anchor on the plane's side it entered from
    options = wobble.WorldOptions(dt=0.0005)
    options.ground_plane.enabled = True
    options.ground_plane.stiffness = 20000
    world = wobble.World(options)
    world.add_body(pot3)
    world.set_state(0, [0, 0.5, 0, 0.1, 0, 0.05, 0, 0, 0])  # its foot 0.5 above the plane, tilted
    for _ in range(4000):  # until it touches (it bounces: contacts come and go)
        world.step(1)
        points, anchors = world.contacts(0)
        if len(points) > 3:
            break
    assert len(points) > 0 and anchors.shape == (len(points), 3)
    # the contact points are below the plane y = 0; the deepest is the penetration
    y = pot3.mass_points_at(world.q(0))[points, 1]
    assert np.all(y < 0)
    assert world.penetration(0) == pytest.approx(-y.min(), rel=1e-12)


def test_a_point_force_on_a_3d_body_gives_its_impulse(pot3):
    # one explicit step from rest solves M(q0) v1 = dt Jᵀ f, so the linear momentum Σ m_k ẋ_k,
    # with ẋ_k = ṫ + (R ω) × (x_k − t) + R B_k γ̇ at the start's configuration, is f dt
    world = wobble.World(no_ground("thesis", 0.01, gravity=False))
    world.add_body(pot3)
    q0 = np.array([1.0, 2.0, 3.0, 0.3, -0.2, 0.5, 0, 0, 0])
    world.set_state(0, q0)
    x = pot3.mass_points_at(q0)
    f = np.array([30.0, -50.0, 20.0])
    world.apply_point_force(0, 7, force=f)
    world.step(1)
    v = world.qd(0)
    r = q0[3:6]
    angle = np.linalg.norm(r)
    k = r / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
    B_gamma_dot = pot3.mass_points_at(np.concatenate([np.zeros(6), v[6:]])) - pot3.mass_points_at(np.zeros(9))
    xd = v[:3] + np.cross(R @ v[3:6], x - q0[:3]) + B_gamma_dot @ R.T
    P = (np.array(pot3.masses)[:, None] * xd).sum(axis=0)
    np.testing.assert_allclose(P, f * 0.01, rtol=0, atol=1e-9 * np.linalg.norm(f) * 0.01)
    with pytest.raises(wobble.InputError):
        world.apply_point_force(0, 7, force=[1.0, 2.0])
