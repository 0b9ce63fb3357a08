"""The package's import structure: no module but the package's ``__init__`` imports a name from
the package root (``from . import X`` names a submodule or the compiled ``_core``), and the
layer contract in pyproject.toml (``lint-imports``, run by scripts/test) holds."""

from __future__ import annotations

import ast
from pathlib import Path

import mindyn

PACKAGE = Path(mindyn.__file__).parent


def _submodules(folder: Path) -> set[str]:
    """The names importable from the package ``folder``: its modules, packages and extensions."""
    names = {p.stem.split(".")[0] for p in folder.glob("*.py")}
    names |= {p.name.split(".")[0] for p in folder.glob("*.so")}
    names |= {p.name for p in folder.iterdir() if (p / "__init__.py").is_file()}
    return names - {"__init__"}


def _root_imports(path: Path) -> list[str]:
    """The ``from <package> import X`` of ``path`` whose X is not a submodule of that package."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    here = path.parent
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level and not node.module:
            target = here
            for _ in range(node.level - 1):
                target = target.parent
            subs = _submodules(target)
            for alias in node.names:
                if alias.name not in subs:
                    bad.append(f"{path.parent.name}/{path.name}:{node.lineno}: {alias.name}")
    return bad


def test_no_module_imports_from_the_package_root():
    files = [p for p in PACKAGE.rglob("*.py") if p.name != "__init__.py" or p.parent != PACKAGE]
    assert len(files) > 20
    bad = [b for f in files for b in _root_imports(f)]
    assert not bad, bad


def test_the_check_sees_a_root_import(tmp_path):
    """The check above can fail: a module that takes a function from its package's root."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from .a import f\n")
    (pkg / "a.py").write_text("def f():\n    return 1\n")
    (pkg / "b.py").write_text("from . import a\nfrom . import f\n")
    assert _root_imports(pkg / "a.py") == []
    assert _root_imports(pkg / "b.py") == ["pkg/b.py:2: f"]


def test_layer_contract_holds(tmp_path):
    """import-linter's layers contract of pyproject.toml (scripts/test runs it too)."""
    from importlinter.cli import lint_imports

    root = Path(__file__).resolve().parents[1]
    config = str(root / "pyproject.toml")
    assert lint_imports(config_filename=config, no_cache=True, no_logo=True) == 0


def test_import_mindyn_leaves_identification_and_solvers_out():
    """``import mindyn`` (every use of the library, every command) loads the model, base
    parameters, controllers and IK, not the identification package with scipy.signal or the
    convex solvers, which take a second or more to import."""
    import subprocess
    import sys

    code = (
        "import sys, mindyn; "
        "print(sorted(m for m in ('mindyn.identification', 'scipy.signal', 'cvxpy') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
