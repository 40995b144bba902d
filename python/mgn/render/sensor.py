"""Depth sensor models applied to rendered z-depth (typed façade over the C++ core).

Presets (see ``cpp/include/mgn/render/depth_sensor.hpp`` for the exact models):

- ``"ideal"``: the rendered depth; only pixels where nothing is seen are invalid.
- ``"structured-light"``: industrial projector-camera sensor: sub-millimetre noise growing with
  z^2, invalid pixels where the projector (10 cm along camera +x) cannot see the surface, and on
  transparent, dark and mirror-like surfaces.
- ``"tof"``: Kinect-like time of flight: noise 1.2 mm + 1.9 mm/m^2 (z - 0.4 m)^2, flying pixels at
  depth edges, invalid on transparent, dark and mirror-like surfaces.

Invalid pixels are **NaN** in the sensor depth; the noise-free input is kept as ``depth_ideal``
(0 where nothing is seen). Row v of the noise draws from the stream (seed, v).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Material, Mesh
from mgn.scene.cameras import Intrinsics

__all__ = [
    "SURFACE_DARK",
    "SURFACE_MIRROR",
    "SURFACE_TRANSPARENT",
    "DepthImage",
    "SensorName",
    "apply_depth_sensor",
    "sensor_params",
    "surface_flags",
]

SensorName = Literal["ideal", "structured-light", "tof"]
#: Surface flag bits (see :func:`surface_flags`).
SURFACE_TRANSPARENT: int = _core.render.SURFACE_TRANSPARENT
SURFACE_DARK: int = _core.render.SURFACE_DARK
SURFACE_MIRROR: int = _core.render.SURFACE_MIRROR

_PRESETS = {
    "ideal": _core.render.DepthSensorPreset.Ideal,
    "structured-light": _core.render.DepthSensorPreset.StructuredLight,
    "tof": _core.render.DepthSensorPreset.ToF,
}


def sensor_params(preset: SensorName, **overrides: float | bool) -> _core.render.DepthSensorParams:
    """Default parameters of a preset, with fields overridden by keyword (SI units), e.g.
    ``sensor_params("structured-light", baseline=0.05)``."""
    if preset not in _PRESETS:
        raise InvalidArgumentError(
            f"sensor preset must be one of {sorted(_PRESETS)}, got {preset!r}"
        )
    p = _core.render.DepthSensorParams.preset_defaults(_PRESETS[preset])
    for key, value in overrides.items():
        if key == "preset" or not hasattr(p, key):
            raise InvalidArgumentError(f"unknown depth sensor parameter {key!r}")
        setattr(p, key, value)
    p.validate()
    return p


def surface_flags(item: Material | Mesh) -> int:
    """Flag bits of a material (or the union over a mesh's materials): transparent if opacity x
    alpha < 0.5 or (PBR) transmission >= 0.5, dark if untextured with linear luminance < 0.03,
    mirror if specular luminance >= 0.8 and shininess >= 200 or (PBR) metallic >= 0.5 with
    roughness <= 0.25 (polished metal)."""
    if isinstance(item, Mesh):
        return int(_core.render.mesh_surface_flags(item))
    return int(_core.render.surface_flags(item))


@dataclass(frozen=True)
class DepthImage:
    """Sensor output: ``depth`` (H, W) float32 m, NaN invalid; ``depth_ideal`` (H, W) float32 m,
    0 where nothing is seen; ``valid`` (H, W) bool."""

    depth: npt.NDArray[np.float32]
    depth_ideal: npt.NDArray[np.float32]
    valid: npt.NDArray[np.bool_]


def apply_depth_sensor(
    depth: npt.ArrayLike,
    instance_ids: npt.ArrayLike,
    K: Intrinsics,
    sensor: SensorName | _core.render.DepthSensorParams = "structured-light",
    *,
    flags_by_id: npt.ArrayLike | None = None,
    seed: int = 0,
    num_threads: int = 0,
) -> DepthImage:
    """Apply a depth sensor model to a rendered z-depth image.

    Args:
        depth: (H, W) z-depth in metres, 0 where nothing is seen (``RenderOutput.depth``).
        instance_ids: (H, W) instance ids (``RenderOutput.instance_ids``).
        K: the intrinsics the images were rendered with.
        sensor: a preset name or parameters from :func:`sensor_params`.
        flags_by_id: per instance id, surface flag bits (``Renderer.surface_flags_by_id()``);
            None = no special surfaces.
        seed: noise stream seed.
        num_threads: threads for the rows (0 = all); the result does not depend on it.
    """
    params = sensor_params(sensor) if isinstance(sensor, str) else sensor
    flags = [] if flags_by_id is None else [int(f) for f in np.asarray(flags_by_id).ravel()]
    out = _core.render.apply_depth_sensor(
        np.asarray(depth, np.float32),
        np.asarray(instance_ids, np.int32),
        flags,
        K.to_core(),
        params,
        int(seed),
        int(num_threads),
    )
    return DepthImage(out.depth, out.depth_ideal, out.valid)
