"""Generated inverse-dynamics code (C99, IEC 61131-3 Structured Text) and the runtime
base-parameter dynamics.

The generator writes the Newton-Euler recursion of a robot into an expression graph, customised
to the model: exact zeros and ones of the geometry, the base parameters at their pivot positions
of the classical vector (every other entry exactly zero), constant folding, removal of
multiplications by 0 and +-1, common-subexpression elimination and dead-code removal. Three
functions can be generated: ``inverse_dynamics`` (tau from q, dq, ddq and p), ``gravity``
(tau from q and p) and ``regressor`` (W_b with tau = W_b p).

Controller steps (:func:`generate_controller`): the Slotine-Li adaptive PD of
:class:`mindyn.control.AdaptivePD` with ``Y p`` and ``Y^T s`` generated from the Slotine-Li
recursion customised the same way (the regressor's columns, or the adjoint pass of ``s^T Y p``,
whichever needs fewer operations), computed torque and PD with gravity compensation, as a C99 state
struct with init and step functions or one Structured Text FUNCTION_BLOCK holding the estimate;
:class:`CompiledController` runs the C step in :func:`mindyn.control.simulate`, and
:func:`plcopen_project` packs Structured Text function blocks into a PLCopen XML project.

The momentum observer (:func:`generate_observer`): the step of
:class:`mindyn.control.MomentumObserver` with ``p = A(q) dq`` and ``beta = -dL/dq + friction +
offset`` from one momentum pass customised to the robot, to run beside a controller step;
:class:`CompiledObserver` calls the C step.

The modules, one concern each: :mod:`~mindyn.codegen.generation` (:func:`generate`,
:class:`GeneratedCode`), :mod:`~mindyn.codegen.parameters` (:func:`read_parameter_file`,
:func:`read_identified_parameters`),
:mod:`~mindyn.codegen.dynamics` (:class:`BaseDynamics`), :mod:`~mindyn.codegen.controllers`
(:func:`generate_controller`, :func:`generate_observer`), :mod:`~mindyn.codegen.compiled`
(:class:`CompiledController`, :class:`CompiledObserver`) and :mod:`~mindyn.codegen.plcopen`
(:func:`plcopen_project`). Structured Text comes with its blocks
(:attr:`GeneratedCode.program`, a :class:`mindyn._core.STProgram`), from which the C++ core
writes the text and :func:`plcopen_project` the PLCopen XML.
"""

from .compiled import CompiledController, CompiledObserver
from .controllers import (
    CONTROLLERS,
    GeneratedController,
    GeneratedObserver,
    generate_controller,
    generate_observer,
)
from .dynamics import BaseDynamics
from .generation import FUNCTIONS, GeneratedCode, generate
from .parameters import read_identified_parameters, read_parameter_file
from .plcopen import PLCOPEN_NS, plcopen_project

__all__ = [
    "CONTROLLERS",
    "FUNCTIONS",
    "PLCOPEN_NS",
    "BaseDynamics",
    "CompiledController",
    "CompiledObserver",
    "GeneratedCode",
    "GeneratedController",
    "GeneratedObserver",
    "generate",
    "generate_controller",
    "generate_observer",
    "plcopen_project",
    "read_identified_parameters",
    "read_parameter_file",
]
