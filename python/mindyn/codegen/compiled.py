"""Generated C steps compiled with the system C compiler and called through ctypes: a
controller of :func:`mindyn.control.simulate` (:class:`CompiledController`) and the momentum
observer (:class:`CompiledObserver`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import _args, _core
from ..base import BaseParameters
from .controllers import GeneratedController, GeneratedObserver

__all__ = ["CompiledController", "CompiledObserver"]


def _compile_shared(code: GeneratedController | GeneratedObserver, what: str):
    """Compiles generated C into a shared library in a temporary folder with the system C
    compiler (``$CC``, else ``cc`` or ``gcc``); returns the folder (kept alive by its holder)
    and the loaded library."""
    import ctypes
    import os
    import shutil
    import subprocess
    import tempfile

    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise _core.ModelError("no C compiler found (set CC, or install cc or gcc)")
    folder = tempfile.TemporaryDirectory(prefix=f"mindyn-{what}-")
    path = Path(folder.name)
    src, so = code.write(path / f"{code.function}.c")[1], path / f"{code.function}.so"
    cmd = [cc, "-std=c99", "-O2", "-shared", "-fPIC", "-o", str(so), str(src), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        first = (res.stderr.strip().splitlines() or ["no message"])[0]
        raise _core.ModelError(f"compiling the generated {what} with {cc} failed: {first}")
    return folder, ctypes.CDLL(str(so))


class CompiledController:
    """A generated C controller step compiled with the system C compiler (``$CC``, else ``cc``
    or ``gcc``) into a temporary folder and called through ctypes: a controller of
    :func:`mindyn.control.simulate` (:class:`mindyn.control.Controller`), ``tau =
    controller(t, q, dq, q_d, dq_d, ddq_d)``, with ``reset()`` and, for the adaptive step,
    ``period`` (the period it was generated for; a simulation at another period is refused).

    Parameters
    ----------
    code : GeneratedController
        C code from :func:`generate_controller`.
    base : BaseParameters, optional
        Reported to :func:`~mindyn.control.simulate` (the true base parameters in its result).
        Its check of the sampled loop before the run takes the step's model in it; without it,
        in the simulated robot's base set whose names are the step's.

    Attributes
    ----------
    p_hat : ndarray
        The current estimate (a copy).
    """

    def __init__(self, code: GeneratedController, base: BaseParameters | None = None):
        import ctypes

        _args.instance(code, "code", GeneratedController, "the C code of generate_controller")
        if code.lang != "c":
            raise _args.fail(
                "code", "is Structured Text; expected the C code of generate_controller"
            )
        _args.optional(_args.instance, base, "base", BaseParameters)
        self.code = code
        self.base = base
        self.name = code.kind
        self._dir, self._lib = _compile_shared(code, "controller")
        n, np_ = len(code.settings["kd"]), len(code.names)
        dbl = ctypes.c_double
        fields: list[tuple[str, Any]] = [("p", dbl * np_), ("p0", dbl * np_), ("kd", dbl * n)]
        if code.kind == "adaptive-pd":
            fields += [("lambda_", dbl * n), ("gamma", dbl * np_)]
            fields += [("p_min", dbl * np_), ("p_max", dbl * np_)]
        else:
            fields += [("kp", dbl * n)]
        fields += [("tau_max", dbl * n)]
        if code.kind == "adaptive-pd" and code.settings["nu"] > 0:
            fields += [("nu", dbl)]
        if code.kind == "adaptive-pd":
            fields += [("period", dbl)]
        self._State = type("State", (ctypes.Structure,), {"_fields_": fields})
        self._state = self._State()
        self._init = getattr(self._lib, f"{code.function}_init")
        self._step = getattr(self._lib, f"{code.function}_step")
        ptr = ctypes.POINTER(dbl)
        self._step.argtypes = [ctypes.POINTER(self._State)] + [ptr] * 6
        self._step.restype = None
        self._ptr = ptr
        self._n = n
        self.reset()

    def reset(self) -> None:
        import ctypes

        self._init(ctypes.byref(self._state))

    @property
    def p_hat(self) -> np.ndarray:
        return np.array(self._state.p[:], dtype=float)

    def __getattr__(self, name):
        # ``period`` exists for the adaptive step only (the others do not depend on it)
        if name == "period" and self.__dict__.get("code") is not None:
            if self.code.kind == "adaptive-pd":
                return float(self.code.settings["period"])
        raise AttributeError(name)

    def __call__(self, t, q, dq, q_d, dq_d, ddq_d):
        import ctypes

        _args.number(t, "t")
        args = [
            _args.array(a, k, (self._n,), unit="joint")
            for k, a in zip(("q", "dq", "q_d", "dq_d", "ddq_d"), (q, dq, q_d, dq_d, ddq_d))
        ]
        tau = np.zeros(self._n)
        ptrs = [a.ctypes.data_as(self._ptr) for a in args + [tau]]
        self._step(ctypes.byref(self._state), *ptrs)
        return tau


class CompiledObserver:
    """A generated C observer step compiled with the system C compiler and called through
    ctypes: ``r = observer(q, dq, tau)`` per sample (the first call starts it, r = 0), with
    ``reset()``."""

    def __init__(self, code: GeneratedObserver):
        import ctypes

        _args.instance(code, "code", GeneratedObserver, "the C code of generate_observer")
        if code.lang != "c":
            raise _args.fail("code", "is Structured Text; expected the C code of generate_observer")
        self.code = code
        self._dir, self._lib = _compile_shared(code, "observer")
        n, np_ = len(code.gains), len(code.names)
        dbl = ctypes.c_double
        fields: list[tuple[str, Any]] = [
            ("p", dbl * np_),
            ("ko", dbl * n),
            ("c", dbl * n),
            ("period", dbl),
        ]
        fields += [("half", dbl), ("started", ctypes.c_int)]
        fields += [(f, dbl * n) for f in ("p_start", "integral", "r", "tau_prev", "beta_prev")]
        self._State = type("State", (ctypes.Structure,), {"_fields_": fields})
        self._state = self._State()
        self._init = getattr(self._lib, f"{code.function}_init")
        self._step = getattr(self._lib, f"{code.function}_step")
        self._ptr = ctypes.POINTER(dbl)
        self._step.argtypes = [ctypes.POINTER(self._State)] + [self._ptr] * 4
        self._step.restype = None
        self._n = n
        self.reset()

    def reset(self) -> None:
        import ctypes

        self._init(ctypes.byref(self._state))

    def __call__(self, q, dq, tau) -> np.ndarray:
        import ctypes

        args = [
            _args.array(a, k, (self._n,), unit="joint")
            for k, a in zip(("q", "dq", "tau"), (q, dq, tau))
        ]
        r = np.zeros(self._n)
        self._step(ctypes.byref(self._state), *[a.ctypes.data_as(self._ptr) for a in args + [r]])
        return r
