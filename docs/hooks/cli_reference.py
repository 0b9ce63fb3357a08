"""MkDocs hook: the command-line reference, generated from mindyn's own argparse parser.

A page holding the line ``<!-- mindyn-cli-reference -->`` gets, in its place, one section per
command of ``mindyn.cli.build_parser()``: the command's summary and its ``--help`` text as the
parser formats it. The reference is therefore the parser's, at the time the site is built.
"""

from __future__ import annotations

import argparse
import os

MARKER = "<!-- mindyn-cli-reference -->"
WIDTH = "100"  # argparse wraps help text at $COLUMNS


def _subcommands(parser: argparse.ArgumentParser):
    """(name, summary, parser) of every command, in the order the parser lists them."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            summaries = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                yield name, summaries.get(name, ""), sub


def help_text(parser: argparse.ArgumentParser) -> str:
    """``parser.format_help()`` at the reference's fixed width."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        return parser.format_help()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def reference() -> str:
    """The reference as Markdown."""
    from mindyn.cli import build_parser

    parser = build_parser()
    out = ["## mindyn", "", "```text", help_text(parser).rstrip(), "```", ""]
    for name, summary, sub in _subcommands(parser):
        text = summary or ""
        out += [f"## mindyn {name}", "", f"{text[:1].upper()}{text[1:]}.", "", "```text"]
        out += [help_text(sub).rstrip(), "```", ""]
    return "\n".join(out)


def on_page_markdown(markdown: str, **kwargs) -> str:
    if MARKER in markdown:
        return markdown.replace(MARKER, reference())
    return markdown
