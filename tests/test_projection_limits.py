"""The projection method's limits have one source, the C++ core that checks them
(``_core.projection_limits()``): the refusals name them, and the command line's help reads them
from there (replacing the core's figures changes the help)."""

from __future__ import annotations

import mindyn
from mindyn import _core, cli


def test_the_refusals_are_the_limits():
    lim = _core.projection_limits()
    n = lim["chain_joints"]
    assert n > 0 and lim["tree_joints"] >= n and 0 < lim["root_path_joints"] <= n
    over = _core.projection_refusal(mindyn.load(f"planar{n + 1}")._m)
    assert over is not None and f"at most {n} joints" in over
    # at the limit, no joint limit refuses the chain (its memory estimate may)
    at = _core.projection_refusal(mindyn.load(f"planar{n}")._m)
    assert at is None or "joints" not in at.split(",")[0]
    assert lim["budget_bytes"] > 0 and lim["parameters"] > 10 * n


def _base_help(capsys) -> str:
    assert cli.main(["base", "--help"]) == 0
    return " ".join(capsys.readouterr().out.split())


def test_the_help_reads_the_limits_from_the_core(capsys, monkeypatch):
    lim = _core.projection_limits()
    text = _base_help(capsys)
    assert (
        f"more than {lim['chain_joints']} joints on a chain, {lim['tree_joints']} on a tree or "
        f"{lim['root_path_joints']} on one of its root paths, {lim['parameters']} parameters"
    ) in text
    fake = {"chain_joints": 7, "tree_joints": 8, "root_path_joints": 5, "parameters": 90}
    monkeypatch.setattr(_core, "projection_limits", lambda: dict(fake, budget_bytes=1.0))
    text = _base_help(capsys)
    assert "more than 7 joints on a chain, 8 on a tree or 5 on one of its root paths, 90" in text
    assert "(7 joints on a chain, 8 on a tree or 5 on one of its root paths)" in text
    assert f"{lim['chain_joints']} joints" not in text
