"""Materials of the built-in catalogue: sRGB colours to linear RGBA, a :class:`MaterialSpec`
from a few numbers, and the materials several objects share.

Colours are linear RGBA in [0, 1]; the specular level, shininess and opacity drive the raster
preview, the physically based parameters (roughness, metallic, transmission, index of
refraction) the path tracer.
"""

from __future__ import annotations

import numpy as np

from .spec import MaterialSpec

__all__ = [
    "BLACK",
    "CARDBOARD_PRINT",
    "CLEAR_GLASS",
    "PRINTED_METAL",
    "WHITE",
    "linear_rgba",
    "make_material",
]


def linear_rgba(hex_srgb: str, alpha: float = 1.0) -> tuple[float, float, float, float]:
    """'#rrggbb' sRGB colour -> linear RGBA."""
    c = np.array([int(hex_srgb[i : i + 2], 16) for i in (1, 3, 5)], dtype=np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return (round(float(lin[0]), 4), round(float(lin[1]), 4), round(float(lin[2]), 4), alpha)


def make_material(
    name: str,
    color: tuple[float, float, float, float],
    specular: float = 0.2,
    shininess: float = 20.0,
    opacity: float = 1.0,
    *,
    roughness: float,
    metallic: float = 0.0,
    transmission: float = 0.0,
    ior: float = 1.5,
) -> MaterialSpec:
    """Material with a grey specular colour of level ``specular`` (raster preview) and its
    physically based parameters (path tracer)."""
    return MaterialSpec(
        name,
        color,
        (specular, specular, specular),
        shininess,
        opacity,
        None,
        metallic=metallic,
        roughness=roughness,
        ior=ior,
        transmission=transmission,
    )


WHITE = (1.0, 1.0, 1.0, 1.0)
BLACK = (0.03, 0.03, 0.03, 1.0)
# Printed cardboard: a rough dielectric (uncoated board, matte print).
CARDBOARD_PRINT = make_material("cardboard_print", WHITE, 0.1, 10.0, roughness=0.75)
# Printed tinplate: lacquered print over steel, the metal showing through.
PRINTED_METAL = make_material("printed_metal", WHITE, 0.6, 60.0, roughness=0.28, metallic=0.45)
# Clear soda-lime glass / PET: a smooth dielectric that transmits (n = 1.5).
CLEAR_GLASS = make_material(
    "clear_glass",
    (0.85, 0.92, 0.9, 0.15),
    0.9,
    120.0,
    0.15,
    roughness=0.02,
    transmission=1.0,
    ior=1.5,
)
