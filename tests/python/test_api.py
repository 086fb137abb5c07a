"""The module's surface: the stub names what the module has, everything public has a
docstring, and 10⁵ calls leak nothing."""
import ast
import pathlib
import resource

import numpy as np

import wobble

STUB = pathlib.Path(wobble.__file__).with_name("__init__.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
            for base in node.bases:  # a stub class has what its stub bases declare
                if isinstance(base, ast.Name) and base.id in members:
                    members[node.name] |= members[base.id]
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
    return top, members


def public(obj):
    return {n for n in dir(obj) if not n.startswith("_")}


def test_the_stub_names_exactly_what_the_module_has():
    top, members = stub_names()
    module = public(wobble) - {"Any"}
    assert module - top == set(), "in the module, not in the stub"
    optional = set() if hasattr(wobble, "render") else {"has_display", "render_world", "render"}  # built without VTK
    optional |= set() if hasattr(wobble, "cmaes") else {"cmaes"}  # built without pagmo
    assert top - module - {"ArrayLike", "NDArray", "__version__"} - optional == set(), "in the stub, not in the module"
    for name, names in members.items():
        cls = getattr(wobble, name)
        if issubclass(cls, BaseException):
            continue  # their attributes are set when raised
        assert public(cls) == {n for n in names if not n.startswith("_")}, name


def test_everything_public_has_a_docstring():
    for name in public(wobble):
        obj = getattr(wobble, name)
        if callable(obj):
            assert obj.__doc__, name


def rss_kib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() // 1024


def test_no_leak_over_a_hundred_thousand_calls(table):
    world = wobble.World()
    world.add_body(table)
    q = np.array([0, 50, 0, 0, 0, 0, 0.0])

    def calls(n):
        for _ in range(n):
            world.set_state(0, q)
            world.step()
            world.q(0)
            world.energies(0)
            world.contacts(0)

    calls(2000)  # warm up: allocator pools, caches
    before = rss_kib()
    calls(100_000)
    grown = rss_kib() - before
    # a leak of even 16 bytes a call would be 8 MiB here (five calls per round)
    assert grown < 2048, f"resident memory grew by {grown} KiB over 10^5 rounds"
