"""A ``results.json`` read back into the report it was written from, to render it again."""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from pathlib import Path

from benchlib.report import BenchReport

__all__ = ["StaleResults", "report_from_json", "typed"]


class StaleResults(ValueError):
    """A results file that this version of the report cannot read (written by another one)."""


def typed(kind, value, where: str = "results"):
    """``value`` parsed from JSON, rebuilt as ``kind`` (the annotation it was written from).

    Dataclasses (by their fields' annotations), lists, tuples, dicts, optionals, paths and
    numbers; JSON's ``NaN`` stays a float.

    Raises:
        StaleResults: a field the dataclass does not have, or a required one missing, named by
            its path in the file.
    """
    if value is None:
        return None
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if dataclasses.is_dataclass(kind):
        return _dataclass(kind, value, where)
    if origin in (types.UnionType, typing.Union):
        return typed(next(a for a in args if a is not type(None)), value, where)
    if origin is list:
        return [typed(args[0], item, f"{where}[{i}]") for i, item in enumerate(value)]
    if origin is tuple:
        kinds = [args[0]] * len(value) if args[-1] is Ellipsis else args
        return tuple(
            typed(k, item, f"{where}[{i}]")
            for i, (k, item) in enumerate(zip(kinds, value, strict=True))
        )
    if origin is dict:
        return {key: typed(args[1], item, f"{where}.{key}") for key, item in value.items()}
    if kind is Path:
        return Path(value)
    if kind is float:
        return float(value)
    return value


def _dataclass(kind, value: dict, where: str):
    hints = typing.get_type_hints(kind)
    fields = {f.name: f for f in dataclasses.fields(kind) if f.init}
    unknown = sorted(set(value) - set(fields))
    if unknown:
        raise StaleResults(
            f"{where}: {kind.__name__} has no field {', '.join(unknown)}; the file was written by "
            "another version of the benchmark: run it again (make bench)"
        )
    required = {
        name
        for name, f in fields.items()
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }
    missing = sorted(required - set(value))
    if missing:
        raise StaleResults(
            f"{where}: {kind.__name__} needs {', '.join(missing)}, which the file lacks; the file "
            "was written by another version of the benchmark: run it again (make bench)"
        )
    return kind(**{k: typed(hints[k], v, f"{where}.{k}") for k, v in value.items()})


def report_from_json(path: Path) -> BenchReport:
    """The report a ``results.json`` holds (its verdicts and targets are computed again).

    Raises:
        StaleResults: written by another version of the report.
    """
    payload = json.loads(Path(path).read_text())
    for computed in ("verdicts", "targets"):
        payload.pop(computed, None)
    return typed(BenchReport, payload, str(path))
