"""The suction-cup calibration board: a printable plate with graded features (docs/models.md §4).

The board is one watertight solid built with ``manifold3d`` booleans: a 300 x 200 x 15 mm plate
with features added on top (steps, ridges, convex cylinders, domes) or cut into it (grooves,
concave cylinders, through-holes). Each feature comes with the nominal cup poses to try on it,
so that measured outcomes can be fed to the calibration of the seal model (c1, c2).

Frame (object frame of the board, metres): the origin is the plate's bottom-left-front corner,
x runs along the 300 mm edge, y along the 200 mm edge, z up; the plate occupies
[0, 0.3] x [0, 0.2] x [0, 0.015], so its top face is at z = 0.015 m. A pose is a contact point on
the surface and the unit outward surface normal there; the cup approaches along -normal. (The
tilt poses are the exception: their "normal" is the reversed, tilted approach axis.)

Layout (rows along y, features left to right along x; every pose's ring, up to 9 mm radius,
stays clear of the neighbouring features):

====  =======  ========================================================================
row   y (mm)   features (graded parameter)
====  =======  ========================================================================
A     19       steps 1, 2, 4, 6, 8, 10, 12 mm high; poses across the left edge
B     51       ridges (width x height) and grooves (width x depth) 1..8 mm; poses across
C     83       convex cylinders R 40, 25, 20, 15, 12, 10, 8, 7, 5 mm (axis along y); crest
               and flank poses
D     115      concave cylinders, the same radii; trough and flank poses
E     147      domes R 40, 25, 15, 10, 7, 5 mm; apex, flank and foot poses; outer edge
               (poses 1..11 mm inside x = 300 mm)
F     179      through-holes 2 .. 12 mm, poses beside the rim; approach tilt 2..40 deg on the
               flat plate (two spots: about y, about x); 90° corner at (300, 200) mm
====  =======  ========================================================================

Flat controls sit at the free right end of rows B..F, and two more on the plate's right side
face (normal +x, the cup approaches horizontally).

Why tilt poses: with the spring model (docs/models.md §1) the force balance on curved surfaces
depends mostly on c2 (ring springs), while a tilted approach on a plane depends only on c1
(compression springs: the ring points sit at different heights along the approach axis); steps,
ridges, grooves and holes mostly test the geometric checks. Together they make both constants
identifiable.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import manifold3d
import numpy as np
import numpy.typing as npt

from mgn.base.atomic import atomic_write_bytes, atomic_write_text
from mgn.errors import BackendError, IoError

__all__ = [
    "PLATE_SIZE",
    "TOP_Z",
    "board_poses",
    "make_calibration_board",
    "write_binary_stl",
    "write_calibration_board",
]

MM = 1e-3
#: Plate size (x, y, z), m.
PLATE_SIZE = (0.300, 0.200, 0.015)
#: Height of the plate's top face, m.
TOP_Z = PLATE_SIZE[2]

_ROW_Y = {"A": 19 * MM, "B": 51 * MM, "C": 83 * MM, "D": 115 * MM, "E": 147 * MM, "F": 179 * MM}
_ROW_HALF = 13 * MM  # features span row centre +- 13 mm in y
_RING_CLEAR = 9 * MM  # pose envelope: largest cup ring radius the layout keeps clear
_GAP = 3 * MM  # extra clearance between one feature's pose envelope and the next footprint
_X_MARGIN = 8 * MM
_EMBED = 0.5 * MM  # added solids start this far below the top face (no coplanar faces)
_SAGITTA = 0.002 * MM  # chord tolerance of curved surfaces
_STEP_HEIGHTS_MM = (1, 2, 4, 6, 8, 10, 12)
_STEP_OFFSETS_MM = (-8, -6, -4, -2, -1, 1, 2, 4, 6, 8)
_STEP_WIDTH = 20 * MM
_RIDGES_MM = ((1, 1), (2, 2), (4, 2), (8, 2), (4, 4))  # (width, height) and (width, depth)
_ACROSS_OFFSETS_MM = (-9, -6, -3, 0, 3, 6, 9)
_CYLINDER_RADII_MM = (40, 25, 20, 15, 12, 10, 8, 7, 5)
_CAP_MM = 6.0  # largest height of convex cylinders / depth of concave ones
_CYLINDER_HALF_WIDTH = 16 * MM  # largest footprint half-width of a cylinder
_DOME_RADII_MM = (40, 25, 15, 10, 7, 5)
_HOLE_DIAMETERS_MM = (2, 4, 6, 8, 10, 12)
_HOLE_RIM_OFFSETS_MM = (1, 3, 5, 8, 10)  # pose distance beyond the rim
_EDGE_INSETS_MM = (1, 3, 5, 7, 9, 11)
_CORNER_INSETS_MM = (2, 4, 6, 8, 10)
_TILTS_DEG = (2, 5, 10, 15, 20, 25, 30, 35, 40)  # approach tilt on the flat plate
_TILT_CLEAR = 12 * MM  # ring envelope of a tilted approach (9 mm / cos 40 deg)


@dataclass
class _Feature:
    name: str
    kind: str
    parameter: str
    parameter_m: float
    footprint: tuple[float, float, float, float] | None  # (x0, y0, x1, y1) on the plate, m
    dims: dict[str, float] = field(default_factory=dict)
    poses: list[dict[str, Any]] = field(default_factory=list)

    def add_pose(
        self, point: Sequence[float], normal: Sequence[float], offset_m: float, description: str
    ) -> None:
        n = np.asarray(normal, dtype=np.float64)
        self.poses.append(
            {
                "point": tuple(float(v) for v in point),
                "normal": tuple(float(v) for v in n / np.linalg.norm(n)),
                "offset_m": float(offset_m),
                "description": description,
            }
        )

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "kind": self.kind,
            "parameter": self.parameter,
            "parameter_m": self.parameter_m,
            **{(k if k.endswith("_rad") else f"{k}_m"): v for k, v in self.dims.items()},
            "footprint_m": self.footprint,
            "poses": self.poses,
        }


def _segments(radius: float) -> int:
    """Circular segments so that the chord error stays below the sagitta tolerance."""
    n = math.pi / math.acos(1.0 - _SAGITTA / radius)
    return int(max(64, min(512, 4 * math.ceil(n / 4))))


def _box(x0: float, y0: float, z0: float, x1: float, y1: float, z1: float) -> manifold3d.Manifold:
    return manifold3d.Manifold.cube((x1 - x0, y1 - y0, z1 - z0)).translate((x0, y0, z0))


def _y_cylinder(xc: float, yc: float, zc: float, radius: float) -> manifold3d.Manifold:
    """Cylinder with its axis along y through (xc, ., zc), spanning the row (yc +- 13 mm)."""
    cyl = manifold3d.Manifold.cylinder(2 * _ROW_HALF, radius, radius, _segments(radius), True)
    return cyl.rotate((90.0, 0.0, 0.0)).translate((xc, yc, zc))


def _pack(
    extents: Sequence[tuple[float, float, float, float]], x_start: float
) -> tuple[list[float], float]:
    """Left-to-right placement of features along x.

    Each entry is (footprint left, footprint right, envelope left, envelope right), distances
    from the feature's reference x. The next feature's footprint starts ``_GAP`` beyond this
    one's pose envelope and its pose envelope ``_GAP`` beyond this one's footprint. Returns the
    reference x of every feature and the right end of the last envelope/footprint.
    """
    xs: list[float] = []
    x = x_start + max(extents[0][0], extents[0][2])
    for i, (fl, _, el, _) in enumerate(extents):
        if i:
            _, fr_prev, _, er_prev = extents[i - 1]
            x = xs[-1] + max(er_prev + _GAP + fl, fr_prev + _GAP + el)
        xs.append(x)
    return xs, xs[-1] + max(extents[-1][1], extents[-1][3])


def _steps(adds: list[manifold3d.Manifold], feats: list[_Feature]) -> float:
    y = _ROW_Y["A"]
    off = np.array(_STEP_OFFSETS_MM) * MM
    ext = [(0.0, _STEP_WIDTH, -off.min() + _RING_CLEAR, off.max() + _RING_CLEAR)]
    xs, end = _pack(ext * len(_STEP_HEIGHTS_MM), _X_MARGIN)
    for edge, h_mm in zip(xs, _STEP_HEIGHTS_MM, strict=True):
        h = h_mm * MM
        adds.append(
            _box(edge, y - _ROW_HALF, TOP_Z - _EMBED, edge + _STEP_WIDTH, y + _ROW_HALF, TOP_Z + h)
        )
        f = _Feature(
            f"step_{h_mm:02d}mm",
            "step",
            "height",
            h,
            (edge, y - _ROW_HALF, edge + _STEP_WIDTH, y + _ROW_HALF),
            {"height": h, "width": _STEP_WIDTH},
        )
        for d in off:
            z = TOP_Z + (h if d > 0 else 0.0)
            side = "on the step" if d > 0 else "below the step"
            f.add_pose(
                (edge + d, y, z), (0, 0, 1), d, f"{abs(d) / MM:g} mm {side}, across its edge"
            )
        feats.append(f)
    return end


def _ridges_and_grooves(
    adds: list[manifold3d.Manifold], cuts: list[manifold3d.Manifold], feats: list[_Feature]
) -> float:
    y = _ROW_Y["B"]
    off = np.array(_ACROSS_OFFSETS_MM) * MM
    specs = [("ridge", w, h) for w, h in _RIDGES_MM] + [("groove", w, h) for w, h in _RIDGES_MM]
    env = off.max() + _RING_CLEAR
    ext = [(w * MM / 2, w * MM / 2, env, env) for _, w, _ in specs]
    xs, end = _pack(ext, _X_MARGIN)
    for xc, (kind, w_mm, h_mm) in zip(xs, specs, strict=True):
        w, h = w_mm * MM, h_mm * MM
        x0, x1 = xc - w / 2, xc + w / 2
        if kind == "ridge":
            adds.append(_box(x0, y - _ROW_HALF, TOP_Z - _EMBED, x1, y + _ROW_HALF, TOP_Z + h))
            inside_z, dims = TOP_Z + h, {"width": w, "height": h}
            name = f"ridge_w{w_mm}_h{h_mm}mm"
        else:
            cuts.append(_box(x0, y - _ROW_HALF, TOP_Z - h, x1, y + _ROW_HALF, TOP_Z + 1 * MM))
            inside_z, dims = TOP_Z - h, {"width": w, "depth": h}
            name = f"groove_w{w_mm}_d{h_mm}mm"
        f = _Feature(name, kind, "width", w, (x0, y - _ROW_HALF, x1, y + _ROW_HALF), dims)
        for d in off:
            inside = abs(d) < w / 2
            where = f"in the {kind}" if kind == "groove" else f"on the {kind}"
            f.add_pose(
                (xc + d, y, inside_z if inside else TOP_Z),
                (0, 0, 1),
                d,
                f"{d / MM:+g} mm from the {kind} centre line ({where if inside else 'plate'})",
            )
        feats.append(f)
    return end


def _cylinder_rows(
    adds: list[manifold3d.Manifold], cuts: list[manifold3d.Manifold], feats: list[_Feature]
) -> tuple[float, float]:
    ends = []
    for kind, row in (("convex_cylinder", "C"), ("concave_cylinder", "D")):
        y = _ROW_Y[row]
        geo = []
        for r_mm in _CYLINDER_RADII_MM:
            r, cap = r_mm * MM, min(_CAP_MM, r_mm) * MM
            b = math.sqrt(r * r - (r - cap) ** 2)  # half-width of the footprint
            if b > _CYLINDER_HALF_WIDTH:
                b = _CYLINDER_HALF_WIDTH
                cap = r - math.sqrt(r * r - b * b)
            geo.append((r_mm, r, cap, b))
        ext = [(b, b, b / 2 + _RING_CLEAR, b / 2 + _RING_CLEAR) for *_, b in geo]
        xs, end = _pack(ext, _X_MARGIN)
        ends.append(end)
        for xc, (r_mm, r, cap, b) in zip(xs, geo, strict=True):
            fp = (xc - b, y - _ROW_HALF, xc + b, y + _ROW_HALF)
            if kind == "convex_cylinder":
                zc = TOP_Z + cap - r
                cyl = _y_cylinder(xc, y, zc, r)
                clip = _box(
                    xc - r - MM,
                    y - _ROW_HALF,
                    TOP_Z - _EMBED,
                    xc + r + MM,
                    y + _ROW_HALF,
                    TOP_Z + cap + MM,
                )
                adds.append(cyl ^ clip)
                f = _Feature(
                    f"convex_cylinder_r{r_mm:02d}mm",
                    kind,
                    "radius",
                    r,
                    fp,
                    {"radius": r, "height": cap},
                )
                sign, label = 1.0, "crest"
            else:
                zc = TOP_Z - cap + r
                cuts.append(_y_cylinder(xc, y, zc, r))
                f = _Feature(
                    f"concave_cylinder_r{r_mm:02d}mm",
                    kind,
                    "radius",
                    r,
                    fp,
                    {"radius": r, "depth": cap},
                )
                sign, label = -1.0, "trough"
            for dy in (-3 * MM, 0.0, 3 * MM):
                f.add_pose(
                    (xc, y + dy, zc + sign * r),
                    (0, 0, 1),
                    dy,
                    f"on the {label}, {dy / MM:+g} mm along it",
                )
            for dx in (-b / 2, b / 2):
                dz = math.sqrt(r * r - dx * dx)
                n = (sign * dx, 0.0, dz)
                f.add_pose(
                    (xc + dx, y, zc + sign * dz), n, dx, f"on the flank, {dx / MM:+.2f} mm across"
                )
            feats.append(f)
    return ends[0], ends[1]


def _domes(adds: list[manifold3d.Manifold], feats: list[_Feature]) -> float:
    y = _ROW_Y["E"]
    geo = []
    for r_mm in _DOME_RADII_MM:
        r = r_mm * MM
        cap = min(_CAP_MM * MM, r)
        if r > _ROW_HALF:
            cap = min(cap, r - math.sqrt(r * r - _ROW_HALF**2))  # footprint fits the row
        geo.append((r_mm, r, cap, math.sqrt(r * r - (r - cap) ** 2)))
    foot = (2 * MM, 5 * MM)
    ext = [(b, b, max(b, _RING_CLEAR), b + foot[-1] + _RING_CLEAR) for *_, b in geo]
    xs, end = _pack(ext, _X_MARGIN)
    for xc, (r_mm, r, cap, b) in zip(xs, geo, strict=True):
        zc = TOP_Z + cap - r
        sphere = manifold3d.Manifold.sphere(r, _segments(r)).translate((xc, y, zc))
        clip = _box(
            xc - r - MM, y - r - MM, TOP_Z - _EMBED, xc + r + MM, y + r + MM, TOP_Z + cap + MM
        )
        adds.append(sphere ^ clip)
        f = _Feature(
            f"dome_r{r_mm:02d}mm",
            "dome",
            "radius",
            r,
            (xc - b, y - b, xc + b, y + b),
            {"radius": r, "height": cap},
        )
        f.add_pose((xc, y, zc + r), (0, 0, 1), 0.0, "on the apex")
        dx = b / 2
        dz = math.sqrt(r * r - dx * dx)
        f.add_pose(
            (xc + dx, y, zc + dz), (dx, 0, dz), dx, f"on the flank, {dx / MM:+.2f} mm from the apex"
        )
        for g in foot:
            f.add_pose(
                (xc + b + g, y, TOP_Z),
                (0, 0, 1),
                b + g,
                f"on the plate {g / MM:g} mm beyond the foot",
            )
        feats.append(f)
    return end


def _holes(cuts: list[manifold3d.Manifold], feats: list[_Feature]) -> float:
    y = _ROW_Y["F"]
    off = np.array(_HOLE_RIM_OFFSETS_MM) * MM
    ext = [
        (d * MM / 2, d * MM / 2, d * MM / 2, d * MM / 2 + off.max() + _RING_CLEAR)
        for d in _HOLE_DIAMETERS_MM
    ]
    xs, end = _pack(ext, _X_MARGIN)
    for xc, d_mm in zip(xs, _HOLE_DIAMETERS_MM, strict=True):
        rad = d_mm * MM / 2
        cyl = manifold3d.Manifold.cylinder(TOP_Z + 2 * MM, rad, rad, _segments(rad))
        cuts.append(cyl.translate((xc, y, -MM)))
        f = _Feature(
            f"hole_d{d_mm:02d}mm",
            "hole",
            "diameter",
            2 * rad,
            (xc - rad, y - rad, xc + rad, y + rad),
        )
        f.dims["diameter"] = 2 * rad
        for g in off:
            f.add_pose(
                (xc + rad + g, y, TOP_Z), (0, 0, 1), rad + g, f"{g / MM:g} mm beyond the rim"
            )
        feats.append(f)
    return end


def _controls(feats: list[_Feature], row_ends: dict[str, float]) -> None:
    sx, sy, _ = PLATE_SIZE
    # Rows must leave room for the pose rings of the outer edge (row E) and the corner (row F).
    limits = dict.fromkeys(row_ends, sx - _X_MARGIN)
    limits["E"] = sx - _EDGE_INSETS_MM[-1] * MM - _RING_CLEAR - _GAP
    limits["F"] = sx - _CORNER_INSETS_MM[-1] * MM - _RING_CLEAR - _GAP
    for row, end in row_ends.items():
        if end > limits[row]:
            raise AssertionError(f"calibration board layout: row {row} does not fit on the plate")
    edge = _Feature("outer_edge", "edge", "inset", 0.0, None)
    y = _ROW_Y["E"]
    for d in np.array(_EDGE_INSETS_MM) * MM:
        edge.add_pose((sx - d, y, TOP_Z), (0, 0, 1), d, f"{d / MM:g} mm inside the right edge")
    corner = _Feature("corner_90deg", "corner", "inset", 0.0, None)
    for d in np.array(_CORNER_INSETS_MM) * MM:
        corner.add_pose(
            (sx - d, sy - d, TOP_Z), (0, 0, 1), d, f"{d / MM:g} mm inside both edges of the corner"
        )
    # Approach tilt on the flat plate (row F, after the holes): the same contact point, the
    # approach axis tilted about y (first spot) or x (second spot). The "normal" of these poses
    # is the reversed approach axis, not the surface normal.
    xt = row_ends["F"] + _GAP + _TILT_CLEAR
    for axis, x in (("y", xt), ("x", xt + 2 * _TILT_CLEAR + _GAP)):
        for deg in _TILTS_DEG:
            a = math.radians(deg)
            n = (math.sin(a), 0.0, math.cos(a)) if axis == "y" else (0.0, math.sin(a), math.cos(a))
            tilt = _Feature(f"tilt_{axis}_{deg:02d}deg", "tilt", "none", 0.0, None)
            tilt.dims["angle_rad"] = a
            tilt.add_pose(
                (x, _ROW_Y["F"], TOP_Z),
                n,
                0.0,
                f"flat plate, approach tilted {deg} deg about {axis}",
            )
            feats.append(tilt)
    row_ends["F"] = xt + 3 * _TILT_CLEAR + _GAP
    # Flat controls in the free ends of rows B, C, D, E and F.
    flat = _Feature("flat", "flat", "none", 0.0, None)
    for row in ("B", "C", "D", "E", "F"):
        x = row_ends[row] + _GAP + _RING_CLEAR
        if x + _RING_CLEAR > sx - _GAP:
            raise AssertionError(
                f"calibration board layout: no room for a flat control in row {row}"
            )
        flat.add_pose((x, _ROW_Y[row], TOP_Z), (0, 0, 1), 0.0, f"flat plate, row {row}")
    side = _Feature("side_face", "flat", "none", 0.0, None)
    for row in ("C", "D"):
        side.add_pose(
            (sx, _ROW_Y[row], TOP_Z / 2),
            (1, 0, 0),
            0.0,
            f"right side face, row {row} (horizontal approach)",
        )
    feats.extend([flat, side, edge, corner])


def _build() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], list[dict[str, Any]]]:
    adds: list[manifold3d.Manifold] = []
    cuts: list[manifold3d.Manifold] = []
    feats: list[_Feature] = []
    ends = {"A": _steps(adds, feats)}
    ends["B"] = _ridges_and_grooves(adds, cuts, feats)
    ends["C"], ends["D"] = _cylinder_rows(adds, cuts, feats)
    ends["E"] = _domes(adds, feats)
    ends["F"] = _holes(cuts, feats)
    _controls(feats, ends)
    plate = _box(0.0, 0.0, 0.0, *PLATE_SIZE)
    solid = manifold3d.Manifold.batch_boolean([plate, *adds], manifold3d.OpType.Add)
    solid = manifold3d.Manifold.batch_boolean([solid, *cuts], manifold3d.OpType.Subtract)
    if solid.status() != manifold3d.Error.NoError or solid.genus() != len(_HOLE_DIAMETERS_MM):
        raise BackendError(
            f"calibration board: boolean failed ({solid.status()}, genus {solid.genus()})"
        )
    mesh = solid.to_mesh64()
    vertices = np.ascontiguousarray(np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3])
    faces = np.ascontiguousarray(np.asarray(mesh.tri_verts, dtype=np.int32))
    out, pose_id = [], 0
    for f in feats:
        for p in f.poses:
            p["pose_id"] = pose_id
            pose_id += 1
        out.append(f.as_dict())
    return vertices, faces, out


_CACHE: tuple[npt.NDArray[np.float64], npt.NDArray[np.int32], list[dict[str, Any]]] | None = None


def make_calibration_board() -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.int32], list[dict[str, Any]]
]:
    """The calibration board mesh and its features with the cup poses to try.

    Returns:
        ``(vertices, faces, features)``: vertices (V, 3) float64 in metres (board frame, see the
        module docstring), faces (F, 3) int32 wound counter-clockwise seen from outside, and one
        dict per feature with ``name``, ``kind`` (step, ridge, groove, convex_cylinder,
        concave_cylinder, dome, hole, flat, edge, corner), ``parameter`` (the name of the graded
        quantity: height, width, radius, diameter, inset or none), ``parameter_m`` (its value,
        m; 0 for the controls), the feature's other dimensions as ``<name>_m``, ``footprint_m``
        ((x0, y0, x1, y1) on the plate or None) and ``poses``: a list of dicts with ``pose_id``
        (int, unique, consecutive from 0), ``point`` (contact point, m), ``normal`` (unit
        outward normal), ``offset_m`` (signed position relative to the feature's reference
        line: the step edge, the centre line, the rim, the plate edge) and ``description``.

    The mesh is a single closed, manifold solid. The result is computed once per process; the
    returned arrays and dicts are copies.
    """
    global _CACHE  # noqa: PLW0603 -- a module-level cache, filled once
    if _CACHE is None:
        _CACHE = _build()
    v, f, feats = _CACHE
    return v.copy(), f.copy(), [{**d, "poses": [dict(p) for p in d["poses"]]} for d in feats]


def board_poses(
    features: Sequence[dict[str, Any]],
) -> tuple[
    list[int], list[str], npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]
]:
    """Flattened poses of ``features``: (pose_ids, feature names, parameter_m (P,), points (P, 3),
    normals (P, 3)), in pose order."""
    ids, names, params, pts, nrm = [], [], [], [], []
    for f in features:
        for p in f["poses"]:
            ids.append(int(p["pose_id"]))
            names.append(str(f["name"]))
            params.append(float(f["parameter_m"]))
            pts.append(p["point"])
            nrm.append(p["normal"])
    return (
        ids,
        names,
        np.asarray(params, dtype=np.float64),
        np.asarray(pts, dtype=np.float64).reshape(-1, 3),
        np.asarray(nrm, dtype=np.float64).reshape(-1, 3),
    )


def write_binary_stl(
    vertices: npt.ArrayLike, faces: npt.ArrayLike, *, scale: float = 1.0, name: str = ""
) -> bytes:
    """Binary STL bytes of a triangle mesh (coordinates multiplied by ``scale``, float32)."""
    v = np.asarray(vertices, dtype=np.float64) * scale
    f = np.asarray(faces, dtype=np.int64)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    rec = np.zeros(
        len(f), dtype=np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    )
    rec["normal"] = n
    rec["v"] = tri
    header = name.encode("ascii", "replace")[:80].ljust(80, b" ")
    out: bytes = header + np.uint32(len(f)).astype("<u4").tobytes() + rec.tobytes()
    return out


POSES_COLUMNS = (
    "pose_id",
    "feature",
    "parameter_m",
    "x_m",
    "y_m",
    "z_m",
    "nx",
    "ny",
    "nz",
    "offset_m",
    "description",
)
RESULTS_COLUMNS = ("pose_id", "sealed", "tear_off_force_N")

_README = """\
mgn suction-cup calibration board
=================================

Files
-----
board.stl              the board to print (binary STL, units: MILLIMETRES). One closed solid,
                       {sx:g} x {sy:g} x {sz:g} mm, flat side down. Print solid or with >= 3
                       perimeters and >= 4 top layers so that the top surface is airtight;
                       sand away stringing at the hole rims.
poses.csv              the cup poses to try (units: METRES, board frame below).
results_template.csv   copy to results.csv and fill in one row per attempt.

Board frame
-----------
Origin at the plate's bottom-left-front corner (the corner at minimum x and y, on the build
plate); x along the {sx:g} mm edge, y along the {sy:g} mm edge, z up. The plate's top face is at
z = {top:g} m. Features by row (y of the row centre): A 19 mm steps, B 51 mm ridges and grooves,
C 83 mm convex cylinders, D 115 mm concave cylinders, E 147 mm domes, F 179 mm through-holes
and the two approach-tilt spots; the outer edge is x = {sx:g} mm (row E) and the 90-degree
corner is (x, y) = ({sx:g}, {sy:g}) mm. Two poses are on the right side face (x = {sx:g} mm).

poses.csv
---------
pose_id      unique integer id of the pose
feature      feature name, e.g. step_04mm, ridge_w2_h2mm, dome_r10mm, hole_d06mm, flat
parameter_m  the feature's graded parameter in metres (step height, ridge/groove width,
             cylinder/dome radius, hole diameter; 0 for the controls)
x_m y_m z_m  contact point on the board surface, metres
nx ny nz     unit outward surface normal; the cup approaches along -normal (tilt_* poses:
             the reversed approach axis, tilted from the plate normal by the stated angle)
offset_m     signed position relative to the feature's reference line, metres
description  the same in words

results.csv
-----------
pose_id           a pose of poses.csv; a pose may appear in several rows (repeated attempts)
sealed            1 if the cup sealed (held vacuum / lifted the board), 0 if not; leave blank
                  for poses you did not try (those rows are ignored)
tear_off_force_N  optional measured tear-off force in newtons (recorded, not used by the fit)

Then run:  mgn suction calibrate results.csv
"""


def write_calibration_board(
    out_dir: str | os.PathLike[str], *, overwrite: bool = False
) -> dict[str, Path]:
    """Write the board for printing and the experiment sheets into ``out_dir``.

    Files (each written atomically): ``board.stl`` (binary STL in millimetres), ``poses.csv``
    (metres; columns :data:`POSES_COLUMNS`), ``results_template.csv`` (columns
    :data:`RESULTS_COLUMNS`, ``sealed`` and the force left blank) and ``README.txt``.

    Args:
        out_dir: the folder (created if needed).
        overwrite: replace existing files; without it an existing file is an error (so that
            filled-in results are never overwritten by accident).

    Returns:
        The paths written, keyed by ``stl``, ``poses``, ``results_template`` and ``readme``.

    Raises:
        IoError: a file exists (without ``overwrite``) or cannot be written.
    """

    root = Path(out_dir)
    paths = {
        "stl": root / "board.stl",
        "poses": root / "poses.csv",
        "results_template": root / "results_template.csv",
        "readme": root / "README.txt",
    }
    if not overwrite:
        existing = [str(p) for p in paths.values() if p.exists()]
        if existing:
            raise IoError(
                f"write_calibration_board: {existing} already exist;"
                " pass overwrite=True to replace them"
            )
    vertices, faces, features = make_calibration_board()

    poses = io.StringIO()
    w = csv.writer(poses, lineterminator="\n")
    w.writerow(POSES_COLUMNS)
    for f in features:
        for p in f["poses"]:
            w.writerow(
                [
                    p["pose_id"],
                    f["name"],
                    f"{f['parameter_m']:.6f}",
                    *(f"{v:.6f}" for v in p["point"]),
                    *(f"{v:.6f}" for v in p["normal"]),
                    f"{p['offset_m']:.6f}",
                    p["description"],
                ]
            )
    template = io.StringIO()
    w = csv.writer(template, lineterminator="\n")
    w.writerow(RESULTS_COLUMNS)
    for f in features:
        for p in f["poses"]:
            w.writerow([p["pose_id"], "", ""])

    sx, sy, sz = (v / MM for v in PLATE_SIZE)
    stl = write_binary_stl(vertices, faces, scale=1.0 / MM, name="mgn calibration board, units: mm")
    atomic_write_bytes(paths["stl"], stl)
    atomic_write_text(paths["poses"], poses.getvalue())
    atomic_write_text(paths["results_template"], template.getvalue())
    atomic_write_text(paths["readme"], _README.format(sx=sx, sy=sy, sz=sz, top=TOP_Z))
    return paths
