"""Off-screen RGB-D and instance-id rendering (OSMesa, typed façade over the C++ core).

One :class:`Renderer` owns one GL context, created once and reused for every view; meshes are
uploaded once and placed as instances. Run one renderer per process to use several cores (the
GL rasteriser also uses threads). Long calls release the GIL.

Images are top row first: ``rgb`` (H, W, 3) uint8 sRGB, ``depth`` (H, W) float32 metric z-depth
in metres (0 where nothing is seen; transparent surfaces are seen), ``instance_ids`` (H, W)
int32 (0 = background).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.geometry.mesh import Mesh
from mgn.scene.cameras import CameraView

__all__ = ["Instance", "LightSample", "RenderOutput", "Renderer"]

#: The C++ defaults (mgn/render/renderer.hpp): the one place they are written.
_LIGHT = _core.render.LightSample()


@dataclass(frozen=True)
class Instance:
    """One placed copy of an uploaded mesh.

    Attributes:
        mesh_id: id returned by :meth:`Renderer.add_mesh`.
        X_WO: (4, 4) pose of the mesh in the world.
        instance_id: value in the instance pass (>= 0; 0 = background, e.g. tote and floor).
        randomize_color: replace its colour by a random one per view when rendering with
            ``randomize=True`` (domain randomisation of tote / floor).
    """

    mesh_id: int
    X_WO: npt.NDArray[np.float64] = field(repr=False)
    instance_id: int
    randomize_color: bool = False


@dataclass(frozen=True)
class LightSample:
    """Main point light: world position (m), intensity (1 nominal), colour temperature (K) and
    ambient level. ``position_W=None`` places it 1.5 m above the centre of the scene."""

    position_W: tuple[float, float, float] | None = None
    intensity: float = _LIGHT.intensity
    color_temperature: float = _LIGHT.color_temperature
    ambient: float = _LIGHT.ambient

    def to_core(self) -> _core.render.LightSample:
        """The C++ light (``position_W=None``: NaN, the default position)."""
        light = _core.render.LightSample()
        if self.position_W is not None:
            x, y, z = (float(v) for v in self.position_W)
            light.position_W = (x, y, z)
        light.intensity = float(self.intensity)
        light.color_temperature = float(self.color_temperature)
        light.ambient = float(self.ambient)
        return light


@dataclass(frozen=True)
class RenderOutput:
    """Images of one view (None for passes not requested) and the light used."""

    rgb: npt.NDArray[np.uint8] | None
    depth: npt.NDArray[np.float32] | None
    instance_ids: npt.NDArray[np.int32] | None
    light: LightSample


class Renderer:
    """OSMesa renderer with framebuffers of at most ``max_width`` x ``max_height`` px."""

    def __init__(self, max_width: int = 1200, max_height: int = 1200) -> None:
        self._r = _core.render.Renderer(int(max_width), int(max_height))
        self._mesh_flags: list[int] = []
        self._instances: list[Instance] = []

    @property
    def max_size(self) -> tuple[int, int]:
        """(max_width, max_height) in px."""
        return int(self._r.max_width), int(self._r.max_height)

    @property
    def num_meshes(self) -> int:
        return int(self._r.num_meshes)

    def add_mesh(self, mesh: Mesh) -> int:
        """Upload a mesh (with its materials and textures) once; returns its id."""
        mesh_id = int(self._r.add_mesh(mesh))
        self._mesh_flags.append(int(_core.render.mesh_surface_flags(mesh)))
        return mesh_id

    def set_instances(self, instances: Sequence[Instance]) -> None:
        """Replace the placed instances."""
        items = list(instances)
        poses = (
            np.stack([np.asarray(i.X_WO, np.float64) for i in items])
            if items
            else np.zeros((0, 4, 4))
        )
        self._r.set_instances(
            [int(i.mesh_id) for i in items],
            poses,
            [int(i.instance_id) for i in items],
            [bool(i.randomize_color) for i in items],
        )
        self._instances = items

    @property
    def instances(self) -> list[Instance]:
        return list(self._instances)

    def surface_flags_by_id(self) -> npt.NDArray[np.uint8]:
        """Per instance id, the union of the surface flags (transparent / dark / mirror bits of
        :mod:`mgn.render.sensor`) of the meshes placed with that id."""
        n = max((i.instance_id for i in self._instances), default=0) + 1
        flags = np.zeros(n, np.uint8)
        for i in self._instances:
            flags[i.instance_id] |= self._mesh_flags[i.mesh_id]
        return flags

    def render(
        self,
        view: CameraView,
        *,
        rgb: bool = True,
        depth: bool = True,
        instances: bool = True,
        visible_instances: Sequence[int] | None = None,
        shadows: bool = True,
        randomize: bool = False,
        seed: int = 0,
        view_index: int = 0,
        light: LightSample | None = None,
        background: tuple[float, float, float] = (0.0, 0.0, 0.0),
        check_camera_inside: bool = True,
    ) -> RenderOutput:
        """Render one view.

        Args:
            view: camera (intrinsics no larger than the framebuffers) and pose.
            rgb, depth, instances: which passes to produce. Without ``rgb`` no shading or shadow
                pass runs (cheap geometry-only pass).
            visible_instances: draw only instances with these ids (e.g. one object alone for its
                amodal mask); None draws all.
            shadows: shadow mapping from the main light.
            randomize: draw the light and the colours of ``randomize_color`` instances from the
                stream (seed, view_index); otherwise ``light`` is used.
            background: linear RGB of empty pixels.
            check_camera_inside: raise if the camera centre is inside a closed mesh.
        """
        if view.K.distortion:
            raise InvalidArgumentError(
                f"Renderer.render draws pinhole images; the camera has distortion "
                f"{list(view.K.distortion)}: render it with mgn.render.iter_views (which resamples "
                "through the lens) or render lens_for(K).render_K (mgn.scene.lens)"
            )
        o = _core.render.RenderOptions()
        o.rgb = bool(rgb)
        o.depth = bool(depth)
        o.instances = bool(instances)
        o.visible_instances = (
            [] if visible_instances is None else [int(i) for i in visible_instances]
        )
        o.shadows = bool(shadows)
        o.randomize = bool(randomize)
        o.seed = int(seed)
        o.view_index = int(view_index)
        o.light = (LightSample() if light is None else light).to_core()
        r, g, b = (float(c) for c in background)
        o.background = (r, g, b)
        o.check_camera_inside = bool(check_camera_inside)
        out = self._r.render(view.K.to_core(), view.X_WC, o)
        ld = out.light
        used = LightSample(
            tuple(float(x) for x in ld.position_W),  # type: ignore[arg-type]
            float(ld.intensity),
            float(ld.color_temperature),
            float(ld.ambient),
        )
        return RenderOutput(out.rgb, out.depth, out.instance_ids, used)
