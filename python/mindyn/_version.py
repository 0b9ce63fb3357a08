"""The package version, read from the installed package's metadata (it is written once, in
pyproject.toml)."""

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("mindyn")
except _metadata.PackageNotFoundError:  # pragma: no cover - imported from a source tree
    __version__ = "unknown"
