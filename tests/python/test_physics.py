"""The physics from Python against closed forms and against the C++ command line on the same
case: the module must give exactly what libwobble gives."""
import copy
import subprocess

import numpy as np
import pytest

import wobble
from conftest import no_ground

G = 9.81


@pytest.mark.parametrize("integrator", ["thesis", "rk4"])
def test_free_fall_matches_the_closed_form(table, integrator):
    # thesis scheme (Eq. 4.22/4.23): y_n = y0 + n h v0 - g h^2 n(n+1)/2; RK4 is exact on a parabola
    world = wobble.World(no_ground(integrator, 0.01))
    world.add_body(table)
    world.set_state(0, [10, 1000, 0.4, 0, 0, 0, 0], [3, 20, 0, 0, 0, 0, 0])
    n, h = 500, 0.01
    world.step(n)
    t = n * h
    y = 1000 + n * h * 20 - G * h * h * n * (n + 1) / 2 if integrator == "thesis" else 1000 + 20 * t - 0.5 * G * t * t
    q, qd = world.q(0), world.qd(0)
    assert q[1] == pytest.approx(y, abs=1e-9 * 1000)
    assert q[0] == pytest.approx(10 + 3 * t, abs=1e-9 * 100)
    assert qd[1] == pytest.approx(20 - G * t, abs=1e-10 * 100)
    # uniform gravity neither turns nor deforms the body
    assert q[2] == pytest.approx(0.4, abs=1e-12)
    assert np.all(np.abs(q[3:]) < 1e-12)
    assert world.time == pytest.approx(t, rel=1e-12)


def test_kinetic_energy_is_the_direct_sum_over_mass_points(table):
    # ½ Σ m_k |ẋ_k|² by central differences of the point positions equals ½ q̇ᵀ M q̇ (Eq. 4.9)
    q = np.array([1.0, 200.0, 0.3, 0.05, -0.02, 0.04, 0.01])
    qd = np.array([2.0, -1.0, 0.2, 0.1, 0.3, -0.2, 0.05])
    world = wobble.World(no_ground())
    world.add_body(table)
    eps = 1e-6
    world.set_state(0, q + eps * qd)
    x_plus = world.point_positions(0)
    world.set_state(0, q - eps * qd)
    x_minus = world.point_positions(0)
    v = (x_plus - x_minus) / (2 * eps)
    direct = 0.5 * np.sum(table.masses * np.sum(v * v, axis=1))
    world.set_state(0, q, qd)
    assert world.energies(0).kinetic == pytest.approx(direct, rel=1e-7)


def test_energies_sum_to_their_total_and_the_world_total(table):
    world = wobble.World(wobble.WorldOptions(dt=0.01))
    world.add_body(table)
    world.set_state(0, [0, -0.5, 0.01, 0.02, 0, 0, 0])  # the legs' feet half a unit deep
    world.step(5)
    e = world.energies(0)
    assert e.total() == pytest.approx(e.kinetic + e.gravity + e.modes + e.ground + e.springs, rel=1e-15)
    assert sum(e.per_mode) == pytest.approx(e.modes, rel=1e-12)
    assert world.total_energy() == pytest.approx(e.total(), rel=1e-15)
    points, anchors = world.contacts(0)
    assert len(points) > 0 and anchors.shape == (len(points), 2)
    assert world.penetration(0) > 0


def test_simulate_equals_the_command_line_on_the_same_case(table, data, cli, tmp_path):
    # wobble simulate writes shortest round-trip numbers: the CSV is the C++ run, exactly
    csv = tmp_path / "drop.csv"
    subprocess.run([cli, "simulate", "--object", str(data / "table.obj"), "--modes", str(data / "table_modes.def"),
                    "--q", "0 50 0 0 0 0 0", "--integrator", "thesis", "--dt", "0.01", "--duration", "3",
                    "--ground-slope", "-5", "--out", str(csv)], check=True, capture_output=True)
    options = wobble.WorldOptions(dt=0.01, integrator="thesis")
    options.ground.slope = np.radians(-5)
    world = wobble.World(options)
    world.add_body(table)
    world.set_state(0, [0, 50, 0, 0, 0, 0, 0])
    run = wobble.simulate(world, 3.0)
    cpp = wobble.read_trajectory_csv(str(csv), table)
    assert len(run) == len(cpp) == 301
    assert run.columns == cpp.columns
    np.testing.assert_allclose(run.array, cpp.array, rtol=1e-12, atol=1e-12)
    # and the same final state as the world stepped from Python
    np.testing.assert_array_equal(run.q()[-1], world.q(0))


def test_trajectory_views_are_read_only_and_outlive_the_world(table):
    world = wobble.World(no_ground())
    world.add_body(table)
    world.set_state(0, [0, 0, 0, 0.1, 0, 0, 0])
    run = wobble.simulate(world, 1.0, every=10)
    q = run.q()
    del world, run  # the view keeps the samples alive
    assert q.shape == (11, 7)
    assert not q.flags.writeable
    with pytest.raises(ValueError):
        q[0, 0] = 1.0
    assert np.all(np.isfinite(q))


def test_simulate_samples_film_frames(table):
    world = wobble.World(no_ground(dt=0.01))
    world.add_body(table)
    run = wobble.simulate(world, 2.0, fps=10)
    np.testing.assert_allclose(run.time, np.arange(21) * 0.1, atol=1e-9)


def test_world_data_put_back_replays_the_same_steps_exactly(table, data):
    """A run from a taken WorldData is the run from where it was taken, bit for bit (contacts,
    anchors and targets included); a world whose body differs refuses it."""
    world = wobble.World()
    world.add_body(table)
    world.set_state(0, [0, 30, 0.05, 0, 0, 0, 0], [3, 0, 0, 0, 0, 0, 0])  # lands on a leg, sliding
    world.set_mode_targets(0, [0.05, 0, 0, 0.02])
    world.step(300)
    assert len(world.contacts(0)[0]) > 0, "on the ground when the data is taken"
    taken = world.data()
    assert (taken.steps, taken.time) == (world.steps, world.time)

    def record(n):
        q = []
        for _ in range(n):
            world.step()
            q.append(world.q(0))
        return np.array(q)

    first = record(150)
    assert np.abs(first[-1] - first[0]).max() > 1e-3, "the body moves on meanwhile"
    assert taken.steps == 300, "a copy: the world's steps do not change it"
    world.set_data(copy.deepcopy(taken))
    assert world.steps == taken.steps and world.time == taken.time
    np.testing.assert_array_equal(record(150), first)

    other = wobble.World()
    other.add_body(wobble.load_body(str(data / "table.obj")))  # no modes: another q size
    q_before = other.q(0)
    with pytest.raises(ValueError, match="does not fit"):
        other.set_data(taken)
    np.testing.assert_array_equal(other.q(0), q_before)
