"""What the installed package ships: its version, read from pyproject.toml, and py.typed."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import mindyn

ROOT = Path(__file__).resolve().parents[1]


def test_version_is_pyprojects():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    (version,) = re.findall(r'(?m)^version = "([^"]+)"$', text)
    assert mindyn.__version__ == version
    init = (ROOT / "python/mindyn/__init__.py").read_text(encoding="utf-8")
    assert not re.search(r'__version__ = "[0-9]', init)  # no second literal


def test_typed_marker_and_license_are_shipped():
    assert (resources.files("mindyn") / "py.typed").is_file()
    assert (resources.files("mindyn") / "_core.pyi").is_file()  # the extension's stub
    assert "BSD 3-Clause" in (ROOT / "LICENSE").read_text(encoding="utf-8")
