"""
mgn compiled core (private): use the typed API of the `mgn` package instead.
"""

from __future__ import annotations

from . import collision, core, geometry, grasp, raytrace, render, scene

__all__: list[str] = ["collision", "core", "geometry", "grasp", "raytrace", "render", "scene"]
__version__: str = "0.1.0"
