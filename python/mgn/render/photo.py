"""Photographs of a scene: the path-traced RGB of a view, denoised and developed
(:class:`PhotoRenderer`).

Two engines make the ``{v}_rgb.png`` of a view (:class:`mgn.render.settings.RenderSettings`,
config section ``render``):

- ``raster``: the OpenGL (OSMesa) Blinn-Phong preview of :class:`mgn.render.Renderer`; fast.
- ``path``: the physically based path tracer :mod:`mgn.render.path` (glTF metallic-roughness
  materials, :mod:`mgn.render.materials`; glass, area lights, an environment dome), denoised with
  Intel Open Image Denoise (the optional ``pyoidn`` package, :mod:`mgn.render.denoiser`) and
  developed with exposure, a filmic curve and optional sensor noise
  (:func:`mgn.render.path.develop`).

Labels never depend on the engine: depth, instance ids and every mask come from the raster's
geometry passes, which the path tracer matches pixel for pixel (same meshes, camera model and
pixel centres; ``tests/python/render/test_photo.py`` checks >= 99.9 % agreement).

Each view's lights, environment, tote / floor materials and exposure are drawn by the domain
randomisation of :mod:`mgn.render.lighting` from the stream (seed, view index) only, the
objects' materials, when ``render.randomize.object_appearance`` is on, from the stream (seed,
view index, object id), and the light at the camera (``render.randomize.camera_light``) from a
stream (seed, view index) of its own, so a view looks the same whatever the number of threads
or workers and whichever other views are rendered.

Units: metres, radiance in the tracer's units (a white Lambertian surface under irradiance E
shows E / pi); poses (4, 4) float64 ``X_AB``.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn.geometry import Mesh
from mgn.render.denoiser import denoise, denoiser_available
from mgn.render.lighting import (
    ViewLighting,
    draw_lighting,
    draw_object_materials,
    with_camera_light,
)
from mgn.render.materials import (
    OBJECT_TEXTURE_TILE,
    TEXTURE_TILE,
    box_uv_mesh,
    pbr_default,
    pbr_material,
)
from mgn.render.path import FilmOptions, PathScene, PathTraceOptions, develop
from mgn.render.settings import RenderSettings
from mgn.scene.cameras import CameraView

__all__ = ["PhotoRenderer"]


_WARNED_NO_DENOISER = False


class PhotoRenderer:
    """Path-traced photographs of one scene: the geometry is built once, each view draws its
    lighting and materials from (seed, view) and is traced, denoised and developed.

    Args:
        objects: (mesh, X_WO, instance id >= 1) per object.
        tote: the tote mesh or None (instance id 0), placed at ``X_W_tote``.
        floor: (floor mesh, X_W_floor) or None (instance id 0).
        settings: the engine settings (engine must be ``path``).
        tote_color: linear RGB of the tote when materials are not randomised.
        randomize: the scene's randomisation master switch (``camera.randomize``).
        seed: scene seed of the randomisation, the sampler and the sensor noise.
        num_threads: tracer and denoiser threads (0 = all cores); images do not depend on it.
    """

    def __init__(
        self,
        objects: Sequence[tuple[Mesh, npt.ArrayLike, int]],
        tote: Mesh | None,
        X_W_tote: npt.ArrayLike,
        floor: tuple[Mesh, npt.ArrayLike] | None,
        settings: RenderSettings,
        *,
        tote_color: Sequence[float] = (0.2, 0.35, 0.6),
        randomize: bool = True,
        seed: int = 0,
        num_threads: int = 0,
    ) -> None:
        global _WARNED_NO_DENOISER  # noqa: PLW0603 -- warn once per process
        self.settings = settings
        self.randomize = randomize
        self.seed = int(seed)
        self.num_threads = int(num_threads)
        self._X_tote = np.asarray(X_W_tote, np.float64)
        self._tote_color = tuple(float(c) for c in tote_color[:3])
        self.denoised = settings.denoise and denoiser_available()
        if settings.denoise and not self.denoised and not _WARNED_NO_DENOISER:
            _WARNED_NO_DENOISER = True
            warnings.warn(
                "render.denoise: the 'pyoidn' package (Intel Open Image Denoise) is not "
                "installed; tracing render.spp_without_denoiser = "
                f"{settings.spp_without_denoiser} samples per pixel instead "
                "(pip install 'mgn[render]' to denoise)",
                RuntimeWarning,
                stacklevel=2,
            )
        self.spp = settings.spp if self.denoised else settings.spp_without_denoiser
        # Object geometry and materials (fixed, or drawn per view with the object appearance
        # part; a mesh without uvs then gets box-projected ones for the procedural textures);
        # tote and floor materials are per view.
        self._appearance = randomize and settings.randomize.object_appearance
        meshes: list[Mesh] = []
        poses: list[npt.NDArray[np.float64]] = []
        ids: list[int] = []
        mats: list[list[Any]] = []
        cache: dict[int, list[Any]] = {}
        uv_meshes: dict[int, Mesh] = {}
        for mesh, X_WO, inst in objects:
            if id(mesh) not in cache:
                cache[id(mesh)] = [pbr_material(m) for m in mesh.materials] or [pbr_default()]
                uvs = mesh.uvs
                has_uvs = uvs is not None and len(np.asarray(uvs)) == mesh.num_vertices
                uv_meshes[id(mesh)] = (
                    mesh
                    if has_uvs or not self._appearance
                    else box_uv_mesh(mesh, OBJECT_TEXTURE_TILE, mesh.name, keep_face_materials=True)
                )
            meshes.append(uv_meshes[id(mesh)])
            poses.append(np.asarray(X_WO, np.float64))
            ids.append(int(inst))
            mats.append(cache[id(mesh)])
        self._n_objects = len(meshes)
        if tote is not None:
            meshes.append(box_uv_mesh(tote, TEXTURE_TILE, "tote"))
            poses.append(self._X_tote)
            ids.append(0)
            mats.append([None] * max(1, len(tote.materials)))
        if floor is not None:
            meshes.append(box_uv_mesh(floor[0], TEXTURE_TILE * 2, "floor"))
            poses.append(np.asarray(floor[1], np.float64))
            ids.append(0)
            mats.append([None] * max(1, len(floor[0].materials)))
        self._meshes, self._poses, self._ids, self._mats = meshes, poses, ids, mats
        self._has_tote, self._has_floor = tote is not None, floor is not None
        self._scene: Any = None
        self._scene_materials: Any = None
        #: Wall seconds of the last :meth:`render`: ``trace``, ``denoise``, ``develop``.
        self.last_seconds: dict[str, float] = {}

    def describe(self) -> dict[str, Any]:
        """The engine record of the images this renderer makes (see RenderSettings.describe)."""
        return self.settings.describe(self.denoised)

    def lighting(self, view_index: int) -> ViewLighting:
        return draw_lighting(
            self.settings,
            self.seed,
            view_index,
            target_W=self._X_tote[:3, 3],
            tote_color=self._tote_color,
            randomize=self.randomize,
        )

    def object_materials(self, view_index: int) -> list[list[Any]]:
        """The objects' materials in view ``view_index`` (per object, one per material slot):
        fixed, or drawn by :func:`mgn.render.lighting.draw_object_materials`."""
        mats = [list(m) for m in self._mats[: self._n_objects]]
        if not self._appearance:
            return mats
        return [
            list(draw_object_materials(self.settings, self.seed, view_index, inst, m))
            for inst, m in zip(self._ids[: self._n_objects], mats, strict=True)
        ]

    def _scene_for(self, lit: ViewLighting, view_index: int = 0) -> Any:
        key = (
            lit.tote,
            lit.floor,
            id(lit.tote.base_color_texture),
            id(lit.floor.base_color_texture),
        )
        if self._appearance or self._scene is None or self._scene_materials != key:
            mats = self.object_materials(view_index) + [
                list(m) for m in self._mats[self._n_objects :]
            ]
            k = self._n_objects
            if self._has_tote:
                mats[k] = [lit.tote] * len(mats[k])
                k += 1
            if self._has_floor:
                mats[k] = [lit.floor] * len(mats[k])
            self._scene = PathScene(
                self._meshes,
                np.stack(self._poses) if self._poses else np.zeros((0, 4, 4)),
                self._ids,
                mats,
                lit.lights,
                lit.environment,
            )
            self._scene_materials = None if self._appearance else key
            return self._scene
        return self._scene.with_lighting(lit.lights, lit.environment)

    def render(
        self, view: CameraView, view_index: int, labels: bool = False
    ) -> tuple[npt.NDArray[np.uint8], Any]:
        """(H, W, 3) uint8 sRGB photograph of one view and the tracer output (radiance,
        albedo, normal; depth and instance ids only with ``labels``, else 0: the dataset's
        labels come from the ray-cast label pass, and skipping the tracer's own label rays
        saves ~1.4 % of a view's tracing)."""

        s = self.settings
        t0 = time.perf_counter()
        lit = self.lighting(view_index)
        lit = with_camera_light(
            lit,
            s,
            self.seed,
            view_index,
            view.X_WC,
            target_W=self._X_tote[:3, 3],
            randomize=self.randomize,
        )
        scene = self._scene_for(lit, view_index)
        out = scene.render(
            view,
            PathTraceOptions(
                spp=self.spp,
                max_bounces=s.max_bounces,
                seed=self.seed & (2**63 - 1),
                view_index=int(view_index),
                num_threads=self.num_threads,
                aperture_radius=s.aperture_radius,
                clamp=s.clamp,
                adaptive_samples=s.adaptive_samples,
                adaptive_max=s.adaptive_max,
                labels=labels,
            ),
        )
        radiance = out.radiance
        t1 = time.perf_counter()
        if self.denoised:
            radiance = denoise(
                radiance,
                out.albedo,
                out.normal,
                s.denoise_quality,
                num_threads=self.num_threads,
                guides=s.denoise_guides,
                resolution=s.denoise_resolution,
            )
        t2 = time.perf_counter()
        rgb = develop(
            radiance,
            FilmOptions(
                exposure=lit.exposure,
                tone=s.tone,
                shot_noise=s.shot_noise,
                read_noise=s.read_noise,
                seed=self.seed & (2**63 - 1),
                view_index=int(view_index),
                num_threads=self.num_threads,
            ),
        )
        self.last_seconds = {
            "trace": t1 - t0,
            "denoise": t2 - t1,
            "develop": time.perf_counter() - t2,
        }
        return rgb, out
