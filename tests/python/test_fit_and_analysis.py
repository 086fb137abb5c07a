"""Fits and the mass matrix from Python, checked against the direct per-point formulas: M from
Σ m_k J_kᵀ J_k of the point positions, a pose recovered from the points it puts down."""
import numpy as np
import pytest

import wobble
from conftest import no_ground


def point_jacobians(table, q, eps=1e-6):
    """∂x_k/∂q of every mass point by central differences of World.point_positions."""
    world = wobble.World(no_ground())
    world.add_body(table)
    J = np.zeros((table.num_points, 2, table.num_q))
    for i in range(table.num_q):
        dq = np.zeros(table.num_q)
        dq[i] = eps
        world.set_state(0, q + dq)
        plus = world.point_positions(0)
        world.set_state(0, q - dq)
        minus = world.point_positions(0)
        J[:, :, i] = (plus - minus) / (2 * eps)
    return J


def test_mass_matrix_is_the_sum_over_mass_points(table):
    q = np.array([5.0, 30.0, 0.7, 0.1, -0.05, 0.2, 0.03])
    J = point_jacobians(table, q)
    direct = np.einsum("k,kai,kaj->ij", table.masses, J, J)
    M = wobble.mass_matrix(table, q)
    np.testing.assert_allclose(M, direct, rtol=1e-6, atol=1e-6 * np.abs(direct).max())
    c = wobble.condition_number(table, q)
    assert c.cond == pytest.approx(np.linalg.cond(M), rel=1e-9)
    np.testing.assert_allclose(c.singular_values, np.linalg.svd(M, compute_uv=False), rtol=1e-9)


def test_angle_sweep_near_one_mode_follows_the_inverse_square_law(data):
    # two unit fields at angle α have Gram eigenvalue 1 − cos α ≈ α²/2 with α ∝ δ = π/2 − φ, so
    # cond ∝ 1/δ²: ten times closer is a hundred times worse; at δ = 0 the modes are one
    obj = str(data / "table.obj")
    cond, scaled = wobble.angle_sweep(obj, np.pi / 2 - np.array([1e-3, 1e-4, 0.0]))
    assert 90 < cond[1] / cond[0] < 110
    assert np.isinf(cond[2])
    last_quarter, _ = wobble.angle_sweep(obj, np.radians(np.linspace(70, 89.9, 12)))
    assert np.all(np.diff(last_quarter) > 0)
    with pytest.raises(wobble.InputError):
        wobble.angle_sweep(obj, [np.nan])


def test_check_mode_set_reports_angles(table):
    r = wobble.check_mode_set(table)
    assert r.level in ("ok", "warning")
    assert r.pair_angle_deg.shape == (4, 4)
    np.testing.assert_allclose(r.pair_angle_deg, r.pair_angle_deg.T)


def test_a_pose_is_recovered_from_the_points_it_puts_down(table):
    truth = np.array([40.0, 12.0, 0.15, 0.3, -0.2, 0.1, 0.25])
    world = wobble.World(no_ground())
    world.add_body(table)
    world.set_state(0, truth)
    points = world.point_positions(0)
    fit = wobble.fit_pose(table, points, mass_points=list(range(table.num_points)))
    assert fit.report.usable
    np.testing.assert_allclose(fit.q, truth, atol=1e-6)
    assert fit.rms_residual < 1e-6
    assert fit.conditioning.undetermined == []


def test_fit_inputs_are_checked(table):
    pts = np.zeros((3, 2))
    with pytest.raises(wobble.InputError, match="exactly one"):
        wobble.fit_pose(table, pts)
    with pytest.raises(wobble.InputError, match="mass_points"):
        wobble.fit_pose(table, pts, mass_points=[0, 1, 99])
    bad = pts.copy()
    bad[1, 0] = np.inf
    with pytest.raises(wobble.InputError, match=r"points\[1\]"):
        wobble.fit_pose(table, bad, mass_points=[0, 1, 2])
    with pytest.raises(wobble.InputError, match="loss"):
        wobble.fit_pose(table, pts, mass_points=[0, 1, 2], loss="l1")
    with pytest.raises(wobble.InputError, match=r"weights\[0\]"):
        wobble.fit_pose(table, pts, mass_points=[0, 1, 2], weights=[0, 1, 1])


@pytest.mark.parametrize("gradient", ["jets", "adjoint"])
def test_a_dynamic_fit_recovers_what_generated_its_reference(table, gradient):
    # the reference: the table's own modes (table_modes.def) from a known start, no ground
    options = no_ground("thesis", 0.01)
    q0 = np.array([0, 100, 0.1, 0.2, -0.1, 0.1, 0.05])
    qd0 = np.array([30, 60, 1.0, 0.5, -0.8, 0.6, 0.4])
    world = wobble.World(options)
    world.add_body(table)
    world.set_state(0, q0, qd0)
    times, points = [], []
    for frame in range(26):  # every 2nd step of 0.5 s
        times.append(world.time)
        points.append(world.point_positions(0))
        world.step(2)
    K = np.array([m.stiffness for m in table.modes])
    c = np.array([m.damping for m in table.modes])
    fit = wobble.fit_dynamic(table, times, np.array(points), list(range(table.num_points)), options=options,
                             q0=q0 + [2, -1, 0.01, 0.02, -0.02, 0.01, 0.02], qd0=qd0 + [-3, 2, 0.1, 0.1, 0.1, -0.1, 0.1],
                             stiffness=1.4 * K, damping=0.6 * c + 1.0, gradient=gradient,
                             max_iterations=50 if gradient == "jets" else 500)  # BFGS takes ~20x LM's iterations
    assert fit.report.usable, fit.report.brief_report
    np.testing.assert_allclose(fit.params.q0, q0, atol=1e-6)
    np.testing.assert_allclose(fit.params.qd0, qd0, atol=1e-5)
    np.testing.assert_allclose(fit.params.stiffness, K, rtol=1e-5)
    assert fit.rms_residual < 1e-5
    with pytest.raises(wobble.InputError, match="thesis"):
        wobble.fit_dynamic(table, times, np.array(points), list(range(table.num_points)),
                           options=wobble.WorldOptions(integrator="rk4"))
    with pytest.raises(wobble.InputError, match="jets' or 'adjoint"):
        wobble.fit_dynamic(table, times, np.array(points), list(range(table.num_points)), options=options,
                           gradient="finite")


def test_a_trajectory_fit_follows_the_frames(table):
    # a simulated run's points, fitted frame by frame with a light smoothness term
    options = no_ground("thesis", 0.01)
    world = wobble.World(options)
    world.add_body(table)
    world.set_state(0, [0, 100, 0.1, 0.2, -0.1, 0.1, 0.05], [30, 60, 1.0, 0.5, -0.8, 0.6, 0.4])
    times, points, qs = [], [], []
    for frame in range(10):
        times.append(world.time)
        points.append(world.point_positions(0))
        qs.append(world.q(0))
        world.step(3)
    fit = wobble.fit_trajectory(table, times, np.array(points), list(range(table.num_points)), smoothness=1e-6)
    assert fit.report.usable and fit.q.shape == (10, 7)
    np.testing.assert_allclose(fit.q, np.array(qs), atol=1e-3)
    assert fit.rms_residual < 0.05
