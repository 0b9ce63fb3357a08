"""
mindyn C++ core: models, linear-in-parameters dynamics, kinematics
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
import typing
__all__: list[str] = ['ArgumentError', 'BaseDynamics', 'BaseParameters', 'Error', 'IkSolver', 'Integrator', 'Kinematics', 'Model', 'ModelError', 'MomentumObserver', 'OFFSET_PREFIX', 'RobotFileNotFoundError', 'STFunctionBlock', 'STProgram', 'STVariable', 'base_parameters', 'classical_parameter_names', 'coriolis_matrix', 'from_pinocchio_order', 'generate_code', 'generate_controller', 'generate_observer', 'inertial_from_com', 'inertial_from_urdf', 'influence_coordinates', 'khalil_order', 'link_poses', 'load_urdf', 'load_yaml', 'multibody_coriolis_matrix', 'multibody_energies', 'multibody_forward_dynamics', 'multibody_frame_jacobian', 'multibody_inverse_dynamics', 'multibody_link_poses', 'multibody_mass_matrix', 'multibody_momentum', 'multibody_regressor', 'multibody_slotine_li_regressor', 'parse_csv_numbers', 'parse_urdf', 'parse_yaml', 'planar_arm', 'pose_error', 'projection_cost', 'projection_limits', 'projection_refusal', 'recursive_refusal', 'slotine_li_regressor', 'slotine_li_regressor_classical', 'snap_changes', 'sole_joints', 'sosfilt_rows', 'to_pinocchio_order', 'tool_jacobian']
class Error(Exception):
    """
    Base class of the errors mindyn raises.
    """
class ModelError(Error, ValueError):
    pass
class ArgumentError(Error, ValueError, TypeError):
    pass
class RobotFileNotFoundError(Error, FileNotFoundError):
    pass
class Model:
    def energies(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> typing.Any:
        ...
    def energy_regressors(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], rotor: bool = False, friction: bool = False, offset: bool = False) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        ...
    def forward_dynamics(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def friction_shapes(self, dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        """
        The friction columns of each slot at the slot velocities `dq`, (n, c) or (m, n, c).
        """
    def gravity_torque(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def inverse_dynamics(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def joint_post(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 fixed transform from the moved joint frame to link k (0-based k).
        """
    def joint_pre(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 fixed transform from link k-1 to the frame of joint k (0-based k).
        """
    def joint_transform(self, arg0: typing.SupportsInt | typing.SupportsIndex, arg1: typing.SupportsFloat | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        ...
    def mass_matrix(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def momentum_regressors(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], rotor: bool = False, friction: bool = False, offset: bool = False) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        ...
    def parameter_names(self, rotor: bool = False, friction: bool = False, offset: bool = False) -> list[str]:
        ...
    def parameters(self, rotor: bool = False, friction: bool = False, offset: bool = False) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    def regressor(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], rotor: bool = False, friction: bool = False, offset: bool = False) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def with_drive_of(self, other: Model) -> Model:
        """
        A new model with the joints of this one and the transmissions, drive side and friction model of `other` (a model of as many joints); this one is unchanged.
        """
    def with_drive_side(self, side: str) -> Model:
        """
        A new model whose rotor inertia and friction act on the motors ('motor') or on the joints ('joint'); this one is unchanged.
        """
    def with_friction_model(self, kind: str, velocity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = ...) -> Model:
        """
        A new model with this friction model (coulomb | asymmetric | smooth | stribeck; smooth and stribeck need a positive velocity per slot); this one is unchanged.
        """
    def with_gravity(self, gravity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]) -> Model:
        """
        A new model, the same but for its gravity vector (base frame, m/s^2); this one is unchanged.
        """
    def with_joint_terms(self, *, rotor: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, viscous: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, coulomb: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, motor_rotor: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, motor_viscous: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, motor_coulomb: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, motor_third: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, offset: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> Model:
        """
        A new model with the given joint-side rotor inertia, viscous and Coulomb friction (n each), the motors' own (n_m each, as a YAML table's transmissions give them; NaN: none, derived from the joint's), the motors' own third friction parameters (n_m, NaN: none) and torque offsets (n); a term not given is kept. This one is unchanged.
        """
    def with_spherical(self, names: collections.abc.Sequence[str]) -> Model:
        """
        A new model, the same but with the named floating (free-flyer) joints made spherical: the rotation about the same joint frame's origin, without translation (a ball joint, which URDF text cannot carry); this one is unchanged.
        """
    def with_transmission(self, *, T: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], motors: collections.abc.Sequence[str], types: collections.abc.Sequence[str], format: str) -> Model:
        """
        A new model with the transmission q_m = T q (no offsets, no torque constants) of the named motors, each of its `types`, and the rotor inertia and friction on them; this one is unchanged.
        """
    @property
    def axes(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @property
    def convention(self) -> str:
        ...
    @property
    def coulomb(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @coulomb.setter
    def coulomb(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def dh(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @property
    def drive_side(self) -> str:
        ...
    @property
    def drives(self) -> list:
        ...
    @property
    def friction_model(self) -> dict:
        ...
    @property
    def gravity(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
    @property
    def inertial(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @inertial.setter
    def inertial(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def joint_names(self) -> list[str]:
        ...
    @property
    def joint_types(self) -> list[str]:
        ...
    @property
    def limits(self) -> list:
        ...
    @property
    def link_names(self) -> list[str]:
        ...
    @property
    def n(self) -> int:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def notes(self) -> str:
        ...
    @property
    def nq(self) -> int:
        ...
    @property
    def nv(self) -> int:
        ...
    @property
    def parents(self) -> list[int]:
        ...
    @property
    def rotor_inertia(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @rotor_inertia.setter
    def rotor_inertia(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def single_dof(self) -> bool:
        ...
    @property
    def source(self) -> str:
        ...
    @property
    def synthetic_inertia(self) -> bool:
        ...
    @property
    def third_friction(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @third_friction.setter
    def third_friction(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def tool(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        ...
    @property
    def torque_offset(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def transmission(self) -> dict:
        ...
    @property
    def unread_transmissions(self) -> list:
        ...
    @property
    def viscous(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @viscous.setter
    def viscous(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
class Kinematics:
    def __init__(self, arg0: Model) -> None:
        ...
    def jacobian(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    def pose(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], link: typing.SupportsInt | typing.SupportsIndex = -1) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        ...
class BaseParameters:
    def embed(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    def energy_regressor(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def momentum_regressors(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        ...
    def regressor(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def set_formulas(self, set: str) -> list[str]:
        """
        A set's formulas at full precision.
        """
    def set_matrix(self, set: str) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        """
        Y of a set ('lagrangian', 'energy', 'eom'), dense.
        """
    def set_rows(self, set: str, first: typing.SupportsInt | typing.SupportsIndex, count: typing.SupportsInt | typing.SupportsIndex) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"], list[int]]:
        """
        Rows first .. first + count - 1 of a set's Y on the columns where they have entries: (dense rows, those columns).
        """
    def values(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    def with_friction_velocity(self, velocity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> BaseParameters:
        """
        The same base set for the model with its friction model's velocity scale replaced.
        """
    @property
    def Y(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @property
    def basis_rows(self) -> int:
        ...
    @property
    def classical_names(self) -> list[str]:
        ...
    @property
    def energy(self) -> dict:
        ...
    @property
    def eom(self) -> dict:
        ...
    @property
    def formulas(self) -> list[str]:
        ...
    @property
    def friction(self) -> bool:
        ...
    @property
    def lagrangian(self) -> dict:
        ...
    @property
    def lagrangian_equals_energy(self) -> bool:
        ...
    @property
    def lagrangian_equals_eom(self) -> bool:
        ...
    @property
    def method(self) -> str:
        ...
    @property
    def model(self) -> Model:
        ...
    @property
    def n(self) -> int:
        ...
    @property
    def names(self) -> list[str]:
        ...
    @property
    def offset(self) -> bool:
        ...
    @property
    def pivots(self) -> list[int]:
        ...
    @property
    def rotor(self) -> bool:
        ...
    @property
    def seconds(self) -> float:
        ...
    @property
    def snappable(self) -> list[str]:
        ...
    @property
    def snapped(self) -> list[str]:
        ...
    @property
    def terms_formed(self) -> int:
        ...
class Integrator:
    def __init__(self, model: Model, params: typing.Any = None, coulomb_smoothing: typing.SupportsFloat | typing.SupportsIndex = 0.0) -> None:
        """
        RK4 of the forward dynamics with the torque held (mindyn::Integrator) for the classical parameters `params` in any layout (default the model's).
        """
    def acceleration(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        """
        Forward dynamics of the simulated robot (Coulomb friction as in step).
        """
    def step(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dt: typing.SupportsFloat | typing.SupportsIndex, substeps: typing.SupportsInt | typing.SupportsIndex = 1) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]]:
        """
        Advances (q, dq) by dt seconds in `substeps` RK4 steps with tau held; returns them.
        """
class IkSolver:
    def __init__(self, model: Model, tolerance: typing.SupportsFloat | typing.SupportsIndex = 1e-05, max_iterations: typing.SupportsInt | typing.SupportsIndex = 100, max_attempts: typing.SupportsInt | typing.SupportsIndex = 100, max_time: typing.SupportsFloat | typing.SupportsIndex = 0.005, orientation_weight: typing.SupportsFloat | typing.SupportsIndex = 0.3, seed: typing.SupportsInt | typing.SupportsIndex = 42) -> None:
        ...
    def jacobian(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    def pose(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        ...
    def solve(self, target: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"], q0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> dict:
        ...
    @property
    def lower(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def upper(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
class MomentumObserver:
    @staticmethod
    def default_gain(period: typing.SupportsFloat | typing.SupportsIndex) -> float:
        ...
    def __init__(self, base: BaseParameters, values: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], gains: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], period: typing.SupportsFloat | typing.SupportsIndex, offset: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], held_torque: bool = True) -> None:
        ...
    def reset(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    def run(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], t: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
        """
        Residual of every sample (m, n) of a log of m samples at the observer's period (or at the time stamps t): reset at sample 0 (r = 0), step at the others.
        """
    def step(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def beta(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def gains(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def integral(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def momentum(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def period(self) -> float:
        ...
    @property
    def residual(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
class STVariable:
    """
    A variable of a generated FUNCTION_BLOCK: name, IEC 61131-3 elementary type (LREAL, BOOL), array bounds (lower, upper) per dimension.
    """
    def __repr__(self) -> str:
        ...
    @property
    def declared_type(self) -> str:
        """
        The declaration's type (ARRAY[1..6] OF LREAL).
        """
    @property
    def dims(self) -> list[tuple[int, int]]:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def type(self) -> str:
        ...
class STFunctionBlock:
    """
    A generated FUNCTION_BLOCK: name, inputs (VAR_INPUT), outputs (VAR_OUTPUT), locals (VAR), a note (comment after the declarations) and the body's statements.
    """
    def __repr__(self) -> str:
        ...
    @property
    def body(self) -> str:
        ...
    @property
    def inputs(self) -> list[STVariable]:
        ...
    @property
    def locals(self) -> list[STVariable]:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def note(self) -> str:
        ...
    @property
    def outputs(self) -> list[STVariable]:
        ...
class STProgram:
    """
    A generated Structured Text program as blocks: the comments before the function blocks, and the blocks.
    """
    def __repr__(self) -> str:
        ...
    def text(self) -> str:
        """
        The Structured Text the generator writes for these blocks.
        """
    @property
    def blocks(self) -> list[STFunctionBlock]:
        ...
    @property
    def comments(self) -> list[str]:
        ...
class BaseDynamics:
    def __init__(self, base: BaseParameters, offset: bool = False) -> None:
        ...
    def gravity(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], p: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def inverse_dynamics(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], p: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    def regressor(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
        ...
    @property
    def counts(self) -> dict:
        ...
    @property
    def geometry_snap(self) -> dict:
        """
        Constants of the geometry within `tolerance` of 0 or +-1 taken as exact: how many beyond round-off (`count`) and the largest change (`largest`).
        """
    @property
    def n(self) -> int:
        ...
    @property
    def names(self) -> list[str]:
        ...
    @property
    def np(self) -> int:
        ...
def base_parameters(model: Model, rotor: bool = False, friction: bool = False, method: str = 'projection', order: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex] = [], tolerance: typing.SupportsFloat | typing.SupportsIndex = 1e-09, samples: typing.SupportsInt | typing.SupportsIndex = 0, seed: typing.SupportsInt | typing.SupportsIndex = 1, snap: typing.SupportsFloat | typing.SupportsIndex = 0.0, offset: bool = False) -> BaseParameters:
    ...
def classical_parameter_names(model: Model, rotor: bool = False, friction: bool = False, offset: bool = False) -> list[str]:
    """
    The classical parameters generated code takes (friction in the model's friction model; the torque offsets last).
    """
def coriolis_matrix(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], params: typing.Any = None) -> numpy.typing.NDArray[numpy.float64]:
    ...
def from_pinocchio_order(arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def generate_code(model: Model, base: BaseParameters, rotor: bool = False, friction: bool = False, functions: collections.abc.Sequence[str] = ['inverse_dynamics'], name: str = 'robot', numeric: bool = False, values: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None, lang: str = 'c', header_name: str = 'robot.h', minimise: str = 'operations', inline_trig: bool = True, offset: bool = False, formulas: collections.abc.Sequence[str] | None = None, contacts: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex] = [], world_wrenches: bool = True) -> dict:
    """
    Generated code and operation counts. base=None: the classical parameters; offset: a torque offset per joint after them; formulas: the text of each base parameter's formula in the header comment (default: full precision); contacts: the links (joint indices) whose wrenches a floating base's inverse dynamics takes, in world axes or (world_wrenches=False) the links' own.
    """
def generate_controller(base: BaseParameters, offset: bool, kind: str, name: str, settings: dict, lang: str = 'c', header_name: str = 'controller.h', inline_trig: bool = True, model: Model = None) -> dict:
    """
    A generated controller step (adaptive-pd, computed-torque, gravity-compensation) and its operation counts.
    """
def generate_observer(base: BaseParameters, offset: bool, name: str, p: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], gains: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], period: typing.SupportsFloat | typing.SupportsIndex, held_torque: bool = True, lang: str = 'c', header_name: str = 'observer.h', inline_trig: bool = True) -> dict:
    """
    A generated momentum-observer step and its operation counts.
    """
def inertial_from_com(mass: typing.SupportsFloat | typing.SupportsIndex, com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"], inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def inertial_from_urdf(mass: typing.SupportsFloat | typing.SupportsIndex, com: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"], rotation: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"], inertia: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def influence_coordinates(model: Model, rotor: bool = False) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"], list[str]]:
    """
    Z (rows x 10n or 11n) and the basis function of each row, as text.
    """
def khalil_order(arg0: typing.SupportsInt | typing.SupportsIndex, arg1: bool, arg2: bool) -> list[int]:
    ...
def link_poses(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> list[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]]:
    ...
def load_urdf(path: str, tip: str = '', root_joint: str = '') -> Model:
    ...
def load_yaml(arg0: str) -> Model:
    ...
def multibody_coriolis_matrix(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    ...
def multibody_energies(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> tuple[float, float]:
    ...
def multibody_forward_dynamics(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], tau: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def multibody_frame_jacobian(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], link: typing.SupportsInt | typing.SupportsIndex, placement: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"], local: bool) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    """
    The Jacobian (6 x nv, linear rows first) of the frame at `placement` (4x4) in link `link`: base axes, or the frame's own (local).
    """
def multibody_inverse_dynamics(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], a: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def multibody_link_poses(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> list[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]]:
    """
    The pose of every link in the base frame (n 4x4).
    """
def multibody_mass_matrix(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    ...
def multibody_momentum(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], params: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    """
    The system's momentum (linear; angular about the base origin), base axes.
    """
def multibody_regressor(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], a: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    ...
def multibody_slotine_li_regressor(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], v: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], vr: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], ar: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    ...
def parse_csv_numbers(data: bytes, columns: typing.SupportsInt | typing.SupportsIndex) -> typing.Any:
    """
    The rows of `data` (bytes: lines of `columns` comma-separated decimal numbers, blanks around them, LF or CR LF line ends, lines of blanks skipped) as an array (rows, columns), each value correctly rounded as Python's float() gives it; None when anything else is met (another character or spelling, a row of another length, a value out of the range of a double).
    """
def parse_urdf(xml: str, tip: str = '', source: str = '<string>') -> Model:
    ...
def parse_yaml(text: str, source: str = '<string>') -> Model:
    ...
def planar_arm(n: typing.SupportsInt | typing.SupportsIndex, vertical: bool = True, length: typing.SupportsFloat | typing.SupportsIndex = 0.5, mass: typing.SupportsFloat | typing.SupportsIndex = 2.0) -> Model:
    ...
def pose_error(T: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"], target: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    """
    The twist (p_target - p, rotation vector of R_target R^T) taking T onto target (the pose error of the inverse kinematics).
    """
def projection_cost(model: Model, rotor: bool = False) -> dict:
    """
    Upper bounds of what the projection method forms (terms, rows, entries) and its memory estimate in bytes, counted on sparsity patterns before computing; `budget`: the limit.
    """
def projection_limits() -> dict:
    """
    The projection method's limits, as projection_refusal checks them: most joints on a chain, on a tree and on one root path of a tree, most parameters, the memory budget in bytes.
    """
def projection_refusal(model: Model, rotor: bool = False, friction: bool = False) -> typing.Any:
    """
    Why the projection method cannot take the model with these joint terms (its joint, parameter and memory limits, checked before computing), or None when it can.
    """
def recursive_refusal(model: Model, rotor: bool = False, friction: bool = False) -> typing.Any:
    """
    Why the recursive method cannot take the model with these joint terms (rotor inertia of a motor coupling joints whose coupled energy it cannot prove independent of the links'), or None when it can.
    """
def slotine_li_regressor(base: BaseParameters, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dqr: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddqr: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
    """
    Base Slotine-Li regressor Y_b (n, nb) or (m, n, nb): Y_b p_b = A ddqr + C dqr + c (+ friction).
    """
def slotine_li_regressor_classical(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], dqr: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], ddqr: typing.Annotated[numpy.typing.ArrayLike, numpy.float64], rotor: bool = False, friction: bool = False) -> numpy.typing.NDArray[numpy.float64]:
    ...
def snap_changes(model: Model, tolerance: typing.SupportsFloat | typing.SupportsIndex = 0.001) -> tuple[list, list[str]]:
    """
    What a snap of `tolerance` [rad] would round in the model (which is unchanged): each angle and axis component rounded (dicts: joint, joint_name, frame 'origin' | 'link frame' | 'axis', component 'yaw' | 'pitch' | 'roll' | 'x' | 'y' | 'z', value, snapped, deviation) and the lines of text that describe the changes.
    """
def sole_joints(T: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> list[int]:
    """
    Per motor (row of the transmission T), the joint it alone drives and drives alone, or -1 (it turns with several joints, or another motor turns that joint too): the motors whose rotor inertia and friction a joint can carry.
    """
def sosfilt_rows(sos: numpy.ndarray, x: numpy.ndarray, z: numpy.ndarray, cols: typing.Any = None, out: typing.Any = None) -> None:
    """
    Second-order sections `sos` (sections, 6; a0 = 1) run down the rows of `x` (samples, columns; rows in any order, e.g. reversed, columns adjacent), on the columns `cols` of `x` (all when None), from the state `z` (sections, 2, columns), which is updated in place; the output is written into `out` (samples, columns; it may be `x` itself) unless None. Per column the values are scipy.signal.sosfilt's.
    """
def to_pinocchio_order(arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    ...
def tool_jacobian(model: Model, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    ...
OFFSET_PREFIX: str = 'Off'
