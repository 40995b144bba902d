"""Pinhole cameras and camera rigs (docs/models.md §6; typed façade over the C++ core).

Camera frame C is OpenCV: x right, y down, z forward. Pixel (u, v) has its centre at image
coordinates (u + 0.5, v + 0.5), the same model as :func:`mgn.camera_rays`. Poses ``X_WC`` are
(4, 4) float64 camera poses in the world. Lengths in metres, angles in radians, intrinsics in px.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError, InvalidTypeError
from mgn.geometry.raytrace import camera_rays

__all__ = [
    "CameraView",
    "Intrinsics",
    "MgnRigParams",
    "hemisphere_rig",
    "look_at",
    "mgn_rig",
    "mgn_rig_from_params",
    "mgn_views",
]

#: Real-sensor presets: (width, height, fx = fy px), principal point at the image centre.
#: Derived from the manufacturers' published resolution and field of view (docs/cameras.md):
#: Zivid 2+ M130: 2448 x 2048, 0.32 mm per pixel at 1300 mm -> f = 1300 / 0.32 px;
#: Photoneo PhoXi 3D Scanner M: 2064 x 1544 (Photoneo wiki and ROS driver), 47.5 deg horizontal
#: projection angle -> f = 1032 / tan(23.75 deg) (36.4 deg vertically; published 36.0 +- 2 deg);
#: Intel RealSense D435 depth: 1280 x 720, 87 deg horizontal field -> f = 640 / tan(43.5 deg).
SENSOR_PRESETS: dict[str, tuple[int, int, float]] = {
    "zivid2_plus_m130": (2448, 2048, 1300.0 / 0.32),
    "photoneo_phoxi_m": (2064, 1544, 1032.0 / math.tan(math.radians(23.75))),
    "realsense_d435": (1280, 720, 640.0 / math.tan(math.radians(43.5))),
}

#: MetaGraspNet synthetic camera: focal length and horizontal aperture, mm.
MGN_FOCAL_LENGTH_MM = 35.0
MGN_APERTURE_MM = 20.955
#: ``clipping_range`` of ``{v}_camera_params.json``, [near, far] in cm: MetaGraspNet's value
#: (1 cm to 10 km). mgn's renderers clip nothing of a scene (the raster engine fits its clip
#: planes to the scene's depth range, the ray tracers start at the camera centre), so every
#: surface in this range is drawn.
MGN_CLIPPING_RANGE_CM: tuple[float, float] = (1.0, 1.0e6)


@dataclass(frozen=True)
class Intrinsics:
    """Camera intrinsics in pixels: a pinhole, optionally with OpenCV lens distortion.
    Validated on construction.

    Attributes:
        width, height: image size, px (> 0).
        fx, fy: focal lengths, px (> 0).
        cx, cy: principal point, px (continuous image coordinates; the image centre is W/2, H/2;
            OpenCV's camera matrix has cx - 0.5, cy - 0.5: :attr:`K_opencv`).
        distortion: OpenCV coefficients k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[, tau_x,
            tau_y]]]] (4, 5, 8, 12 or 14 numbers; the model is in :mod:`mgn.scene.lens`); empty
            for a pinhole. All zeros is stored as empty (the same camera). Images of a camera
            with distortion are rendered as a pinhole and resampled
            (:func:`mgn.scene.lens.lens_for`).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InvalidArgumentError(f"Intrinsics.{name} must be an integer, got {value!r}")
            object.__setattr__(self, name, int(value))
        for name in ("fx", "fy", "cx", "cy"):
            object.__setattr__(self, name, float(getattr(self, name)))
        try:
            dist = tuple(float(c) for c in self.distortion)
        except (TypeError, ValueError) as e:
            raise InvalidArgumentError(
                f"Intrinsics.distortion must be a list of numbers, got {self.distortion!r}"
            ) from e
        if len(dist) not in (0, 4, 5, 8, 12, 14) or not all(math.isfinite(c) for c in dist):
            raise InvalidArgumentError(
                "Intrinsics.distortion must be 4, 5, 8, 12 or 14 finite OpenCV coefficients "
                f"(k1, k2, p1, p2, k3, ...), got {list(dist)}"
            )
        object.__setattr__(self, "distortion", dist if any(c != 0.0 for c in dist) else ())
        self.to_core()  # validates (InvalidArgumentError names the bad value)

    @classmethod
    def mgn_synthetic(cls) -> Intrinsics:
        """1200 x 1200, 35 mm focal length on a 20.955 mm aperture (fx = fy ~= 2004.3 px)."""
        return cls._from_core(_core.render.Intrinsics.mgn_synthetic())

    @classmethod
    def zivid_two_like(cls) -> Intrinsics:
        """1944 x 1200, fx = fy = 1780 px: an industrial camera like a Zivid Two (approximate)."""
        return cls._from_core(_core.render.Intrinsics.zivid_two_like())

    @classmethod
    def preset(cls, name: str) -> Intrinsics:
        """A named preset: ``mgn_synthetic``, ``zivid_two_like`` or a real sensor of
        :data:`SENSOR_PRESETS` (``zivid2_plus_m130``, ``photoneo_phoxi_m``, ``realsense_d435``).

        Raises:
            InvalidArgumentError: an unknown name (the message lists the presets).
        """
        if name == "mgn_synthetic":
            return cls.mgn_synthetic()
        if name == "zivid_two_like":
            return cls.zivid_two_like()
        if name in SENSOR_PRESETS:
            w, h, f = SENSOR_PRESETS[name]
            return cls(w, h, f, f, w / 2.0, h / 2.0)

        names = ["mgn_synthetic", "zivid_two_like", *SENSOR_PRESETS]
        raise InvalidArgumentError(f"unknown intrinsics preset {name!r}; presets: {names}")

    @classmethod
    def _from_core(cls, k: _core.render.Intrinsics) -> Intrinsics:
        return cls(k.width, k.height, k.fx, k.fy, k.cx, k.cy)

    def to_core(self) -> _core.render.Intrinsics:
        """The C++ pinhole intrinsics (the distortion is not part of them)."""
        return _core.render.Intrinsics(self.width, self.height, self.fx, self.fy, self.cx, self.cy)

    @property
    def K(self) -> npt.NDArray[np.float64]:  # the usual symbol
        """(3, 3) matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def K_opencv(self) -> npt.NDArray[np.float64]:  # the usual symbol
        """(3, 3) camera matrix in OpenCV's pixel convention (pixel centres on integers):
        ``K`` with cx - 0.5, cy - 0.5. With :attr:`distortion` it is what ``cv2.projectPoints``,
        ``cv2.undistort`` and ``cv2.initUndistortRectifyMap`` take for mgn's images."""
        return np.array(
            [[self.fx, 0.0, self.cx - 0.5], [0.0, self.fy, self.cy - 0.5], [0.0, 0.0, 1.0]]
        )

    def pinhole(self) -> Intrinsics:
        """The same intrinsics without distortion (the rectified camera)."""
        return Intrinsics(self.width, self.height, self.fx, self.fy, self.cx, self.cy)

    def scaled(self, factor: float) -> Intrinsics:
        """The same field of view at ``factor`` times the resolution (rounded). The distortion
        coefficients act on normalised coordinates and are kept."""
        w, h = round(self.width * factor), round(self.height * factor)
        return Intrinsics(
            w,
            h,
            self.fx * w / self.width,
            self.fy * h / self.height,
            self.cx * w / self.width,
            self.cy * h / self.height,
            self.distortion,
        )

    def camera_params(
        self, clipping_range_cm: tuple[float, float] = MGN_CLIPPING_RANGE_CM
    ) -> dict[str, Any]:
        """``{v}_camera_params.json`` content (docs/format.md): px values plus MetaGraspNet's keys
        in MetaGraspNet's units: ``focal_length`` and the apertures in mm (the apertures of a
        35 mm lens giving these focal lengths), ``horizontal_fov`` / ``vertical_fov`` in
        radians (2 atan(W / 2 fx), 2 atan(H / 2 fy)) and ``clipping_range`` [near, far] in cm
        (default :data:`MGN_CLIPPING_RANGE_CM`). A camera with distortion adds
        ``distortion_model: "opencv"`` and ``distortion`` (the coefficients; the images are
        distorted by them, docs/cameras.md).
        """
        hfov = 2.0 * math.atan(0.5 * self.width / self.fx)
        vfov = 2.0 * math.atan(0.5 * self.height / self.fy)
        h_ap = MGN_FOCAL_LENGTH_MM * self.width / self.fx
        v_ap = MGN_FOCAL_LENGTH_MM * self.height / self.fy
        return {
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "width": self.width,
            "height": self.height,
            "focal_length": MGN_FOCAL_LENGTH_MM,
            "horizontal_aperture": h_ap,
            "vertical_aperture": v_ap,
            "horizontal_fov": hfov,
            "vertical_fov": vfov,
            "resolution": {"height": self.height, "width": self.width},
            "clipping_range": [float(x) for x in clipping_range_cm],
        } | (
            {"distortion_model": "opencv", "distortion": list(self.distortion)}
            if self.distortion
            else {}
        )


def _pose(X: npt.ArrayLike, name: str) -> npt.NDArray[np.float64]:
    a = np.array(X, dtype=np.float64)
    if a.shape != (4, 4):
        raise InvalidArgumentError(f"{name} must be a (4, 4) pose, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidArgumentError(f"{name} has non-finite entries")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class CameraView:
    """A camera: intrinsics and the (4, 4) pose ``X_WC`` of its OpenCV frame in the world."""

    K: Intrinsics
    X_WC: npt.NDArray[np.float64] = field(repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.K, Intrinsics):
            raise InvalidTypeError(
                f"CameraView.K must be an Intrinsics, got {type(self.K).__name__}"
            )
        object.__setattr__(self, "X_WC", _pose(self.X_WC, "CameraView.X_WC"))

    @property
    def position(self) -> npt.NDArray[np.float64]:
        """Camera centre in the world, m."""
        out: npt.NDArray[np.float64] = self.X_WC[:3, 3].copy()
        return out

    def rays(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """Rays through the pixel centres (see :func:`mgn.camera_rays`)."""

        return camera_rays(self.K.K, self.K.width, self.K.height, self.X_WC)


@dataclass(frozen=True)
class MgnRigParams:
    """Random parameters of a MetaGraspNet rig: radii (m), tilts from vertical and azimuth span
    (rad)."""

    R_start: float
    R_end: float
    theta_start: float
    theta_end: float
    phi_end: float


def _vec3(x: npt.ArrayLike, name: str) -> npt.NDArray[np.float64]:
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,):
        raise InvalidArgumentError(f"{name} must be 3 numbers, got shape {a.shape}")
    return a


def mgn_rig(
    seed: int, target: npt.ArrayLike = (0.0, 0.0, 0.0)
) -> tuple[npt.NDArray[np.float64], MgnRigParams]:
    """The 37 MetaGraspNet camera poses around ``target`` and the drawn parameters.

    View 0 looks straight down from R_start; view v = 1 + 12 i_R + 4 i_theta + i_phi sits at
    radius R_start + i_R (R_end - R_start)/2, tilt theta_start + i_theta (theta_end -
    theta_start)/2 and azimuth i_phi phi_end/4, looking at the target (docs/models.md §6).

    Returns:
        ((37, 4, 4) float64 poses X_WC, MgnRigParams).
    """
    poses, params = _core.render.mgn_rig(int(seed), _vec3(target, "target"))
    return poses, MgnRigParams(
        params.R_start, params.R_end, params.theta_start, params.theta_end, params.phi_end
    )


def mgn_rig_from_params(
    params: MgnRigParams, target: npt.ArrayLike = (0.0, 0.0, 0.0)
) -> npt.NDArray[np.float64]:
    """(37, 4, 4) poses of given rig parameters."""
    return _core.render.mgn_rig_from_params(
        params.R_start,
        params.R_end,
        params.theta_start,
        params.theta_end,
        params.phi_end,
        _vec3(target, "target"),
    )


def hemisphere_rig(
    radii: npt.ArrayLike,
    tilts: npt.ArrayLike,
    azimuths: npt.ArrayLike,
    target: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> npt.NDArray[np.float64]:
    """(N, 4, 4) poses on a hemisphere: every (radius m, tilt from vertical rad, azimuth rad),
    radius-major, then tilt, then azimuth."""
    return _core.render.hemisphere_rig(
        [float(r) for r in np.atleast_1d(radii)],
        [float(t) for t in np.atleast_1d(tilts)],
        [float(a) for a in np.atleast_1d(azimuths)],
        _vec3(target, "target"),
    )


def look_at(
    eye: npt.ArrayLike, target: npt.ArrayLike, up: npt.ArrayLike = (0.0, 0.0, 1.0)
) -> npt.NDArray[np.float64]:
    """(4, 4) camera pose at ``eye`` looking at ``target``, image up as close to ``up`` as
    possible."""
    return _core.render.look_at(_vec3(eye, "eye"), _vec3(target, "target"), _vec3(up, "up"))


def mgn_views(
    seed: int, target: npt.ArrayLike = (0.0, 0.0, 0.0), K: Intrinsics | None = None
) -> list[CameraView]:
    """The 37 MetaGraspNet views as :class:`CameraView` (default intrinsics: MGN synthetic)."""
    intr = Intrinsics.mgn_synthetic() if K is None else K
    poses, _ = mgn_rig(seed, target)
    return [CameraView(intr, X) for X in poses]
