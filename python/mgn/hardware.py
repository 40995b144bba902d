"""The default end effectors: a Franka-hand-like parallel-jaw gripper and a bellows suction cup.

Values are the MetaGraspNet defaults (docs/models.md §1 and §5), in SI units. Both are frozen
dataclasses that validate themselves and round-trip through YAML, so users describe their own
hardware in a small file::

    gripper = ParallelJawGripper.from_yaml("my_gripper.yaml")

Frames: the gripper's grasp frame has x = closing direction, z = approach direction and its
origin at the first finger contact; the flange sits ``flange_to_contact`` metres behind the grasp
centre along -z. The cup's z axis points from the cup into the surface (approach direction).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import yaml

from mgn.base.atomic import atomic_write_text
from mgn.base.yaml_file import read_yaml
from mgn.errors import InvalidArgumentError

T = TypeVar("T", bound="_YamlDataclass")


class _YamlDataclass:
    """Shared validation and YAML round-trip for the hardware dataclasses."""

    def _check_positive(self, *names: str) -> None:
        for name in names:
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise InvalidArgumentError(
                    f"{type(self).__name__}.{name}: expected a finite number > 0, got {value!r}"
                )

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of the fields (tuples become lists), suitable for YAML or JSON."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            out[f.name] = list(v) if isinstance(v, tuple) else v
        return out

    @classmethod
    def from_dict(cls: type[T], data: dict[str, Any]) -> T:
        """Build from a dict; unknown keys are an error naming the key and the valid ones."""
        if not isinstance(data, dict):
            raise InvalidArgumentError(
                f"{cls.__name__}: expected a mapping, got {type(data).__name__}"
            )
        names = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = sorted(set(data) - set(names))
        if unknown:
            raise InvalidArgumentError(
                f"{cls.__name__}: unknown key(s) {unknown}; valid keys are {sorted(names)}"
            )
        kwargs = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        return cls(**kwargs)

    def to_yaml(self, path: str | os.PathLike[str] | None = None) -> str:
        """YAML text of the fields; also written to ``path`` when given."""
        text: str = yaml.safe_dump(self.to_dict(), sort_keys=False)
        if path is not None:
            atomic_write_text(path, text)
        return text

    @classmethod
    def from_yaml(cls: type[T], path: str | os.PathLike[str]) -> T:
        """Read from a YAML file (keys as in :meth:`to_dict`; missing keys keep defaults)."""

        data = read_yaml(path, f"{cls.__name__} YAML")
        if data is not None and not isinstance(data, dict):
            raise InvalidArgumentError(
                f"{cls.__name__} YAML '{os.fspath(path)}': expected a mapping of keys to values, "
                f"got {type(data).__name__}"
            )
        try:
            return cls.from_dict(data or {})
        except (InvalidArgumentError, ValueError, TypeError) as e:
            raise InvalidArgumentError(f"{cls.__name__} YAML '{os.fspath(path)}': {e}") from e


@dataclass(frozen=True)
class ParallelJawGripper(_YamlDataclass):
    """A two-finger parallel-jaw gripper (defaults: Franka-hand-like, MetaGraspNet).

    Attributes:
        name: identifier recorded in dataset metadata.
        max_opening: largest finger separation, m.
        flange_to_tip: flange to fingertip along the approach axis, m.
        contact_from_tip: contact-pad centre measured back from the tip, m; the grasp centre is
            ``flange_to_tip - contact_from_tip`` from the flange.
        collision_margin: extra opening used for collision checks, m (opening = min(w + margin,
            max_opening)).
        finger_size: finger box (thickness along closing x, width along y, length along z), m.
        palm_size: palm box (x along closing, y, z), m, between the flange and the fingers;
            Franka-hand-like: long along the closing axis.
        friction: finger pad Coulomb friction coefficient.
        palm_mesh, finger_left_mesh, finger_right_mesh: a user gripper from mesh files (all three
            or none): closed meshes in the hand frame (origin at the flange, z = approach,
            x = closing), the fingers placed at opening 0; at an opening o the left finger moves
            by -o/2 and the right one by +o/2 along x. Relative paths in a YAML file are read
            relative to that file. finger_size and palm_size are then ignored.
        mesh_scale: multiplies the mesh coordinates (0.001 for files in millimetres).
    """

    name: str = "franka_like"
    max_opening: float = 0.080
    flange_to_tip: float = 0.1121
    contact_from_tip: float = 0.008
    collision_margin: float = 0.030
    finger_size: tuple[float, float, float] = (0.010, 0.020, 0.050)
    palm_size: tuple[float, float, float] = (0.200, 0.060, 0.060)
    friction: float = 1.0
    palm_mesh: str | None = None
    finger_left_mesh: str | None = None
    finger_right_mesh: str | None = None
    mesh_scale: float = 1.0

    def __post_init__(self) -> None:
        self._check_positive(
            "max_opening", "flange_to_tip", "contact_from_tip", "friction", "collision_margin"
        )
        self._check_positive("mesh_scale")
        meshes = [self.palm_mesh, self.finger_left_mesh, self.finger_right_mesh]
        if any(m is not None for m in meshes) and not all(isinstance(m, str) for m in meshes):
            raise InvalidArgumentError(
                "ParallelJawGripper: palm_mesh, finger_left_mesh and finger_right_mesh must all "
                f"be mesh file paths or all be None, got {meshes!r}"
            )
        for name in ("finger_size", "palm_size"):
            v = getattr(self, name)
            if len(v) != 3 or not all(isinstance(x, (int, float)) and x > 0 for x in v):
                raise InvalidArgumentError(
                    f"ParallelJawGripper.{name}: expected three sizes > 0 (m), got {v!r}"
                )
        if self.contact_from_tip >= self.flange_to_tip:
            raise InvalidArgumentError(
                "ParallelJawGripper: contact_from_tip must be < flange_to_tip, got "
                f"{self.contact_from_tip} >= {self.flange_to_tip}"
            )

    @classmethod
    def from_yaml(cls, path: str | os.PathLike[str]) -> ParallelJawGripper:
        """Read from a YAML file; relative mesh paths are taken relative to the file's folder."""
        g = super().from_yaml(path)
        base = Path(os.path.abspath(path)).parent
        fields = ("palm_mesh", "finger_left_mesh", "finger_right_mesh")
        resolved: dict[str, Any] = {
            f: os.path.join(base, getattr(g, f))  # noqa: PTH118 -- keeps the spelling of the path
            for f in fields
            if getattr(g, f) is not None and not Path(getattr(g, f)).is_absolute()
        }
        return dataclasses.replace(g, **resolved) if resolved else g

    @property
    def has_meshes(self) -> bool:
        """True for a user gripper defined by mesh files."""
        return self.palm_mesh is not None

    @property
    def flange_to_contact(self) -> float:
        """Distance from the flange to the grasp centre along the approach axis, m (104.1 mm)."""
        return self.flange_to_tip - self.contact_from_tip

    def collision_opening(self, width: float) -> float:
        """Finger opening used for collision checks of a grasp of contact width ``width`` (m)."""
        return min(width + self.collision_margin, self.max_opening)


@dataclass(frozen=True)
class SuctionCup(_YamlDataclass):
    """A vacuum suction cup for the spring-mass seal model (defaults: MetaGraspNet).

    Attributes:
        name: identifier recorded in dataset metadata.
        radius: contact-ring radius r, m.
        num_points: mass points N on the ring.
        youngs_modulus: E in MPa-like units as in the paper (scaled by 1e6 in the stiffness).
        pressure_difference: vacuum pressure difference, bar.
        compensable_height: largest height difference the lip absorbs (hill check), m.
        approach_height: start height of the projection above the contact, m.
        c1: fitted compression-spring constant (calibrated, see docs/models.md §4).
        c2: fitted ring-spring constant (calibrated); MetaGraspNet's convention: ring stiffness
            k = E·1e6·π·c2 / (N·L) with the rest length L in cm (see Cup::ring_stiffness).
        outer_radius: outer radius of the cup body for collision checks, m.
        body_height: height of the cup body (bellows) for collision checks, m.
        hole_rays: rays of the hole check spread over the contact disc (MetaGraspNet: 1000).
        bending_k: k of the cup's bending-torque limit tau_max = k * radius * pi * sqrt(2), N
            (> 0; 15.6 as in SuctionNet-1Billion: 0.485 N m for the 7 mm ring); used by the
            suction wrench score and the hold test (docs/models.md §3, §3a).
    """

    name: str = "bellows_14mm"
    radius: float = 0.007
    num_points: int = 128
    youngs_modulus: float = 0.02
    pressure_difference: float = 0.7
    compensable_height: float = 0.007
    approach_height: float = 0.030
    c1: float = 0.03768
    c2: float = 0.06241
    outer_radius: float = 0.010
    body_height: float = 0.030
    hole_rays: int = 1000
    bending_k: float = 15.6

    def __post_init__(self) -> None:
        if not isinstance(self.hole_rays, int) or self.hole_rays < 1:
            raise InvalidArgumentError(
                f"SuctionCup.hole_rays: expected an integer >= 1, got {self.hole_rays!r}"
            )
        self._check_positive(
            "radius",
            "youngs_modulus",
            "pressure_difference",
            "compensable_height",
            "approach_height",
            "c1",
            "c2",
            "outer_radius",
            "body_height",
            "bending_k",
        )
        if not isinstance(self.num_points, int) or self.num_points < 6:
            raise InvalidArgumentError(
                f"SuctionCup.num_points: expected an integer >= 6, got {self.num_points!r}"
            )
        if self.outer_radius < self.radius:
            raise InvalidArgumentError(
                f"SuctionCup.outer_radius ({self.outer_radius}) must be >= radius ({self.radius})"
            )


def default_gripper() -> ParallelJawGripper:
    """The MetaGraspNet default parallel-jaw gripper."""
    return ParallelJawGripper()


def default_cup() -> SuctionCup:
    """The MetaGraspNet default suction cup."""
    return SuctionCup()


#: The one name of each grasp kind, and the aliases accepted for it (MetaGraspNet folder names).
GRASP_KINDS: dict[str, tuple[str, ...]] = {
    "suction": ("suction", "suctioncup", "suction_cup", "cup"),
    "paralleljaw": ("paralleljaw", "parallel_jaw", "pj", "gripper"),
}


def normalize_grasp_kind(kind: str) -> str:
    """``"suction"`` or ``"paralleljaw"`` for any accepted spelling (e.g. the MetaGraspNet folder
    names ``suctioncup`` and ``paralleljaw``, or ``pj``).

    Raises:
        InvalidArgumentError: an unknown kind (the message lists the accepted names).
    """
    k = str(kind).strip().lower().replace("-", "_")
    for name, aliases in GRASP_KINDS.items():
        if k in aliases:
            return name
    accepted = ", ".join(a for v in GRASP_KINDS.values() for a in v)
    raise InvalidArgumentError(
        f"unknown grasp kind {kind!r}; expected suction or paralleljaw (also accepted: {accepted})"
    )


#: The MetaGraspNet folder name of each grasp kind (``grasps/<folder>/``, ``*_grasps/<folder>``).
MGN_FOLDER = {"suction": "suctioncup", "paralleljaw": "paralleljaw"}
