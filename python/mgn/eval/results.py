"""Shared output of the evaluation commands: a plain-text table and an atomically written JSON."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from mgn.base.atomic import atomic_write_text

__all__ = ["format_table", "print_and_write", "to_jsonable", "write_results_json"]


def _cell(value: Any, digits: int) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.{digits}f}"
    return str(value)


def format_table(
    rows: Sequence[Mapping[str, Any]],
    columns: Sequence[str] | None = None,
    *,
    title: str | None = None,
    digits: int = 3,
) -> str:
    """Rows of dicts as an aligned text table (first column left-aligned, the others right).

    ``columns`` picks and orders the keys (default: the keys of the first row); a missing key or
    ``None`` prints as ``-``; floats print with ``digits`` decimals and NaN as ``nan``.
    """
    if columns is None:
        columns = list(rows[0].keys()) if rows else []
    cells = [[_cell(r.get(c), digits) for c in columns] for r in rows]
    widths = [max([len(c)] + [len(row[k]) for row in cells]) for k, c in enumerate(columns)]

    def line(values: Sequence[str]) -> str:
        parts = [
            v.ljust(w) if k == 0 else v.rjust(w)
            for k, (v, w) in enumerate(zip(values, widths, strict=True))
        ]
        return "  ".join(parts).rstrip()

    out = [title] if title else []
    out += [line(list(columns)), line(["-" * w for w in widths])]
    out += [line(row) for row in cells]
    return "\n".join(out)


def to_jsonable(obj: Any) -> Any:
    """numpy scalars/arrays, tuples and mappings converted for ``json.dumps``; NaN becomes None."""

    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_results_json(path: str | os.PathLike[str], results: Any) -> None:
    """Write ``results`` (a dict, or an object with ``to_dict()``) as indented JSON, atomically."""
    doc = results.to_dict() if hasattr(results, "to_dict") else results
    atomic_write_text(path, json.dumps(to_jsonable(doc), indent=2) + "\n")


def print_and_write(results: Any, out: str | os.PathLike[str] | None) -> int:
    """What every ``mgn eval`` command does at the end: print ``results.table()``, write the JSON
    to ``out`` if given, say so; returns the exit code 0."""
    print(results.table())
    if out:
        write_results_json(out, results)
        print(f"wrote {os.fspath(out)}")
    return 0
