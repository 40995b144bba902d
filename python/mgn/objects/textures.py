"""Procedural "printed" textures for the object library (pure numpy, deterministic).

Every function returns an RGB image as a (H, W, 3) uint8 array; row 0 is the top of the image.
Randomness (bar codes, speckles) comes from ``numpy.random.default_rng(seed)`` with a fixed seed,
so the same arguments always give the same bytes. No fonts or other external resources are used:
letters come from a built-in 5 x 7 pixel font drawn as filled blocks.

How images map onto meshes (see :mod:`mgn.objects.shapes` for the UV convention):

- :func:`box_atlas` is a 3 x 2 atlas of square cells, one per box face in the order
  ``+x, -x, +y, -y, +z, -z`` (left to right, top row first); each side cell is drawn upright
  (its top edge is the box's top, +z).
- :func:`wrap_label` is wrapped around a body of revolution: the horizontal axis is the angle,
  the vertical axis the profile from the bottom (last row) to the top (first row).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["FONT_5X7", "Palette", "box_atlas", "draw_text", "wrap_label"]

Color = tuple[int, int, int]

_BAR_INK: Color = (15, 15, 15)  # bar codes are always printed black on white

# 5 x 7 block font, '#' = ink. Written for this project.
FONT_5X7: dict[str, tuple[str, ...]] = {
    "A": (".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"),
    "B": ("####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."),
    "C": (".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."),
    "D": ("####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####."),
    "E": ("#####", "#....", "#....", "####.", "#....", "#....", "#####"),
    "F": ("#####", "#....", "#....", "####.", "#....", "#....", "#...."),
    "G": (".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"),
    "H": ("#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"),
    "I": ("#####", "..#..", "..#..", "..#..", "..#..", "..#..", "#####"),
    "J": ("..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."),
    "K": ("#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"),
    "L": ("#....", "#....", "#....", "#....", "#....", "#....", "#####"),
    "M": ("#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"),
    "N": ("#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#", "#...#"),
    "O": (".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."),
    "P": ("####.", "#...#", "#...#", "####.", "#....", "#....", "#...."),
    "Q": (".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"),
    "R": ("####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"),
    "S": (".####", "#....", "#....", ".###.", "....#", "....#", "####."),
    "T": ("#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."),
    "U": ("#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."),
    "V": ("#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."),
    "W": ("#...#", "#...#", "#...#", "#.#.#", "#.#.#", "##.##", "#...#"),
    "X": ("#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"),
    "Y": ("#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."),
    "Z": ("#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"),
    "0": (".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."),
    "1": ("..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."),
    "2": (".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"),
    "3": ("####.", "....#", "....#", ".###.", "....#", "....#", "####."),
    "4": ("...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."),
    "5": ("#####", "#....", "####.", "....#", "....#", "#...#", ".###."),
    "6": (".###.", "#....", "#....", "####.", "#...#", "#...#", ".###."),
    "7": ("#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."),
    "8": (".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."),
    "9": (".###.", "#...#", "#...#", ".####", "....#", "....#", ".###."),
    " ": (".....",) * 7,
    "-": (".....", ".....", ".....", "#####", ".....", ".....", "....."),
}


@dataclass(frozen=True)
class Palette:
    """Colours of one printed design (8-bit sRGB triples).

    Attributes:
        background: main print colour.
        accent: stripes, panels.
        ink: letters.
        highlight: small details (panels, discs, waves).
    """

    background: Color
    accent: Color
    ink: Color
    highlight: Color


def _fill_rect(img: np.ndarray, x0: float, y0: float, x1: float, y1: float, color: Color) -> None:
    """Fill the pixel rectangle [x0, x1) x [y0, y1) (clipped), coordinates in pixels."""
    h, w, _ = img.shape
    xa, xb = max(0, int(round(x0))), min(w, int(round(x1)))
    ya, yb = max(0, int(round(y0))), min(h, int(round(y1)))
    if xa < xb and ya < yb:
        img[ya:yb, xa:xb] = color


def _fill_disc(img: np.ndarray, cx: float, cy: float, r: float, color: Color) -> None:
    h, w, _ = img.shape
    yy, xx = np.mgrid[0:h, 0:w]
    img[(xx + 0.5 - cx) ** 2 + (yy + 0.5 - cy) ** 2 <= r * r] = color


def _diagonal_stripes(img: np.ndarray, period: float, width: float, color: Color) -> None:
    h, w, _ = img.shape
    yy, xx = np.mgrid[0:h, 0:w]
    img[((xx + yy) % period) < width] = color


def draw_text(img: np.ndarray, text: str, x: float, y: float, scale: float, color: Color) -> None:
    """Draw ``text`` with the 5 x 7 block font; (x, y) is the top-left corner in pixels.

    Each font pixel becomes a ``scale`` x ``scale`` block; characters advance by 6 blocks.
    Unknown characters are drawn as blanks.
    """
    for k, ch in enumerate(text.upper()):
        glyph = FONT_5X7.get(ch, FONT_5X7[" "])
        ox = x + k * 6 * scale
        for row, line in enumerate(glyph):
            for col, px in enumerate(line):
                if px == "#":
                    _fill_rect(
                        img,
                        ox + col * scale,
                        y + row * scale,
                        ox + (col + 1) * scale,
                        y + (row + 1) * scale,
                        color,
                    )


def _barcode(
    img: np.ndarray, rng: np.random.Generator, x0: int, y0: int, x1: int, y1: int, ink: Color
) -> None:
    """A white quiet zone with random bars of 1-3 px, like a retail bar code."""
    _fill_rect(img, x0 - 3, y0 - 3, x1 + 3, y1 + 3, (250, 250, 250))
    x = x0
    dark = True
    while x < x1:
        width = int(rng.integers(1, 4))
        if dark:
            _fill_rect(img, x, y0, min(x + width, x1), y1, ink)
        x += width
        dark = not dark


def _text_fit(length: int, width: float, height: float) -> float:
    """Largest block scale so that ``length`` characters fit into width x height pixels."""
    return max(1.0, min(width / (6 * max(length, 1)), height / 8))


def _front_panel(cell: np.ndarray, pal: Palette, title: str, rng: np.random.Generator) -> None:
    n = cell.shape[0]
    cell[:] = pal.background
    _diagonal_stripes(cell, period=n / 6, width=n / 24, color=pal.accent)
    _fill_rect(cell, n * 0.08, n * 0.22, n * 0.92, n * 0.62, pal.highlight)
    scale = _text_fit(len(title), n * 0.76, n * 0.34)
    tw = len(title) * 6 * scale - scale
    draw_text(cell, title, (n - tw) / 2, n * 0.42 - 3.5 * scale, scale, pal.ink)
    _fill_disc(cell, n * 0.78, n * 0.80, n * 0.11, pal.accent)
    _fill_disc(cell, n * 0.78, n * 0.80, n * 0.06, pal.highlight)
    _fill_rect(cell, 0, n * 0.92, n, n, pal.accent)
    for k in range(int(rng.integers(3, 6))):
        _fill_rect(
            cell,
            n * 0.08,
            n * (0.68 + 0.045 * k),
            n * (0.25 + 0.3 * rng.random()),
            n * (0.70 + 0.045 * k),
            pal.ink,
        )


def _side_panel(cell: np.ndarray, pal: Palette, title: str, rng: np.random.Generator) -> None:
    n = cell.shape[0]
    cell[:] = pal.background
    for k in range(4):
        _fill_rect(cell, 0, n * (0.1 + 0.2 * k), n, n * (0.1 + 0.2 * k) + n * 0.06, pal.accent)
    letter = title[:1]
    scale = n * 0.5 / 7
    draw_text(cell, letter, (n - 5 * scale) / 2, n * 0.25, scale, pal.ink)
    for k in range(6):
        _fill_rect(
            cell,
            n * 0.1,
            n * (0.86 + 0.018 * k),
            n * (0.4 + 0.5 * rng.random()),
            n * (0.87 + 0.018 * k),
            pal.ink,
        )


def _lid_panel(cell: np.ndarray, pal: Palette, rng: np.random.Generator) -> None:
    n = cell.shape[0]
    cell[:] = pal.accent
    _fill_rect(cell, n * 0.05, n * 0.05, n * 0.95, n * 0.95, pal.background)
    _barcode(cell, rng, int(n * 0.2), int(n * 0.55), int(n * 0.8), int(n * 0.8), _BAR_INK)
    draw_text(
        cell,
        "".join(str(int(d)) for d in rng.integers(0, 10, 6)),
        n * 0.2,
        n * 0.83,
        max(1.0, n / 90),
        pal.ink,
    )
    _fill_rect(cell, n * 0.2, n * 0.15, n * 0.8, n * 0.4, pal.highlight)


def box_atlas(
    size: Sequence[float],
    palette: Palette,
    title: str,
    seed: int,
    cell: int = 128,
) -> np.ndarray:
    """Printed carton artwork as a 3 x 2 atlas for :func:`mgn.objects.shapes.grid_box`.

    The two largest side faces get the front design (title, panel, logo disc), the other two
    side faces a big initial with stripes, the top and bottom a bar code.

    Args:
        size: box edge lengths (sx, sy, sz) in metres (only used to pick the front faces).
        palette: colours.
        title: short upper-case word printed on the front (letters, digits, spaces).
        seed: random seed of the details (bar code, text lines).
        cell: cell edge in pixels; the image is (2 * cell, 3 * cell, 3).

    Returns:
        (2 * cell, 3 * cell, 3) uint8 RGB image.
    """
    rng = np.random.default_rng(seed)
    sx, sy, _sz = (float(s) for s in size)
    img = np.zeros((2 * cell, 3 * cell, 3), dtype=np.uint8)
    # faces +x, -x have extent sy x sz; +y, -y: sx x sz
    x_faces_are_front = sy >= sx
    for k in range(6):
        col, row = k % 3, k // 3
        tile = img[row * cell : (row + 1) * cell, col * cell : (col + 1) * cell]
        if k >= 4:
            _lid_panel(tile, palette, rng)
        elif (k < 2) == x_faces_are_front:
            _front_panel(tile, palette, title, rng)
        else:
            _side_panel(tile, palette, title, rng)
    return img


def wrap_label(
    palette: Palette,
    title: str,
    seed: int,
    body: tuple[float, float],
    size: int = 256,
    *,
    metal: Color = (190, 192, 196),
) -> np.ndarray:
    """Label wrapped around a revolved body (a can, a spray can).

    Args:
        palette: colours of the printed label.
        title: short word printed twice around the body.
        seed: random seed of the details.
        body: (v_bottom, v_top), the part of the profile (as texture v in [0, 1]) covered by the
            label; outside it the image shows bare metal (``metal``).
        size: image edge in pixels (square image).

    Returns:
        (size, size, 3) uint8 RGB image.
    """
    rng = np.random.default_rng(seed)
    img = np.empty((size, size, 3), dtype=np.uint8)
    img[:] = metal
    v0, v1 = body
    top = int(round((1.0 - v1) * size))
    bottom = int(round((1.0 - v0) * size))
    label = img[top:bottom]
    h = label.shape[0]
    label[:] = palette.background
    _fill_rect(label, 0, 0, size, h * 0.1, palette.accent)
    _fill_rect(label, 0, h * 0.9, size, h, palette.accent)
    yy, xx = np.mgrid[0:h, 0:size]
    wave = h * (0.62 + 0.08 * np.sin(xx * (4.0 * np.pi / size)))
    label[(yy > wave) & (yy < wave + h * 0.07)] = palette.highlight
    scale = _text_fit(len(title), size * 0.4, h * 0.3)
    for k in range(2):
        draw_text(label, title, size * (0.05 + 0.5 * k), h * 0.25, scale, palette.ink)
    _barcode(label, rng, int(size * 0.80), int(h * 0.72), int(size * 0.95), int(h * 0.86), _BAR_INK)
    return img
