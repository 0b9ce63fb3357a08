"""What the commands state about the choices they made for the user, and how their refusals
name the options, on inputs the other tests do not take: a description with an effort limit on
some joints only, a tree given to a command that needs a chain."""

from __future__ import annotations

import contextlib
import io

import mindyn
import numpy as np
import pytest
from conftest import ROBOTS_DIR
from mindyn import cli


def run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def test_a_tree_refused_by_ik_names_the_tip_option_as_each_interface_spells_it():
    urdf = ROBOTS_DIR / "solo_description/robots/solo12.urdf"
    rc, _, err = run(["ik", urdf, "--xyz", "0.2", "0.1", "-0.2"])
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "--tip <link>" in err and "mindyn.load(" not in err, err
    robot = mindyn.load(urdf)
    with pytest.raises(mindyn.ModelError, match="tip='<link>'"):
        mindyn.ik(robot, np.eye(4))
