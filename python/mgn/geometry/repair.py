"""Repair of nearly closed meshes: the defects that make a solid read as open.

A scanned or exported part is often closed but for a few faces: duplicated faces, a stray
triangle hanging off an edge, faces wound the wrong way, a few missing triangles. Each of these
makes :meth:`mgn.Mesh.validate` report the mesh as not watertight or not consistently wound, and
the object would then get the thin-shell mass of an open mesh and no parallel-jaw labels.
:func:`repair_mesh` fixes them on the topology of the mesh welded by position (the same welding
as ``validate``), keeping the vertex array (positions, uvs) and the materials:

1. duplicate faces (the same three welded vertices) are removed: one face is kept where all are
   wound alike; a face and its reverse (a double-sided sheet) cancel;
2. stray faces are removed: a face with a free (boundary) edge and an edge shared by more than
   two faces, repeatedly (a fin on an otherwise closed surface), and the vertices only they
   used;
3. faces are turned to one winding per connected piece (the winding most of its faces have);
4. small holes are closed: a loop of free edges whose filling is at most
   ``max_hole_area`` of the surface area (default 1 %) gets a fan of triangles.

What cannot be repaired this way is left as it is (e.g. a large opening, an edge where an open
piece meets a closed one); :attr:`RepairReport.closed` says whether the result is closed.
Closed solids that only touch each other along an edge or at a vertex (two cubes sharing one
edge, parts of a multi-part export) need no repair: :meth:`mgn.Mesh.validate` splits the shared
edges and vertices between the pieces (``MeshReport.num_split_edges``, ``num_split_vertices``),
and the mesh is closed with the volume of all pieces; :func:`split_note` says so in words.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh, MeshReport

__all__ = ["RepairReport", "repair_mesh", "split_note"]

#: Largest hole filled, as a fraction of the mesh's surface area.
MAX_HOLE_AREA = 0.01


@dataclass(frozen=True)
class RepairReport:
    """What :func:`repair_mesh` did.

    Attributes:
        mesh: the repaired mesh (the input itself when nothing changed).
        changes: one line per kind of change, for people (empty: nothing changed).
        before, after: :meth:`mgn.Mesh.validate` of the input and of the result.
        holes_left: loops of free edges not closed (larger than ``max_hole_area``, or not a
            simple loop).
    """

    mesh: Mesh
    changes: tuple[str, ...]
    before: MeshReport
    after: MeshReport
    holes_left: int = 0

    @property
    def closed(self) -> bool:
        """The result is watertight and consistently wound (its mass is exact)."""
        return bool(self.after.is_watertight and self.after.is_winding_consistent)


def split_note(report: MeshReport) -> str:
    """What :meth:`mgn.Mesh.validate` split where closed pieces touch, for people: e.g.
    "split 1 edge and 2 vertices where closed pieces touch (2 closed pieces)"; "" when
    nothing was split."""
    edges, vertices = report.num_split_edges, report.num_split_vertices
    if not (edges or vertices):
        return ""
    parts = [f"{edges} edge{'' if edges == 1 else 's'}"] if edges else []
    if vertices:
        parts.append(f"{vertices} {'vertex' if vertices == 1 else 'vertices'}")
    return (
        f"split {' and '.join(parts)} where closed pieces touch "
        f"({report.num_components} closed pieces)"
    )


def _weld(vertices: npt.NDArray[np.float32]) -> npt.NDArray[np.int64]:
    """Index of the first vertex at the same position (``-0`` and ``+0`` alike), per vertex."""
    v = np.ascontiguousarray(vertices + np.float32(0.0))  # -0 -> +0
    _, first, inverse = np.unique(v, axis=0, return_index=True, return_inverse=True)
    return first[inverse.reshape(-1)].astype(np.int64)


def _edge_uses(wf: npt.NDArray[np.int64]) -> dict[tuple[int, int], list[tuple[int, int]]]:
    """Undirected welded edge (min, max) -> [(face, +1 if used min->max else -1), ...]."""
    uses: dict[tuple[int, int], list[tuple[int, int]]] = defaultdict(list)
    for f, (a, b, c) in enumerate(wf.tolist()):
        for p, q in ((a, b), (b, c), (c, a)):
            if p != q:
                uses[(min(p, q), max(p, q))].append((f, 1 if p < q else -1))
    return uses


def _dedupe(wf: npt.NDArray[np.int64]) -> tuple[npt.NDArray[np.bool_], int, int]:
    """(faces kept, duplicates removed, opposite pairs removed)."""
    keep = np.ones(len(wf), bool)
    groups: dict[tuple[int, ...], list[int]] = defaultdict(list)
    for f, tri in enumerate(wf.tolist()):
        groups[tuple(sorted(tri))].append(f)
    dup = opposite = 0
    for faces in groups.values():
        if len(faces) < 2:
            continue
        ref = wf[faces[0]].tolist()
        # Same winding as the first face: a cyclic rotation of it.
        rotations = {tuple(ref[i:] + ref[:i]) for i in range(3)}
        same = [f for f in faces if tuple(wf[f].tolist()) in rotations]
        other = [f for f in faces if f not in same]
        net = len(same) - len(other)
        for f in faces:
            keep[f] = False
        if net != 0:
            keep[(same if net > 0 else other)[0]] = True
        opposite += 2 * min(len(same), len(other))
        dup += len(faces) - 2 * min(len(same), len(other)) - (1 if net != 0 else 0)
    return keep, dup, opposite


def _remove_fins(wf: npt.NDArray[np.int64], keep: npt.NDArray[np.bool_]) -> int:
    """Remove (in ``keep``) faces with a free edge and an over-shared edge, until none is left.
    Returns how many."""
    removed = 0
    for _ in range(64):
        idx = np.flatnonzero(keep)
        uses = _edge_uses(wf[idx])
        count = {e: len(u) for e, u in uses.items()}
        fins = []
        for k, (a, b, c) in enumerate(wf[idx].tolist()):
            edges = [(min(p, q), max(p, q)) for p, q in ((a, b), (b, c), (c, a)) if p != q]
            n = [count[e] for e in edges]
            if 1 in n and any(x > 2 for x in n):
                fins.append(idx[k])
        if not fins:
            break
        keep[fins] = False
        removed += len(fins)
    return removed


def _orient(wf: npt.NDArray[np.int64]) -> tuple[npt.NDArray[np.bool_], int]:
    """(faces to flip, pieces changed): each piece connected through edges of exactly two
    faces gets one winding, the one most of its faces have. A piece that cannot be wound
    consistently (one-sided) is left alone."""
    uses = _edge_uses(wf)
    neighbours: dict[int, list[tuple[int, bool]]] = defaultdict(list)
    for u in uses.values():
        if len(u) == 2:
            (f, s), (g, t) = u
            # Consistent when the two faces use the edge in opposite directions.
            neighbours[f].append((g, s == t))
            neighbours[g].append((f, s == t))
    flip = np.zeros(len(wf), bool)
    seen = np.zeros(len(wf), bool)
    pieces = 0
    for start in range(len(wf)):
        if seen[start]:
            continue
        state = {start: False}
        stack, ok = [start], True
        seen[start] = True
        while stack:
            f = stack.pop()
            for g, mismatch in neighbours[f]:
                want = state[f] ^ mismatch
                if g not in state:
                    state[g] = want
                    seen[g] = True
                    stack.append(g)
                elif state[g] != want:
                    ok = False
        if not ok:
            continue
        flipped = [f for f, s in state.items() if s]
        if not flipped:
            continue
        if 2 * len(flipped) > len(state):  # the majority winding is the other one
            flipped = [f for f, s in state.items() if not s]
        flip[flipped] = True
        pieces += 1
    return flip, pieces


def _boundary_loops(wf: npt.NDArray[np.int64]) -> list[list[int]]:
    """Loops of free edges, each as welded vertices in the direction of its faces."""
    uses = _edge_uses(wf)
    nxt: dict[int, list[int]] = defaultdict(list)
    for (p, q), u in uses.items():
        if len(u) == 1:
            _, s = u[0]
            a, b = (p, q) if s > 0 else (q, p)
            nxt[a].append(b)
    loops, used = [], set()
    for start in list(nxt):
        for first in nxt[start]:
            if (start, first) in used:
                continue
            loop, a, b = [start], start, first
            closed = False
            while (a, b) not in used:
                used.add((a, b))
                if b == start:
                    closed = True
                    break
                loop.append(b)
                options = [c for c in nxt.get(b, []) if (b, c) not in used]
                if len(options) != 1:  # a branching or dead end: not a simple loop
                    break
                a, b = b, options[0]
            if closed and len(loop) >= 3:
                loops.append(loop)
    return loops


def _fan(loop: list[int], v: npt.NDArray[np.float64]) -> tuple[list[tuple[int, int, int]], float]:
    """Triangles closing ``loop`` (wound against the loop's faces) as a fan from the apex that
    gives no degenerate triangle, and their area; ([], 0) when every apex does."""
    n = len(loop)
    best: tuple[list[tuple[int, int, int]], float] = ([], 0.0)
    for k in range(n):
        ring = loop[k:] + loop[:k]
        tris = [(ring[0], ring[i + 1], ring[i]) for i in range(1, n - 1)]
        p = v[np.asarray(tris)]
        cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        areas = 0.5 * np.linalg.norm(cross, axis=1)
        scale = max(float(np.ptp(v[loop], axis=0).max()) ** 2, 1e-30)
        if np.all(areas > 1e-9 * scale):
            # Prefer the fan whose triangles all face one way (a flat-ish hole).
            normal = cross.sum(axis=0)
            if np.all(cross @ normal > 0):
                return tris, float(areas.sum())
            if not best[0]:
                best = (tris, float(areas.sum()))
    return best


def repair_mesh(mesh: Mesh, *, max_hole_area: float = MAX_HOLE_AREA) -> RepairReport:
    """Repair the defects listed in the module doc; see :class:`RepairReport`.

    Args:
        mesh: the mesh (metres).
        max_hole_area: largest hole filled, as a fraction of the surface area (0 fills none).

    Raises:
        InvalidArgumentError: ``max_hole_area`` is negative or not finite.
    """
    if not (np.isfinite(max_hole_area) and max_hole_area >= 0):
        raise InvalidArgumentError(
            f"repair_mesh: max_hole_area must be a fraction >= 0, got {max_hole_area!r}"
        )
    before = mesh.validate()
    if before.is_watertight and before.is_winding_consistent:
        return RepairReport(mesh, (), before, before)
    vertices = np.asarray(mesh.vertices, np.float32)
    faces = np.asarray(mesh.faces, np.int64)
    weld = _weld(vertices)
    wf = weld[faces]
    changes: list[str] = []

    keep, dup, opposite = _dedupe(wf)
    if dup:
        changes.append(f"removed {dup} duplicate face(s)")
    if opposite:
        changes.append(
            f"removed {opposite} face(s) of double-sided sheets (a face and its reverse)"
        )
    fins = _remove_fins(wf, keep)
    if fins:
        changes.append(
            f"removed {fins} stray face(s) hanging off edges shared by more than two faces"
        )
    idx = np.flatnonzero(keep)
    faces, wf = faces[idx], wf[idx]
    face_mats = np.asarray(mesh.face_materials, np.int64)
    face_mats = face_mats[idx] if len(face_mats) else face_mats

    flip, pieces = _orient(wf)
    if flip.any():
        faces[flip] = faces[flip][:, [0, 2, 1]]
        wf[flip] = wf[flip][:, [0, 2, 1]]
        changes.append(
            f"turned {int(flip.sum())} of {len(faces)} faces to the winding of the "
            f"rest of their piece ({pieces} piece(s))"
        )

    v64 = vertices.astype(np.float64)
    area = float(mesh.area)
    new: list[tuple[int, int, int]] = []
    filled, left = 0, 0
    for loop in _boundary_loops(wf):
        tris, fill_area = _fan(loop, v64)
        if tris and fill_area <= max_hole_area * area:
            new += tris
            filled += 1
        else:
            left += 1
    if filled:
        changes.append(f"closed {filled} small hole(s) with {len(new)} triangle(s)")
        faces = np.concatenate([faces, np.asarray(new, np.int64)])
        if len(face_mats):
            face_mats = np.concatenate([face_mats, np.zeros(len(new), np.int64)])
    if not changes:
        return RepairReport(mesh, (), before, before, left)
    # Vertices only removed faces used (a fin's tip) go, so that bounds stay those of the solid.
    used = np.unique(faces)
    remap = np.full(len(vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    if len(used) < len(vertices):
        n = len(vertices) - len(used)
        changes.append(f"dropped {n} {'vertex' if n == 1 else 'vertices'} no face uses any more")
    uvs = mesh.uvs
    out = Mesh(
        vertices[used],
        remap[faces].astype(np.int32),
        None if uvs is None or len(uvs) == 0 else np.asarray(uvs, np.float32)[used],
        list(mesh.materials),
        [int(m) for m in face_mats],
        mesh.name,
    )
    return RepairReport(out, tuple(changes), before, out.validate(), left)
