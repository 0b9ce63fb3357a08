"""Which base-parameter method a command runs on a robot, and why (``mindyn base`` and
``mindyn codegen``); the library's choice when no method is given (``mindyn.base_parameters``)."""

from __future__ import annotations

from ..base import choose_method


def base_method(robot, rotor: bool, method: str | None, friction: bool = False) -> tuple[str, str]:
    """The method ``mindyn base`` runs and why: the one given, else the library's choice
    (:func:`mindyn.base.choose_method`)."""
    if method is not None:
        return method, "--method " + method
    return choose_method(robot, rotor=rotor, friction=friction)
