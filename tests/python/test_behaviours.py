"""Goal behaviours (Witkin & Welch §4.2) from Python: a world built in Python, its points led by
chase, held by connect, let go by release, stopped by an impulse, keyframed by follow and
gated by a Python predicate; checked against where the behaviours promise the points are."""
import numpy as np
import pytest

import wobble


def free_world():
    options = wobble.WorldOptions(dt=0.002, gravity_on=False)
    options.ground.enabled = False
    world = wobble.World(options)
    box = world.add_linear_body(wobble.linear_box(2, [1.0, 0.5], mass=2.0), rigidity=50.0, volume=50.0)
    return world, box


def test_grab_leads_the_corner_to_the_place_then_holds_it_there():
    world, box = free_world()
    corner = wobble.Anchor.point(world, box, u=[1.0, 0.5], name="corner")
    place = wobble.Anchor.place([4.0, 2.0], name="hook")
    b = wobble.Behaviours()
    world.add_controller(b)
    b.grab(corner, place, 0.5, final_velocity=[0.0, 0.0], name="held")
    world.step(250)  # t = 0.5: the chase's contact time, when the connect acts
    # missed by 8e-6 over 3.2 (the step's discretisation of a box that deforms on the way;
    # tests/motion_test.cc checks 1e-6 on a stiff block at half the step)
    np.testing.assert_allclose(corner.position(world), [4.0, 2.0], atol=1e-4)
    world.step(1)
    assert "held" in b.names and b.idle
    assert b.log[0].startswith("t = 0: chase corner -> hook")
    # the nail holds while the box turns about it under an impulse elsewhere
    b.impulse(wobble.Anchor.point(world, box, u=[-1.0, -0.5], name="far"), [0.0, -3.0])
    world.step(500)
    np.testing.assert_allclose(corner.position(world), [4.0, 2.0], atol=1e-3)
    assert world.max_violation() < 1e-3


def test_release_lets_go_and_an_impulse_stops_the_point_dead():
    world, box = free_world()
    corner = wobble.Anchor.point(world, box, u=[1.0, 0.5], name="corner")
    b = wobble.Behaviours()
    world.add_controller(b)
    b.connect(corner, wobble.Anchor.place(corner.position(world)), name="nail")
    b.wait(0.1)
    b.release("nail")
    b.impulse(corner, [2.0, 1.0])
    b.wait(0.2)
    b.impulse(corner, [0.0, 0.0])
    start = corner.position(world)
    world.step(51)  # t = 0.102: released, pushed at t = 0.1 (one step of the free body since)
    np.testing.assert_allclose(corner.velocity(world), [2.0, 1.0], atol=2e-2)
    world.step(98)  # t = 0.298: still moving
    assert np.linalg.norm(corner.velocity(world)) > 0.5
    world.step(2)  # the stop at t = 0.3, then one step
    assert np.linalg.norm(corner.velocity(world)) < 0.05
    assert np.linalg.norm(corner.position(world) - start) > 0.05  # the push moved it (the box was at rest)
    b.release("no such constraint")
    with pytest.raises(wobble.BehaviourError, match="no such constraint"):
        world.step(1)


def test_follow_keyframes_a_point_and_wait_for_asks_python():
    world, box = free_world()
    corner = wobble.Anchor.point(world, box, u=[1.0, 0.5], name="corner")
    p0 = corner.position(world)
    times = [0.2, 0.6, 1.0]
    keys = [p0 + [0.5, 0.0], p0 + [1.0, 1.0], p0 + [1.5, 0.0]]
    b = wobble.Behaviours()
    world.add_controller(b)
    seen = []
    b.wait_for("t >= 0.1", lambda w: seen.append(w.time) or w.time >= 0.1 - 1e-12)
    b.follow(corner, times, keys, onset=0.2, preroll=0.1, name="keys")
    world.step(300)  # t = 0.6: on the second key
    np.testing.assert_allclose(corner.position(world), keys[1], atol=1e-3)
    assert seen and seen[0] == 0.0 and max(seen) >= 0.1 - 1e-12  # the predicate ran until it held
    assert "keys" in b.names
    with pytest.raises(wobble.InputError, match="follow"):
        b.follow(corner, [0.0], [p0], name="one key")
    with pytest.raises(wobble.InputError):
        wobble.Anchor.point(world, box, 999)
