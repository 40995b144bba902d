"""The layout files of a view: ``{v}_order.json`` and ``{v}_order.csv`` read back (docs/format.md).

:func:`read_order_json` gives an :class:`OrderGraph` (lengths in metres), :func:`read_order_csv`
the relation matrix. The files are made by :meth:`mgn.view_labels.layout.Layout.order_json` and
:meth:`~mgn.view_labels.layout.Layout.order_csv` and written by
:func:`mgn.io.scene_folder.write_view`.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from mgn.base.units import M_TO_CM
from mgn.errors import InvalidArgumentError, IoError

__all__ = [
    "OrderGraph",
    "derive_layers",
    "read_order_csv",
    "read_order_json",
    "strongly_connected",
]


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class OrderGraph:
    """What :func:`read_order_json` reads back (SI units: depth differences in metres)."""

    relation: npt.NDArray[np.int8]  #: (N, N) matrix M rebuilt from the parent lists
    occlusion: npt.NDArray[np.float64]  #: (N,)
    layer: npt.NDArray[np.int8]  #: (N,)
    depth_diff: npt.NDArray[np.float64]  #: (N, N) [child, parent] m, NaN where no relation
    edge_size: npt.NDArray[np.float64]  #: (N, N) [child, parent] px, NaN where no relation
    total_covered_edge: npt.NDArray[np.float64]  #: (N,)
    bin_relations: tuple[str, ...]  #: (N,) "" where the file has no bin_rel


def _relation_from_parents(parent: np.ndarray) -> np.ndarray:
    """(N,N) bool parent[i, j] = j occludes i -> matrix M (-1 wins over +1)."""
    m = np.zeros(parent.shape, np.int8)
    m[parent.T] = 1
    m[parent] = -1
    return m


def _read_text(path: str | os.PathLike[str], what: str) -> str:
    try:
        return Path(path).read_text()
    except OSError as e:
        raise IoError(f"{what}: cannot read '{os.fspath(path)}': {e.strerror or e}") from e


def read_order_csv(path: str | os.PathLike[str]) -> npt.NDArray[np.int8]:
    """Reads a ``{v}_order.csv`` and returns the full relation matrix M (N, N) int8: the stored
    -1 entries, and +1 at (j, i) for every stored -1 at (i, j) whose mirror is not -1."""
    text = _read_text(path, "read_order_csv")
    rows = [r for r in text.splitlines() if r.strip()]
    try:
        vals = [[float(x) for x in r.split(",")] for r in rows]
    except ValueError as e:
        raise InvalidArgumentError(f"read_order_csv: '{os.fspath(path)}': {e}") from e
    n = len(vals)
    if any(len(r) != n for r in vals):
        raise InvalidArgumentError(
            f"read_order_csv: '{os.fspath(path)}' must be N x N, got rows of lengths "
            f"{sorted({len(r) for r in vals})} for {n} rows"
        )
    stored = np.asarray(vals, np.float64).reshape(n, n)
    if not np.all(np.isin(stored, (-1.0, 0.0, 1.0))):
        raise InvalidArgumentError(
            f"read_order_csv: '{os.fspath(path)}': entries must be -1, 0 or 1"
        )
    return _relation_from_parents(stored == -1)


def read_order_json(path: str | os.PathLike[str]) -> OrderGraph:
    """Reads a ``{v}_order.json`` (keys "1".."N") into an :class:`OrderGraph` (metres)."""
    text = _read_text(path, "read_order_json")
    try:
        data = json.loads(text)
        n = len(data)
        keys = sorted(int(k) for k in data)
    except (ValueError, TypeError) as e:
        raise InvalidArgumentError(f"read_order_json: '{os.fspath(path)}': {e}") from e
    if keys != list(range(1, n + 1)):
        raise InvalidArgumentError(
            f"read_order_json: '{os.fspath(path)}': keys must be '1'..'{n}', got {keys}"
        )
    parent = np.zeros((n, n), bool)
    dd = np.full((n, n), np.nan)
    edge = np.full((n, n), np.nan)
    occ = np.zeros(n)
    layer = np.zeros(n, np.int8)
    tce = np.zeros(n)
    bins: list[str] = []
    try:
        for i in range(n):
            obj = data[str(i + 1)]
            occ[i] = float(obj["occlusion"])
            layer[i] = int(obj["layer"])
            tce[i] = float(obj.get("total_covered_edge", 0.0))
            bins.append(str(obj.get("bin_rel", "")))
            for p in obj["parents"]:
                j = int(p["id"])
                if j == 0:
                    continue
                if not 1 <= j <= n:
                    raise InvalidArgumentError(f"object {i + 1}: parent id {j} not in 1..{n}")
                parent[i, j - 1] = True
                dd[i, j - 1] = float(p["depth_diff"]) / M_TO_CM
                edge[i, j - 1] = float(p["edge_size"])
    except (KeyError, ValueError, TypeError) as e:
        raise InvalidArgumentError(f"read_order_json: '{os.fspath(path)}': {e!r}") from e
    return OrderGraph(
        relation=_frozen(_relation_from_parents(parent)),
        occlusion=_frozen(occ),
        layer=_frozen(layer),
        depth_diff=_frozen(dd),
        edge_size=_frozen(edge),
        total_covered_edge=_frozen(tce),
        bin_relations=tuple(bins),
    )


def strongly_connected(parents: list[list[int]]) -> list[frozenset[int]]:
    """Per object the strongly connected component of the relation graph (parent -> child) it
    belongs to: the objects it reaches and that reach it, itself included (0-based;
    ``parents[i]`` lists the parents of object i). A component of two or more objects is an
    occlusion cycle."""
    n = len(parents)
    children: list[list[int]] = [[] for _ in range(n)]
    for i, ps in enumerate(parents):
        for p in ps:
            if not 0 <= p < n or p == i:
                raise InvalidArgumentError(
                    f"strongly_connected: object {i} has parent {p}; expected another object "
                    f"0..{n - 1}"
                )
            children[p].append(i)

    def reach(start: int) -> set[int]:
        seen, todo = {start}, [start]
        while todo:
            for w in children[todo.pop()]:
                if w not in seen:
                    seen.add(w)
                    todo.append(w)
        return seen

    down = [reach(i) for i in range(n)]
    return [frozenset(j for j in down[i] if i in down[j]) for i in range(n)]


def derive_layers(parents: list[list[int]]) -> list[int]:
    """The layer of every object from the relation graph (docs/format.md, ``{v}_order.json``):
    ``parents[i]`` lists the 0-based parents of object i. 0: no parent; 1: exactly one parent,
    which is in layer 0; 2: a member of a strongly connected component of two or more objects
    whose members each have at most one parent outside it; 3: the others."""
    comp = strongly_connected(parents)
    interlock = {
        c: all(sum(p not in c for p in parents[m]) <= 1 for m in c) for c in set(comp) if len(c) > 1
    }
    layers = []
    for i, ps in enumerate(parents):
        if not ps:
            layers.append(0)
        elif len(ps) == 1 and not parents[ps[0]] and len(comp[i]) == 1:
            layers.append(1)
        elif len(comp[i]) > 1 and interlock[comp[i]]:
            layers.append(2)
        else:
            layers.append(3)
    return layers
