"""YAML files read with PyYAML's safe loader (joint-terms files, gains files, a description
rewritten by export): every failure, a value the loader cannot build too (``!!int abc``, a date
out of range, ``!!bool maybe``, a 5000-digit integer), is one line naming the file, line and
column."""

from __future__ import annotations

from pathlib import Path

import yaml

from ._core import Error


class SafeLoader(yaml.SafeLoader):
    """PyYAML's safe loader whose value constructors' own errors (a bare ValueError,
    KeyError, ...) become :class:`yaml.constructor.ConstructorError` at the node being built,
    so that they carry its line and column."""

    def construct_object(self, node, deep=False):
        try:
            return super().construct_object(node, deep=deep)
        except (Error, yaml.YAMLError, RecursionError, MemoryError):
            raise  # ours (a subclass's checks), PyYAML's own (with their marks), the machine's
        except Exception as e:  # a value constructor's bare ValueError, KeyError, TypeError, ...
            raise yaml.constructor.ConstructorError(
                None, None, _unbuilt(node, e), node.start_mark
            ) from None


def _unbuilt(node, e: Exception) -> str:
    """The problem of a value the loader could not build: its tag, its text and why."""
    tag = str(node.tag)
    tag = "!!" + tag[len("tag:yaml.org,2002:") :] if tag.startswith("tag:yaml.org,2002:") else tag
    if isinstance(node.value, str):
        text = node.value
        what = repr(text) if len(text) <= 40 else f"'{text[:20]}...' ({len(text)} characters)"
    else:
        what = f"the {node.id}"
    # Python's own reason where it has one worth reading (not a KeyError's key, a None's
    # missing attribute or an index out of range, which say how PyYAML went wrong)
    why = " ".join(str(e).split()) if isinstance(e, (ValueError, OverflowError)) else ""
    return f"cannot build {what} as {tag}" + (f" ({why})" if why else "")


def _line_column(text: str, offset: int) -> tuple[int, int]:
    """1-based line and column of the character at ``offset`` of ``text``."""
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def error_text(e: Exception, path: Path | str, text: str) -> str:
    """``PATH:LINE:COLUMN: not valid YAML: PROBLEM`` (one line) for an error of loading ``text``,
    the content of the file ``path``."""
    where = str(path)
    if isinstance(e, yaml.MarkedYAMLError):
        mark = e.problem_mark or e.context_mark
        if mark is not None:
            where += f":{mark.line + 1}:{mark.column + 1}"
        said = []
        if e.context:
            said.append(e.context)
            m = e.context_mark
            if m is not None and e.problem_mark is not None and m.line != e.problem_mark.line:
                said[-1] += f" (from line {m.line + 1}, column {m.column + 1})"
        if e.problem:
            said.append(e.problem)
        problem = ": ".join(said) or str(e)
    elif isinstance(e, yaml.reader.ReaderError):
        line, column = _line_column(text, e.position)
        where += f":{line}:{column}"
        char = e.character if isinstance(e.character, int) else ord(e.character)
        problem = f"unacceptable character #x{char:04x}: {e.reason}"
    elif isinstance(e, RecursionError):
        problem = "nested deeper than the YAML reader follows"
    else:
        problem = str(e)
    return f"{where}: not valid YAML: {' '.join(problem.split())}"


def load(text: str, path: Path | str, error: type[Exception], *, loader=SafeLoader):
    """The document of the YAML ``text`` of the file ``path``, read by ``loader`` (a subclass
    of :class:`SafeLoader`), or ``error`` with :func:`error_text`'s message."""
    try:
        return yaml.load(text, Loader=loader)
    except (yaml.YAMLError, RecursionError) as e:
        raise error(error_text(e, path, text)) from None
