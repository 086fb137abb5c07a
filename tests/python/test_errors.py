"""Errors reach Python as exceptions with the library's messages: FILE:LINE for files and
scripts, the status cause for a stopped world, limits by name."""
import numpy as np
import pytest

import wobble
from conftest import no_ground


def test_a_bad_object_file_names_its_line(tmp_path, data):
    bad = tmp_path / "bad.obj"
    bad.write_text((data / "table.obj").read_text().replace("\nmass   0 100 50", "\nmass   0 100 fifty"))
    with pytest.raises(wobble.ParseError, match=r"bad\.obj:\d+"):
        wobble.load_body(str(bad), [str(data / "table_modes.def")])
    with pytest.raises(wobble.InputError):  # ParseError is a kind of InputError, and a ValueError
        wobble.load_body(str(bad))
    with pytest.raises(ValueError):
        wobble.load_body(str(tmp_path / "missing.obj"))


def test_dependent_modes_are_refused_as_the_cli_refuses_them(data):
    dup = data.parent / "tests" / "cli" / "duplicate_bend.def"
    with pytest.raises(wobble.InputError, match="cannot be simulated"):
        wobble.load_body(str(data / "table.obj"), [str(data / "table_modes.def"), str(dup)])


def test_states_of_the_wrong_size_or_not_finite(table):
    world = wobble.World()
    world.add_body(table)
    with pytest.raises(wobble.InputError, match=r"expected shape \(7,\)"):
        world.set_state(0, [0, 1, 2])
    with pytest.raises(wobble.InputError, match="finite"):
        world.set_state(0, [0, np.inf, 0, 0, 0, 0, 0])
    with pytest.raises(wobble.InputError, match="bodies"):
        world.q(3)
    with pytest.raises(wobble.InputError, match="integrator"):
        wobble.WorldOptions(integrator="euler")
    with pytest.raises(TypeError, match="no field"):
        wobble.WorldOptions(dtt=0.1)


def test_a_stopped_world_raises_with_its_cause_and_keeps_the_record(table):
    world = wobble.World(wobble.WorldOptions(dt=0.01))
    world.add_body(table)
    world.set_state(0, [0, 10, 0, 0, 0, 0, 0], [0, -1e7, 0, 0, 0, 0, 0])
    with pytest.raises(wobble.SimulationStopped) as stop:
        wobble.simulate(world, 1.0)
    e = stop.value
    assert isinstance(e, wobble.NumericalStop) and isinstance(e, RuntimeError)
    assert e.cause == world.status.cause != "ok"
    assert e.step >= 1 and e.cause in str(e)
    assert len(e.trajectory) >= 1 and np.all(np.isfinite(e.trajectory.array))
    # a stopped world stays stopped, with the same status
    with pytest.raises(wobble.SimulationStopped):
        world.step()


def test_limits_are_named(table):
    world = wobble.World(no_ground())
    world.add_body(table)
    with pytest.raises(wobble.LimitExceeded, match="max_steps"):
        wobble.simulate(world, 1e9)
    with pytest.raises(wobble.LimitExceeded, match="max_record_mb"):
        wobble.simulate(world, 100.0, max_record_mb=0.01)
    with pytest.raises(wobble.InputError):
        world.step(-1)


def test_script_errors_name_the_script_and_line(data):
    interp = wobble.Interpreter()
    with pytest.raises(wobble.ParseError, match=r"<python>:2"):
        interp.run(f"load_obj {data}/table.obj\nfrobnicate 3\n")
    with pytest.raises(wobble.ParseError, match=r"typo\.wob:\d+"):
        interp.run_file(str(data.parent / "tests" / "cli" / "typo.wob"))
