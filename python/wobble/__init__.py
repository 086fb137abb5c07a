"""wobble: soft, cartoon-like characters by dynamic free-form deformation.

Faloutsos (1995) FFD characters and Witkin & Welch (1990) bodies, from the C++ library
libwobble. A body is loaded from an object file and mode files; a World steps it; simulate()
records a Trajectory; rollout() runs many trials on every core; Interpreter runs wobble scripts.

    import wobble
    table = wobble.load_body("data/table.obj", ["data/table_modes.def"])
    world = wobble.World(wobble.WorldOptions(dt=0.01))
    world.add_body(table)
    world.set_state(0, [0, 50, 0, 0, 0, 0, 0])
    run = wobble.simulate(world, 10.0)
    print(run.q()[-1], run.column("total")[-1])
"""
import warnings as _warnings

from ._wobble import *  # noqa: F401,F403  (the extension's names are the package's)
from ._wobble import BodyModel, Ground, RolloutGradient, StageCost, WorldOptions, __doc__ as _extension_doc  # noqa: F401

__version__ = "0.2"


def _keyword_init(cls):
    """Lets cls(**fields) set any of its attributes (WorldOptions(dt=0.01, integrator="rk4"))."""
    plain_init = cls.__init__

    def __init__(self, **fields):
        plain_init(self)
        for name, value in fields.items():
            if name.startswith("_") or not hasattr(self, name):
                raise TypeError(f"{cls.__name__} has no field {name!r}")
            setattr(self, name, value)

    __init__.__doc__ = f"{cls.__name__}(**fields): every field can be given by keyword."
    cls.__init__ = __init__
    return cls


def _repr_fields(cls, names):
    def __repr__(self):
        return f"{cls.__name__}(" + ", ".join(f"{n}={getattr(self, n)!r}" for n in names) + ")"

    cls.__repr__ = __repr__


_keyword_init(Ground)
_keyword_init(WorldOptions)
_repr_fields(WorldOptions, ["dt", "integrator", "gravity_on", "max_condition", "feedback_rate"])
_repr_fields(Ground, ["enabled", "slope", "stiffness", "normal_damping", "friction_damping", "friction_cap"])

# Show the package, not the extension, in reprs and tracebacks (wobble.World, not wobble._wobble.World).
for _name, _obj in list(globals().items()):
    if isinstance(_obj, type) and getattr(_obj, "__module__", "") == "wobble._wobble":
        _obj.__module__ = "wobble"

# Names of before kept one release more (__init__.pyi marks them): each warns
# DeprecationWarning when read and is the object named (the same class, for isinstance).
_DEPRECATED = {
    "BodyModel3": ("BodyModel", BodyModel, "which is one class for 2D and 3D bodies (its dim says which)"),
    "StageCost3": ("StageCost", StageCost, "which takes a body of either dimension"),
    "RolloutGradient3": ("RolloutGradient", RolloutGradient, "which serves both dimensions"),
}


def __getattr__(name):
    if name in _DEPRECATED:
        new_name, obj, why = _DEPRECATED[name]
        _warnings.warn(f"wobble.{name} is deprecated: use wobble.{new_name}, {why}", DeprecationWarning, stacklevel=2)
        return obj
    raise AttributeError(f"module 'wobble' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_DEPRECATED))
