"""Command-line options made from a dataclass's fields, with help from its docstring.

A field ``name`` becomes ``--name`` (underscores as dashes) of the field's type and default, its
help the field's entry in the class docstring's ``Attributes:`` section. A field in seconds
(``*_s``) drops the suffix: a number takes a duration (``10m``), a tuple takes several seconds.
A boolean that defaults to True becomes ``--no-name``, which turns it off. A field of type
``X | None`` takes an ``X``; left out, it stays None.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import re
import types
import typing
from collections.abc import Callable

from davis_io.session import Bounds

__all__ = ["add_dataclass_options", "attribute_docs", "dataclass_values", "plain_text"]

_ENTRY = re.compile(r"^(\w+)(?: \([^)]*\))?:\s*(.*)$")
_ROLE = re.compile(r":\w+:`~?([^`]+)`")
_LITERAL = re.compile(r"``([^`]+)``")


def attribute_docs(docstring: str | None) -> dict[str, str]:
    """The ``Attributes:`` section of a Google-style docstring as ``{name: one-line text}``.

    An entry is ``name: text`` (or ``name (type): text``) indented one level below the section
    title; more deeply indented lines continue it. The section ends at the first line indented
    no deeper than its title.
    """
    lines = inspect.cleandoc(docstring or "").splitlines()
    docs: dict[str, list[str]] = {}
    section_indent = entry_indent = None
    current = None
    for line in lines:
        indent = len(line) - len(line.lstrip())
        text = line.strip()
        if section_indent is None:
            if text == "Attributes:":
                section_indent = indent
            continue
        if not text:
            continue
        if indent <= section_indent:
            break
        if entry_indent is None:
            entry_indent = indent
        match = _ENTRY.match(text)
        if indent == entry_indent and match:
            current = match.group(1)
            docs[current] = [match.group(2)]
        elif current is not None:
            docs[current].append(text)
    return {name: " ".join(part for part in parts if part) for name, parts in docs.items()}


def plain_text(text: str) -> str:
    """Docstring markup (``literal``, :role:`target`) as plain text for ``--help``."""
    return _LITERAL.sub(r"\1", _ROLE.sub(r"\1", text))


def _default(field: dataclasses.Field):
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return field.default


def _given_type(kind):
    """The type a value given on the command line has: ``X`` for ``X | None``."""
    if typing.get_origin(kind) in (typing.Union, types.UnionType):
        (kind,) = (arg for arg in typing.get_args(kind) if arg is not type(None))
    return kind


def _option(
    field: dataclasses.Field, kind, seconds: Callable[[str], float], bounds: Bounds | None
) -> tuple[str, dict]:
    """The option string and ``add_argument`` keywords of one field (help added by the caller)."""
    in_seconds = field.name.endswith("_s")
    flag = "--" + field.name.removesuffix("_s").replace("_", "-")
    if kind is bool:
        if _default(field):
            return "--no-" + flag[2:], {"action": "store_false"}
        return flag, {"action": "store_true"}
    if typing.get_origin(kind) is tuple:
        keywords = {"type": typing.get_args(kind)[0], "nargs": "+"}
    elif kind is float and in_seconds:
        keywords = {"type": seconds, "metavar": "DURATION"}
    elif bounds is not None:
        keywords = {"type": bounds.argument(flag), "metavar": flag[2:].upper().replace("-", "_")}
    else:
        keywords = {"type": kind}
    if in_seconds:
        keywords.setdefault("metavar", "SECONDS")
    return flag, keywords


def add_dataclass_options(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup,
    cls: type,
    seconds: Callable[[str], float],
    flags: dict[str, str] | None = None,
    bounds: dict[str, Bounds] | None = None,
) -> None:
    """Add one option per field of the dataclass ``cls``, its default the field's.

    Args:
        parser: the parser, or one of its argument groups, to add to.
        cls: a dataclass whose docstring documents its fields under ``Attributes:``.
        seconds: parses a duration given on the command line into seconds.
        flags: option strings to use instead of the derived ones, by field name.
        bounds: the range of each numeric field, checked as the option is parsed.
    """
    docs = attribute_docs(cls.__doc__)
    hints = typing.get_type_hints(cls)
    for field in dataclasses.fields(cls):
        kind = _given_type(hints[field.name])
        flag, keywords = _option(field, kind, seconds, (bounds or {}).get(field.name))
        default = _default(field)
        text = plain_text(docs.get(field.name, "")).replace("%", "%%").rstrip(".")
        if keywords.get("action") == "store_false":
            text = f"turn off: {text}"
        elif "action" not in keywords and default not in ((), "", None):
            text = f"{text} (default: {default})"
        parser.add_argument(
            (flags or {}).get(field.name, flag),
            dest=field.name,
            default=default,
            help=text,
            **keywords,
        )


def dataclass_values(cls: type, args: argparse.Namespace) -> dict:
    """Keyword arguments of ``cls`` from parsed options (lists back to tuples)."""
    values = {}
    for field in dataclasses.fields(cls):
        value = getattr(args, field.name)
        values[field.name] = tuple(value) if isinstance(value, list) else value
    return values
