"""Which base-parameter method a command runs on a robot, and why (``mindyn base`` and
``mindyn codegen``); the library's choice when no method is given (``mindyn.base_parameters``);
the projection method's limits as the help texts state them, read from the C++ core that checks
them."""

from __future__ import annotations

from .. import _core
from ..base import choose_method
from .flags import library_options_as_flags


def base_method(robot, rotor: bool, method: str | None, friction: bool = False) -> tuple[str, str]:
    """The method ``mindyn base`` runs and why: the one given, else the library's choice
    (:func:`mindyn.base.choose_method`), its reason naming the command's flags
    (``--method projection``, not the library's ``method='projection'``)."""
    if method is not None:
        return method, "--method " + method
    method, why = choose_method(robot, rotor=rotor, friction=friction)
    return method, library_options_as_flags(why)


def projection_limits_text(*, parameters: bool = True) -> str:
    """The projection method's joint (and parameter) limits in words, from the C++ core's
    ``projection_limits()``: "18 joints on a chain, 44 on a tree or 16 on one of its root
    paths, 704 parameters"."""
    lim = _core.projection_limits()
    text = (
        f"{lim['chain_joints']} joints on a chain, {lim['tree_joints']} on a tree or "
        f"{lim['root_path_joints']} on one of its root paths"
    )
    return text + (f", {lim['parameters']} parameters" if parameters else "")
