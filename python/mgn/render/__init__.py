"""OSMesa rendering and depth sensor models (the cameras are :mod:`mgn.scene.cameras`).

- :mod:`mgn.render.renderer`: :class:`Renderer` (RGB, metric z-depth, instance ids; one GL
  context reused across views).
- :mod:`mgn.render.sensor`: :func:`apply_depth_sensor` with presets ``ideal``,
  ``structured-light`` and ``tof``.
- :mod:`mgn.render.views`: :func:`iter_views`, render the views of a scene as arrays
  (:func:`mgn.render_views` also writes them).
"""

from mgn.render.renderer import Instance, LightSample, Renderer, RenderOutput
from mgn.render.sensor import (
    SURFACE_DARK,
    SURFACE_MIRROR,
    SURFACE_TRANSPARENT,
    DepthImage,
    apply_depth_sensor,
    sensor_params,
    surface_flags,
)
from mgn.render.views import ViewImages, depth_picture, iter_views

__all__ = [
    "SURFACE_DARK",
    "SURFACE_MIRROR",
    "SURFACE_TRANSPARENT",
    "DepthImage",
    "Instance",
    "LightSample",
    "RenderOutput",
    "Renderer",
    "ViewImages",
    "apply_depth_sensor",
    "depth_picture",
    "iter_views",
    "sensor_params",
    "surface_flags",
]
