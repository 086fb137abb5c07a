# Type stub of the wobble package (the extension wobble._wobble and __init__.py), for editors
# and type checkers. tests/python/test_api.py checks that it names exactly what the module has.
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str
ArrayLike = npt.ArrayLike
NDArray = npt.NDArray[np.float64]

class InputError(ValueError): ...
class ParseError(InputError): ...
class LimitExceeded(InputError): ...
class NumericalStop(RuntimeError): ...
class BehaviourError(RuntimeError): ...
class SimulationStopped(NumericalStop):
    cause: str
    step: int
    time: float
    body: int
    trajectory: "Trajectory"

class DeformationMode:
    name: str
    stiffness: float
    damping: float
    active: bool
    source: str
    displacement: NDArray

class BodyModel:
    """An FFD character of either dimension: 2D q = [tx, ty, θ, γ...]; 3D (in a World) q = [tx, ty, tz,
    rx, ry, rz, γ...], q̇ = [v, body ω, γ̇...]. outline is 2D only, the mesh 3D only (InputError)."""
    name: str
    dim: int  # 2 or 3
    num_modes: int
    num_q: int
    num_points: int
    modes: list[DeformationMode]
    mode_names: list[str]
    total_mass: float
    masses: NDArray
    mass_positions: NDArray  # (num_points, dim)
    rest_control: NDArray  # (control points, dim)
    lattice_shape: tuple[int, ...]  # (num_s, num_t), 3D (num_s, num_t, num_u)
    def outline(self, q: Optional[ArrayLike] = None, samples_per_segment: int = 8) -> list[NDArray]: ...
    mesh_points: NDArray
    mesh_triangles: NDArray
    def mesh_vertices(self, q: Optional[ArrayLike] = None) -> NDArray: ...
    def mass_points_at(self, q: Optional[ArrayLike] = None) -> NDArray: ...

class LinearBodyModel:
    name: str
    dim: int
    order: str
    basis_size: int
    num_points: int
    total_mass: float
    mass_matrix: NDArray
    points: NDArray
    masses: list[float]
    def rest_state(self) -> NDArray: ...

def linear_box(dim: int, half_extents: ArrayLike, *, per_side: int = 2, mass: float = 1.0, order: str = "affine",
               name: str = "box") -> LinearBodyModel: ...
def linear_pyramid(dim: int, half_width: float, height: float, *, levels: int = 3, per_side: int = 2,
                   mass: float = 1.0, order: str = "affine", name: str = "pyramid") -> LinearBodyModel: ...
def linear_body(points: ArrayLike, masses: Sequence[float], *, order: str = "affine",
                name: str = "body") -> LinearBodyModel: ...

def load_body(object: str, modes: Sequence[str] = ..., check: bool = True) -> BodyModel:
    """A 2D or 3D body (its dim), as the object file's `dimension` says."""

def load_body3(object: str, modes: Sequence[str] = ..., check: bool = True) -> BodyModel:
    """Deprecated (warns DeprecationWarning; removed in the next release): load_body."""
class BodyModel3(BodyModel):
    """Deprecated (warns DeprecationWarning when read; removed in the next release): BodyModel itself,
    one class for 2D and 3D bodies (wobble.BodyModel3 is wobble.BodyModel)."""

class Ground:
    enabled: bool
    point: NDArray
    slope: float
    stiffness: float
    normal_damping: float
    friction_damping: float
    friction_cap: float
    max_penetration: float
    normal: NDArray
    tangent: NDArray
    def __init__(self, **fields: Any) -> None: ...

class Heightfield:
    """The 3D ground y = h(x, z) on a grid (two triangles per cell, level beyond it)."""
    origin: NDArray
    spacing: NDArray
    heights: NDArray
    def __init__(self, origin: ArrayLike, spacing: ArrayLike, heights: ArrayLike) -> None: ...
    def height_at(self, x: float, z: float) -> float: ...

def read_heightfield(path: str) -> Heightfield: ...

class GroundPlane:
    """The 3D FFD bodies' ground plane (penalty contact, capped friction); off by default."""
    enabled: bool
    point: NDArray
    normal: NDArray
    stiffness: float
    normal_damping: float
    friction_damping: float
    friction_cap: float
    heightfield: Optional[Heightfield]
    def __init__(self) -> None: ...

class WorldOptions:
    dt: float
    integrator: str
    gravity: NDArray  # x y z, for both dimensions (a 2D body feels x, y); set with 2 or 3 components
    gravity_on: bool
    ground: Ground  # what 2D bodies stand on
    ground_plane: GroundPlane  # what 3D bodies stand on
    ground_3d: GroundPlane  # deprecated (one release, warns): ground_plane
    gravity_3d: NDArray  # deprecated (one release, warns): gravity
    max_condition: float
    feedback_rate: float
    def __init__(self, **fields: Any) -> None: ...

class Energies:
    kinetic: float
    gravity: float
    modes: float
    ground: float
    springs: float
    per_mode: list[float]
    def total(self) -> float: ...

class WorldStatus:
    ok: bool
    cause: str
    step: int
    time: float
    body: int
    message: str

class Controller:
    """Subclass it in Python: before_step(world) and after_step(world) run around every step."""
    def __init__(self) -> None: ...
    def before_step(self, world: "World") -> None: ...
    def after_step(self, world: "World") -> None: ...

class PoseGraphController(Controller):
    pose: int
    steps: int
    def __init__(self, world: "World", body: int, graph: "PoseGraph", switch_width: float = 0.0) -> None: ...

class KeyframeController(Controller):
    def __init__(self, world: "World", body: int, times: Sequence[float], amplitudes: ArrayLike,
                 interpolation: str = "linear", hold: Optional[ArrayLike] = None) -> None: ...
    def finished(self) -> bool: ...
    def release(self, world: "World") -> None: ...

class Anchor:
    """A material point of a body, or a fixed place, that a behaviour looks at."""
    name: str
    @staticmethod
    def point(world: "World", body: int, mass_point: Optional[int] = None, *, u: Optional[ArrayLike] = None,
              name: str = "") -> "Anchor": ...
    @staticmethod
    def place(place: ArrayLike, *, name: str = "") -> "Anchor": ...
    def position(self, world: "World") -> NDArray: ...
    def velocity(self, world: "World") -> NDArray: ...

class Behaviours(Controller):
    """Goal behaviours (Witkin & Welch §4.2) run one after another before every step."""
    idle: bool
    pending: int
    current: Optional[str]
    names: dict[str, int]
    log: list[str]
    def __init__(self) -> None: ...
    def chase(self, chaser: Anchor, target: Anchor, duration: float, *,
              final_velocity: Optional[ArrayLike] = None) -> None: ...
    def connect(self, point: Anchor, target: Anchor, *, name: str = "") -> None: ...
    def grab(self, point: Anchor, target: Anchor, duration: float, *, final_velocity: Optional[ArrayLike] = None,
             name: str = "") -> None: ...
    def release(self, name: str) -> None: ...
    def switch(self, name: str, on: bool) -> None: ...
    def wait(self, duration: float) -> None: ...
    def impulse(self, point: Anchor, velocity: ArrayLike) -> None: ...
    def follow(self, point: Anchor, times: Sequence[float], positions: Sequence[ArrayLike], *, onset: float = 0.0,
               preroll: float = 0.0, name: str = "") -> None: ...
    def wait_for(self, description: str, predicate: Callable[["World"], bool]) -> None: ...

class WorldData:
    """Everything a World's steps change, apart from its model: World.data() takes a copy,
    World.set_data(d) puts one back (same bodies and constraints, else InputError)."""
    time: float
    steps: int
    def __init__(self, other: "WorldData") -> None: ...
    def __copy__(self) -> "WorldData": ...
    def __deepcopy__(self, memo: dict) -> "WorldData": ...

class World:
    num_bodies: int
    time: float
    steps: int
    options: WorldOptions
    status: WorldStatus
    def __init__(self, options: WorldOptions = ...) -> None: ...
    # Either dimension: a 3D body's q is [t, rotation vector r, γ], its q̇ [ṫ, body ω, γ̇].
    def add_body(self, body: BodyModel) -> int: ...
    def body(self, body: int) -> BodyModel: ...
    def q(self, body: int = 0) -> NDArray: ...
    def qd(self, body: int = 0) -> NDArray: ...
    def set_state(self, body: int, q: ArrayLike, qd: Optional[ArrayLike] = None) -> None: ...
    # Deprecated (each warns DeprecationWarning; removed in the next release): add_body, body,
    # q, qd, set_state under their old 3D names.
    def add_body3(self, body: BodyModel) -> int: ...
    def body3(self, body: int) -> BodyModel: ...
    def q3(self, body: int = 0) -> NDArray: ...
    def qd3(self, body: int = 0) -> NDArray: ...
    def set_state3(self, body: int, q: ArrayLike, qd: Optional[ArrayLike] = None) -> None: ...
    def set_mode_targets(self, body: int, targets: ArrayLike) -> None: ...
    def step(self, n: int = 1) -> None: ...
    def run_until(self, t_end: float) -> None: ...
    def energies(self, body: int = 0) -> Energies: ...
    def total_energy(self) -> float: ...
    def data(self) -> WorldData: ...
    def set_data(self, data: WorldData) -> None: ...
    def contacts(self, body: int = 0) -> tuple[npt.NDArray[np.int32], NDArray]: ...
    def penetration(self, body: int = 0) -> float: ...
    def point_positions(self, body: int = 0) -> NDArray: ...
    def forces(self, body: int = 0) -> dict[str, NDArray]: ...
    def accelerations(self, body: int = 0) -> NDArray: ...
    def add_nail(self, body: int, mass_point: Optional[int] = None, *, u: Optional[ArrayLike] = None,
                 where: Optional[ArrayLike] = None) -> int: ...
    def apply_point_force(self, body: int, mass_point: Optional[int] = None, *, u: Optional[ArrayLike] = None,
                          force: ArrayLike) -> None: ...
    def add_attachment(self, a: int, b: int, *, a_mass_point: Optional[int] = None, a_u: Optional[ArrayLike] = None,
                       b_mass_point: Optional[int] = None, b_u: Optional[ArrayLike] = None) -> int: ...
    def point_position(self, body: int, mass_point: Optional[int] = None, *, u: Optional[ArrayLike] = None) -> NDArray: ...
    def add_linear_body(self, model: LinearBodyModel, *, rigidity: float = 0.0, volume: float = 0.0,
                        damping: float = 0.0, bending: float = 0.0, ground: bool = False) -> int: ...
    def linear_contacts(self, body: int) -> list[tuple[int, int, NDArray]]: ...
    def linear_state(self, body: int) -> tuple[NDArray, NDArray]: ...
    def set_linear_state(self, body: int, R: ArrayLike, R_dot: Optional[ArrayLike] = None) -> None: ...
    def kind(self, body: int) -> str: ...
    def add_controller(self, controller: Controller) -> None: ...
    def remove_controller(self, controller: Controller) -> None: ...
    def set_enabled(self, id: int, enabled: bool) -> None: ...
    def max_violation(self) -> float: ...
    def constraint_error(self, id: int) -> NDArray: ...

class Trajectory:
    columns: list[str]
    num_bodies: int
    array: NDArray
    time: NDArray
    def __len__(self) -> int: ...
    def column(self, name: str) -> NDArray: ...
    def q(self, body: int = 0) -> NDArray: ...
    def qd(self, body: int = 0) -> NDArray: ...
    def write_csv(self, path: str) -> None: ...

def simulate(world: World, duration: float, *, every: int = 1, fps: float = 0.0, max_steps: int = ...,
             max_record_mb: float = ...) -> Trajectory: ...
def read_trajectory_csv(path: str, body: BodyModel) -> Trajectory: ...  # a 2D body

class RolloutResult:
    time: NDArray
    q: NDArray
    qd: NDArray
    energy: NDArray
    steps_taken: npt.NDArray[np.int64]
    status: list[str]
    messages: list[str]

def rollout(body: BodyModel, q0: ArrayLike, qd0: Optional[ArrayLike] = None, steps: int = 1, *,
            options: WorldOptions = ..., mode_targets: Optional[ArrayLike] = None, every: int = 1,
            threads: int = 0, energies: bool = False, max_steps: int = ...,
            max_record_mb: float = ...) -> RolloutResult: ...

class PoseGraph:
    poses: NDArray
    durations: list[float]
    cyclic: bool
    period: float
    def __init__(self, poses: ArrayLike, durations: Sequence[float], cyclic: bool = True) -> None: ...
    def pose_at(self, t: float) -> int: ...

class TrialOutcome:
    ok: bool
    distance: float
    speed: float
    energy: float
    cost: float
    failure: str

class SynthesisProblem:
    body: Optional[BodyModel]  # the body of either dimension
    body3: Optional[BodyModel]  # deprecated (DeprecationWarning): body
    options: WorldOptions
    q0: NDArray
    qd0: NDArray
    steps: int
    num_active: int
    def run(self, graph: PoseGraph) -> TrialOutcome: ...

class TrialResults:
    cost: NDArray
    distance: NDArray
    speed: NDArray
    energy: NDArray
    ok: npt.NDArray[np.bool_]
    failures: list[str]
    seconds: float

def run_trials(problem: SynthesisProblem, graphs: Union[Sequence[PoseGraph], ArrayLike],
               durations: Optional[ArrayLike] = None, *, cyclic: bool = True, threads: int = 0) -> TrialResults: ...

class AnnealResult:
    best: PoseGraph
    best_outcome: TrialOutcome
    initial_outcome: TrialOutcome
    trials: int
    interrupted: bool
    history: NDArray

def anneal(problem: SynthesisProblem, initial: PoseGraph, *, seed: int = 1, iterations: int = 60, batch: int = 1,
           cooling: float = 0.9, optimize: str = "both", threads: int = 0, max_steps: int = ...) -> AnnealResult: ...

# present when wobble was built with pagmo2 (Debian: libpagmo-dev)
def cmaes(problem: SynthesisProblem, initial: PoseGraph, *, seed: int = 1, generations: int = 60, population: int = 8,
          sigma0: float = 0.1, optimize: str = "both", max_steps: int = ...) -> AnnealResult: ...

class Interpreter:
    body: Optional[BodyModel]
    q: NDArray
    qd: NDArray
    time: float
    control_energy: float
    pose_graph: PoseGraph
    world_options: WorldOptions
    max_steps: int
    max_record_mb: float
    last_run: Optional[Trajectory]
    scene_record: Optional[Trajectory]
    last_anneal: Optional[AnnealResult]
    def __init__(self, echo: bool = False) -> None: ...
    def run_file(self, path: str) -> None: ...
    def run(self, text: str, name: str = "<python>", dir: str = ".") -> None: ...
    def take_output(self) -> str: ...
    def synthesis_problem(self) -> SynthesisProblem: ...
    def replay_script(self) -> str: ...
    @staticmethod
    def help() -> str: ...

class FitReport:
    usable: bool
    termination: str
    brief_report: str
    initial_cost: float
    final_cost: float
    cost_per_iteration: list[float]
    iterations: int
    solve_seconds: float

class FitConditioning:
    condition_number: float
    scaled_condition_number: float
    column_norms: list[float]
    undetermined: list[str]
    poorly_determined: list[str]

class PoseFitResult:
    q: NDArray
    report: FitReport
    point_residuals: list[float]
    rms_residual: float
    at_bound: list[str]
    conditioning: FitConditioning
    rounds: int

# Every fit takes a 3D body too (points (K, 3) / (F, K, 3), q = [t, rotation vector, γ]).
def fit_pose(body: BodyModel, points: ArrayLike, *, mass_points: Optional[Sequence[int]] = None,
             lattice_coords: Optional[ArrayLike] = None, weights: Optional[ArrayLike] = None,
             initial_q: Optional[ArrayLike] = None, loss: str = "squared", loss_scale: float = 1.0,
             prior_weight: float = 0.0, mode_bounds: tuple[float, float] = (-1.0, 1.0),
             max_iterations: int = 200) -> PoseFitResult: ...
class TrajectoryFitResult:
    times: list[float]
    q: NDArray
    report: FitReport
    frame_rms: list[float]
    rms_residual: float
    linear_solver: str

def fit_trajectory(body: BodyModel, times: ArrayLike, points: ArrayLike, mass_points: Sequence[int], *,
                   smoothness: float = 1.0, loss: str = "squared", loss_scale: float = 1.0, prior_weight: float = 0.0,
                   mode_bounds: tuple[float, float] = (-1.0, 1.0), max_iterations: int = 200) -> TrajectoryFitResult: ...

class DynamicParameters:
    q0: NDArray
    qd0: NDArray
    stiffness: NDArray
    damping: NDArray
    graph: PoseGraph

class DynamicFitResult:
    params: DynamicParameters
    report: FitReport
    rms_residual: float
    simulations: int

def fit_dynamic(body: BodyModel, times: ArrayLike, points: ArrayLike, mass_points: Sequence[int], *,
                q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None, stiffness: Optional[ArrayLike] = None,
                damping: Optional[ArrayLike] = None, graph: Optional[PoseGraph] = None, options: WorldOptions = ...,
                fit_q0: bool = True, fit_qd0: bool = True, fit_stiffness: bool = True, fit_damping: bool = True,
                fit_poses: bool = False, fit_times: bool = False, switch_width: float = 0.05,
                max_iterations: int = 50, gradient: str = "jets") -> DynamicFitResult: ...

class StageCost:
    """l_n(q, qd) of one step of a rollout of a 2D or a 3D body with its gradient: a task term, a sum
    (a + b), or StageCost(fn) with fn(n, q, qd) -> (value, dq, dqd) in World coordinates (3D: q = [t,
    rotation vector, gamma], qd = [t dot, body omega, gamma dot]). A term of a body serves that body's
    dimension; upright_at, still_at and a Python fn serve both; a sum serves what both terms do."""
    def __init__(self, fn: Callable[[int, NDArray, NDArray], tuple[float, Optional[ArrayLike], Optional[ArrayLike]]]) -> None: ...
    def __call__(self, n: int, q: ArrayLike, qd: ArrayLike, *, dim: int = 0) -> tuple[float, NDArray, NDArray]:
        """(value, dq, dqd) at step n; dim 2 or 3 picks the body's form (0: the cost's own, 2D when both)."""
    def __add__(self, other: StageCost) -> StageCost: ...

def centre_of_mass_at(body: BodyModel, step: int, goal: ArrayLike, *, weight: float = 1.0,
                      axes: str = ...) -> StageCost:
    """axes: 2D 'x', 'y', 'xy' (default 'xy'); 3D some of 'x', 'y', 'z' (default 'xyz')."""
def centre_of_mass_velocity_at(body: BodyModel, step: int, goal: ArrayLike, *, weight: float = 1.0,
                               axes: str = ...) -> StageCost: ...
def upright_at(step: int, *, weight: float = 1.0, time_scale: float = 0.0) -> StageCost:
    """2D w/2 (theta^2 + tau^2 thetadot^2); 3D w/2 (|R e_y - e_y|^2 + tau^2 |omega|^2). Serves both bodies."""
def still_at(step: int, *, weight: float = 1.0) -> StageCost:
    """w/2 |qd|^2. Serves both bodies."""

class RolloutGradient:
    """d cost / d each parameter; q0, qd0 in World coordinates (3D q0 = [t, rotation vector, gamma])."""
    ok: bool
    message: str
    cost: float
    q0: NDArray
    qd0: NDArray
    stiffness: NDArray
    damping: NDArray
    targets: NDArray
    states_held: int

def rollout_gradient(body: BodyModel, cost: StageCost, *, targets: ArrayLike,
                     options: WorldOptions = ..., q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None,
                     stiffness: Optional[ArrayLike] = None, damping: Optional[ArrayLike] = None,
                     checkpoint_interval: int = 0) -> RolloutGradient: ...
def rollout_cost(body: BodyModel, cost: StageCost, *, targets: ArrayLike, options: WorldOptions = ...,
                 q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None,
                 stiffness: Optional[ArrayLike] = None, damping: Optional[ArrayLike] = None) -> float: ...

class SpacetimeResult:
    ok: bool
    message: str
    knots: NDArray
    targets: NDArray
    initial_cost: float
    cost: float
    control_energy: float
    iterations: int
    gradients: int
    best_start: int
    start_costs: list[float]

def fit_spacetime(body: BodyModel, task: StageCost, *, targets: ArrayLike, knots: int = 21,
                  bound: float = 0.3, control_weight: float = 1.0, options: WorldOptions = ...,
                  q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None,
                  stiffness: Optional[ArrayLike] = None, damping: Optional[ArrayLike] = None,
                  max_iterations: int = 100, starts: int = 1, start_spread: float = 1.0, seed: int = 1,
                  threads: int = 0) -> SpacetimeResult: ...

# Deprecated (one release; issue 45): the 3D body's names of before. The functions warn
# (DeprecationWarning) and call the names above, which take either body; upright_at3 and still_at3
# give the 3D form only (as their StageCost3 did). The classes are the same class objects and
# warn when their old name is read, as BodyModel3 does.
class StageCost3(StageCost):
    """Deprecated: StageCost itself (it takes either body)."""
class RolloutGradient3(RolloutGradient):
    """Deprecated: RolloutGradient itself."""
def centre_of_mass_at3(body: BodyModel, step: int, goal: ArrayLike, *, weight: float = 1.0,
                       axes: str = "xyz") -> StageCost:
    """Deprecated: centre_of_mass_at."""
def centre_of_mass_velocity_at3(body: BodyModel, step: int, goal: ArrayLike, *, weight: float = 1.0,
                                axes: str = "xyz") -> StageCost:
    """Deprecated: centre_of_mass_velocity_at."""
def upright_at3(step: int, *, weight: float = 1.0, time_scale: float = 0.0) -> StageCost:
    """Deprecated: upright_at (its 3D form)."""
def still_at3(step: int, *, weight: float = 1.0) -> StageCost:
    """Deprecated: still_at (its 3D form)."""
def rollout_gradient3(body: BodyModel, cost: StageCost, *, targets: ArrayLike, options: WorldOptions = ...,
                      q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None,
                      stiffness: Optional[ArrayLike] = None, damping: Optional[ArrayLike] = None,
                      checkpoint_interval: int = 0) -> RolloutGradient:
    """Deprecated: rollout_gradient."""
def rollout_cost3(body: BodyModel, cost: StageCost, *, targets: ArrayLike, options: WorldOptions = ...,
                  q0: Optional[ArrayLike] = None, qd0: Optional[ArrayLike] = None,
                  stiffness: Optional[ArrayLike] = None, damping: Optional[ArrayLike] = None) -> float:
    """Deprecated: rollout_cost."""
def fit_spacetime3(body: BodyModel, task: StageCost, *, targets: ArrayLike, knots: int = 21, bound: float = 0.3,
                   control_weight: float = 1.0, options: WorldOptions = ..., q0: Optional[ArrayLike] = None,
                   qd0: Optional[ArrayLike] = None, stiffness: Optional[ArrayLike] = None,
                   damping: Optional[ArrayLike] = None, max_iterations: int = 100, starts: int = 1,
                   start_spread: float = 1.0, seed: int = 1, threads: int = 0) -> SpacetimeResult:
    """Deprecated: fit_spacetime."""
def write_target_schedule(path: str, modes: Sequence[str], dt: float, targets: ArrayLike) -> None: ...
def read_target_schedule(path: str, modes: Sequence[str], dt: float) -> NDArray: ...
# fit_pose_to_curves takes a 2D body, fit_pose_to_surface a 3D one (TypeError for the other dimension)
def fit_pose_to_curves(body: BodyModel, polylines: Sequence[ArrayLike], *, closed: bool = False,
                       initial_q: Optional[ArrayLike] = None, loss: str = "squared", loss_scale: float = 1.0,
                       prior_weight: float = 0.0, mode_bounds: tuple[float, float] = (-1.0, 1.0),
                       max_iterations: int = 200) -> PoseFitResult: ...
def fit_pose_to_surface(body: BodyModel, *, vertices: Optional[ArrayLike] = None, triangles: Optional[ArrayLike] = None,
                        cloud: Optional[ArrayLike] = None, initial_q: Optional[ArrayLike] = None, loss: str = "squared",
                        loss_scale: float = 1.0, prior_weight: float = 0.0,
                        mode_bounds: tuple[float, float] = (-1.0, 1.0), max_iterations: int = 200,
                        mesh_samples: int = 400, two_sided: bool = True) -> PoseFitResult: ...

class ConditionNumber:
    singular: bool
    cond: float
    cond_scaled: float
    singular_values: NDArray

class ModeSetReport:
    level: str
    messages: list[str]
    dofs: list[str]
    pair_angle_deg: NDArray
    smallest_angle_deg: float
    smallest_mode: str
    condition: ConditionNumber

# condition_number, mass_matrix and check_mode_set take a 2D body (TypeError for a 3D one)
def condition_number(body: BodyModel, q: Optional[ArrayLike] = None) -> ConditionNumber: ...
def mass_matrix(body: BodyModel, q: Optional[ArrayLike] = None) -> NDArray: ...
def angle_sweep(object: str, phis: Sequence[float], *, compress: float = 1.0,
                expand: float = 0.5) -> tuple[NDArray, NDArray]: ...
def check_mode_set(body: BodyModel) -> ModeSetReport: ...

# pictures (present when wobble was built with its VTK pipelines)
def has_display() -> bool: ...
def render_world(world: World, *, width: int = 640, height: int = 480, lattice: bool = True, points: bool = True,
                 shape: bool = True, ground: bool = True, overlay: bool = True, color_by: str = "",
                 frame: Optional[Sequence[float]] = None) -> npt.NDArray[np.uint8]: ...
def render(run: Trajectory, options: WorldOptions, folder: str, *, name: str = "run",
           what: Sequence[str] = ("frames", "filmstrip", "vtp"), fps: float = 30.0, width: int = 640,
           height: int = 480, filmstrip_times: Sequence[float] = (), color_by: str = "") -> list[str]: ...
