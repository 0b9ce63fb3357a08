"""Arguments shared by the subcommands of the ``mindyn`` command line."""

from __future__ import annotations

import argparse

from . import bundled_robots


def robot_help() -> str:
    return (
        "a bundled robot (" + ", ".join(bundled_robots()) + "), a URDF file or a YAML DH/MDH table"
    )


def add_robot(p: argparse.ArgumentParser) -> None:
    """The positional ROBOT and ``--tip`` (the last link of a URDF chain)."""
    p.add_argument("robot", metavar="ROBOT", help=robot_help())
    p.add_argument("--tip", help="URDF: the link that ends the chain")


def add_joint_terms(p: argparse.ArgumentParser, verb: str = "include") -> None:
    """``--rotor`` and ``--friction``; ``verb`` says what they do in this command."""
    p.add_argument("--rotor", action="store_true", help=f"{verb} rotor inertia Ia per joint")
    p.add_argument("--friction", action="store_true", help=f"{verb} Fv, Fc per joint")
