"""Building blocks of the catalogue's builders (:mod:`mgn.objects.catalogue`): what a builder
returns (:class:`Built`), millimetre tables to metres, cylinders, elliptic arcs, printed boxes
with their keypoints and smooth random surface noise.

Lengths are metres unless a name says millimetres (``from_mm``, ``keypoints_mm``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from . import textures as tx
from .shapes import Mesh, grid_box, revolve

__all__ = [
    "MM",
    "SEG",
    "Built",
    "arc_fractions",
    "box_keypoints",
    "cylinder",
    "ellipse_arc",
    "from_mm",
    "keypoints_mm",
    "polyline",
    "printed_box",
    "smooth_noise",
]

MM = 1e-3  # metres per millimetre
SEG = 64  # angular steps of bodies of revolution


@dataclass(frozen=True)
class Built:
    """A builder's output: mesh and named keypoints in the builder's own frame (metres)."""

    mesh: Mesh
    keypoints: tuple[tuple[str, tuple[float, float, float]], ...]
    texture: np.ndarray | None = None


def from_mm(points: Sequence[Sequence[float]]) -> np.ndarray:
    return np.asarray(points, dtype=np.float64) * MM


def keypoints_mm(**named: Sequence[float]) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """Keypoints given in millimetres, in keyword order."""
    return tuple((n, tuple(float(c) * MM for c in p)) for n, p in named.items())  # type: ignore[misc]


def arc_fractions(profile: np.ndarray) -> np.ndarray:
    """Texture v of each profile point, as :func:`revolve` assigns it (open profile)."""
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(profile, axis=0), axis=1))])
    out: np.ndarray = arc / arc[-1]
    return out


def cylinder(radius: float, z0: float, z1: float, segments: int = 32, axial_steps: int = 1) -> Mesh:
    """Closed cylinder about the z axis from z0 to z1 (metres)."""
    zs = np.linspace(z0, z1, axial_steps + 1)
    prof = [(0.0, z0)] + [(radius, z) for z in zs] + [(0.0, z1)]
    return revolve(prof, segments)


def polyline(*pieces: np.ndarray) -> np.ndarray:
    """Concatenate point arrays, dropping a piece's first point when it repeats the previous end."""
    out = [pieces[0]]
    for p in pieces[1:]:
        out.append(p[1:] if np.allclose(p[0], out[-1][-1]) else p)
    return np.concatenate(out)


def ellipse_arc(
    centre: Sequence[float], radii: Sequence[float], a0: float, a1: float, n: int
) -> np.ndarray:
    """Points (r, z) on an axis-aligned ellipse arc, angles in radians from a0 to a1 inclusive."""
    t = np.linspace(a0, a1, n)
    return np.stack([centre[0] + radii[0] * np.cos(t), centre[1] + radii[1] * np.sin(t)], axis=1)


def box_keypoints(size: Sequence[float]) -> tuple[tuple[str, tuple[float, float, float]], ...]:
    """Face centres and one top corner of a centred box (metres).

    "front"/"back" are the two largest side faces (those printed with the title, see
    :func:`mgn.objects.textures.box_atlas`), "left"/"right" the two other side faces.
    """
    sx, sy, sz = (0.5 * s for s in size)
    x_is_front = size[1] >= size[0]
    x_names = ("front_centre", "back_centre") if x_is_front else ("right_centre", "left_centre")
    y_names = ("left_centre", "right_centre") if x_is_front else ("back_centre", "front_centre")
    return (
        ("top_centre", (0.0, 0.0, sz)),
        ("bottom_centre", (0.0, 0.0, -sz)),
        (x_names[0], (sx, 0.0, 0.0)),
        (x_names[1], (-sx, 0.0, 0.0)),
        (y_names[0], (0.0, sy, 0.0)),
        (y_names[1], (0.0, -sy, 0.0)),
        ("top_corner", (sx, sy, sz)),
    )


def printed_box(size_mm: Sequence[float], palette: tx.Palette, title: str, seed: int) -> Built:
    size = tuple(s * MM for s in size_mm)
    mesh = grid_box(size, max_edge=0.012, with_uv=True)
    tex = tx.box_atlas(size, palette, title, seed)
    return Built(mesh, box_keypoints(size), tex)


def smooth_noise(seed: int, amplitude: float, terms: int = 7) -> Callable[[np.ndarray], np.ndarray]:
    """Radial factor 1 + a smooth random field on the unit sphere (fixed seed), always > 0."""
    rng = np.random.default_rng(seed)
    dirs = rng.normal(size=(terms, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    freq = rng.uniform(2.0, 6.0, terms)
    phase = rng.uniform(0.0, 2.0 * np.pi, terms)
    weights = rng.uniform(0.5, 1.0, terms)
    weights *= amplitude / weights.sum()

    def factor(d: np.ndarray) -> np.ndarray:
        out: np.ndarray = 1.0 + np.sin(d @ dirs.T * freq + phase) @ weights
        return out

    return factor
