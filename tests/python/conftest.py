"""Shared fixtures of the Python tests: the data folder, the table of Fig. 1.2, the CLI."""
import os
import pathlib

import pytest

import wobble

DATA = pathlib.Path(os.environ.get("WOBBLE_DATA", pathlib.Path(__file__).resolve().parents[2] / "data"))


@pytest.fixture(scope="session")
def data():
    return DATA


@pytest.fixture(scope="session")
def table():
    return wobble.load_body(str(DATA / "table.obj"), [str(DATA / "table_modes.def")])


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("WOBBLE_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("WOBBLE_CLI (the wobble command line) is not built")
    return path


def no_ground(integrator="thesis", dt=0.01, gravity=True):
    options = wobble.WorldOptions(dt=dt, integrator=integrator, gravity_on=gravity)
    options.ground.enabled = False
    return options


def bounding_table(data, script="bounding_table.wob"):
    """An Interpreter that ran data/bounding_table.wob (or data/bounding_table3.wob, the 3D
    table) up to (not including) its anneal: the synthesis problem of §5.2."""
    interp = wobble.Interpreter()
    lines = []
    for line in (data / script).read_text().splitlines():
        if line.startswith("anneal"):
            break
        lines.append(line)
    interp.run("\n".join(lines), name=str(data / script), dir=str(data))
    return interp
