"""The entries of the built-in catalogue: one builder function per object class, registered in
category-id order with its description, material, density, friction and declared tags.

A builder returns a :class:`mgn.objects.blocks.Built` (mesh and named keypoints in its own
frame, metres; a texture for printed objects); :mod:`mgn.objects.library` builds, re-centres and
caches the finished :class:`mgn.objects.ObjectSpec` s. The builders are deterministic (fixed
parameters, fixed random seeds). Category ids are 1..N in definition order and never change
meaning: new builders are only ever appended at the end of this module.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mgn.errors import InvalidArgumentError

from . import textures as tx
from .blocks import (
    MM,
    SEG,
    Built,
    arc_fractions,
    cylinder,
    ellipse_arc,
    from_mm,
    keypoints_mm,
    polyline,
    printed_box,
    smooth_noise,
)
from .materials import BLACK, CARDBOARD_PRINT, CLEAR_GLASS, PRINTED_METAL
from .materials import linear_rgba as lin  # short names keep each entry's material on one line
from .materials import make_material as mat
from .shapes import (
    difference,
    ensure_min_faces,
    extrude,
    grid_box,
    loft,
    revolve,
    rotation_matrix,
    rounded_box,
    superellipsoid,
    sweep_circle,
    sweep_hollow,
    union,
)
from .spec import MaterialSpec

__all__ = ["Entry", "catalogue_entries"]


@dataclass(frozen=True)
class Entry:
    """Catalogue entry: everything about an object class except its geometry."""

    name: str
    description: str
    build: Callable[[], Built]
    material: MaterialSpec
    density: float
    friction: float
    tags: frozenset[str]


#: Registered entries in category-id order (the order of the builder definitions below).
_CATALOGUE: list[Entry] = []


def catalogue_entries() -> tuple[Entry, ...]:
    """The registered entries in category-id order (entry ``i`` has category id ``i + 1``)."""
    return tuple(_CATALOGUE)


def _register(
    name: str,
    description: str,
    *,
    material: MaterialSpec,
    density: float,
    friction: float,
    tags: tuple[str, ...] = (),
) -> Callable[[Callable[[], Built]], Callable[[], Built]]:
    """Decorator adding a builder to the catalogue; ids follow the definition order.

    Only ever append new builders at the end of this module: ids must keep their meaning.
    ``density`` in kg/m^3 (effective), ``friction`` the Coulomb coefficient.
    """

    def add(build: Callable[[], Built]) -> Callable[[], Built]:
        if any(e.name == name for e in _CATALOGUE):
            raise InvalidArgumentError(f"duplicate object name {name!r}")
        _CATALOGUE.append(
            Entry(name, description, build, material, density, friction, frozenset(tags))
        )
        return build

    return add


# ----------------------------------------------------------------------------------------------
# Builders (dimensions in millimetres unless stated)
#
# Profiles of bodies of revolution are (r, z) point tables in millimetres; they are kept as
# compact tables (formatter off) so that they read like drawings.
# ----------------------------------------------------------------------------------------------


def _pal(*colors: tuple[int, int, int]) -> tx.Palette:
    return tx.Palette(*colors)


@_register(
    "box_cereal",
    "Printed cereal carton, 65 x 190 x 240 mm.",
    material=CARDBOARD_PRINT, density=150.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_cereal() -> Built:
    pal = _pal((236, 180, 40), (200, 60, 40), (40, 30, 90), (250, 245, 230))
    return printed_box((65, 190, 240), pal, "CRUNCH", 11)


@_register(
    "box_shoe",
    "Printed shoe-box-like carton, 240 x 150 x 90 mm.",
    material=CARDBOARD_PRINT, density=120.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_shoe() -> Built:
    pal = _pal((190, 150, 110), (120, 85, 60), (20, 20, 20), (235, 225, 210))
    return printed_box((240, 150, 90), pal, "STRIDE", 12)


@_register(
    "box_tea",
    "Small printed tea box, 125 x 75 x 65 mm.",
    material=CARDBOARD_PRINT, density=250.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_tea() -> Built:
    pal = _pal((40, 110, 70), (200, 170, 80), (245, 240, 220), (120, 40, 40))
    return printed_box((125, 75, 65), pal, "TEA", 13)


@_register(
    "box_cube",
    "Printed gift cube, 60 mm.",
    material=CARDBOARD_PRINT, density=300.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_cube() -> Built:
    pal = _pal((90, 160, 220), (240, 240, 240), (200, 40, 60), (250, 210, 60))
    return printed_box((60, 60, 60), pal, "GIFT", 14)


@_register(
    "box_medicine",
    "Flat printed medicine box, 100 x 45 x 20 mm.",
    material=CARDBOARD_PRINT, density=200.0, friction=0.5, tags=("box",),
)  # fmt: skip
def _box_medicine() -> Built:
    pal = _pal((245, 245, 245), (30, 120, 200), (20, 40, 90), (230, 60, 60))
    return printed_box((100, 45, 20), pal, "MED 20", 15)


@_register(
    "can_soda",
    "Soda can with printed label, 66 mm diameter, 123 mm tall.",
    material=PRINTED_METAL, density=880.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _can_soda() -> Built:
    # fmt: off
    prof = from_mm([
        (0, 9), (12, 8.3), (20, 5.5), (24.5, 1.5), (25.5, 0), (27.5, 0), (31, 3), (33, 9),
        *[(33, z) for z in np.linspace(15, 102, 12)],
        (33, 108), (30.5, 115), (27, 119), (27.3, 121.8), (26.9, 122.6), (26.1, 122.6),
        (25.7, 121.8), (25.3, 118.8), (12, 118.8), (0, 118.8),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = arc_fractions(prof)  # the label covers the straight side: profile points 7..20
    pal = _pal((200, 20, 30), (240, 240, 240), (250, 250, 250), (30, 30, 30))
    tex = tx.wrap_label(pal, "FIZZ", 21, (v[7], v[20]))
    kp = keypoints_mm(
        top_centre=(0, 0, 118.8), bottom_centre=(0, 0, 0), side_front=(33, 0, 60),
        side_back=(-33, 0, 60), rim=(0, 26.5, 122.6),
    )  # fmt: skip
    return Built(mesh, kp, tex)


@_register(
    "can_food",
    "Ribbed food tin with paper label, 77 mm diameter, 110 mm tall.",
    material=PRINTED_METAL, density=930.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _can_food() -> Built:
    zr = np.arange(20, 92.1, 1.0)
    ribs = np.stack([37.5 - 0.35 * (1.0 - np.cos(2 * np.pi * (zr - 20) / 8.0)), zr], axis=1)
    # fmt: off
    prof = from_mm([
        (0, 2), (34, 2), (36, 0.8), (37.5, 0), (38.6, 1.2), (38.6, 3.2), (37.5, 4.5), (37.5, 12),
        *ribs,
        (37.5, 100), (37.5, 105.5), (38.6, 106.8), (38.6, 108.8), (37.5, 110), (36, 109.2),
        (34, 108), (0, 108),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = arc_fractions(prof)  # the label covers the side between the two beads
    pal = _pal((245, 235, 200), (40, 120, 60), (150, 30, 20), (230, 120, 30))
    tex = tx.wrap_label(pal, "BEANS", 22, (v[6], v[-8]))
    kp = keypoints_mm(
        top_centre=(0, 0, 108), bottom_centre=(0, 0, 2), side_front=(37.5, 0, 56),
        side_back=(-37.5, 0, 56), rim=(0, 38.6, 108.8),
    )  # fmt: skip
    return Built(mesh, kp, tex)


@_register(
    "spray_can",
    "Aerosol spray can with cap, 53 mm diameter, 192 mm tall.",
    material=PRINTED_METAL, density=750.0, friction=0.35, tags=("cylindrical",),
)  # fmt: skip
def _spray_can() -> Built:
    # fmt: off
    prof = from_mm([
        (0, 6), (15, 4.8), (22, 2), (24.5, 0), (26.5, 1.5),
        *[(26.5, z) for z in np.linspace(10, 140, 14)],
        (26.5, 148), (26, 150.5), (24.5, 152), (25.2, 153), (25.2, 170), (25.2, 185), (24, 189),
        (20, 191), (10, 191.5), (0, 191.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG, with_uv=True)
    v = arc_fractions(prof)
    pal = _pal((30, 60, 160), (250, 200, 30), (250, 250, 250), (230, 60, 40))
    tex = tx.wrap_label(pal, "SPRAY", 23, (v[4], v[20]), metal=(235, 235, 235))
    kp = keypoints_mm(
        cap_top=(0, 0, 191.5), bottom_centre=(0, 0, 6), side_front=(26.5, 0, 75),
        side_back=(-26.5, 0, 75), shoulder=(0, 25.2, 160),
    )  # fmt: skip
    return Built(mesh, kp, tex)


@_register(
    "bottle_water",
    "Opaque plastic water bottle with neck and screw cap, 208 mm tall.",
    material=mat("blue_plastic", lin("#5fa8d3"), 0.4, 40.0, roughness=0.3),
    density=850.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _bottle_water() -> Built:
    zb = np.arange(8, 140.1, 5.0)
    groove = (zb >= 40) & (zb <= 120) & ((zb // 10) % 2 == 1)
    body = np.stack([32.8 - 0.9 * groove, zb], axis=1)
    shoulder = ellipse_arc((13, 140), (19.8, 38), 0, np.pi / 2, 12)[1:]
    # fmt: off
    prof = from_mm([
        (0, 2.5), (15, 1.8), (26, 0.6), (30.5, 0), (32.3, 1.5), (32.8, 4),
        *body, *shoulder,
        (13, 184), (17, 185), (17, 187), (15.5, 188), (15.5, 198), (15.5, 206), (14.5, 208),
        (7, 208), (0, 208),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        cap_top=(0, 0, 208), bottom_centre=(0, 0, 2.5), side_front=(32.8, 0, 90),
        side_back=(-32.8, 0, 90), neck=(0, 13, 181),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "bottle_detergent",
    "Detergent bottle, rounded-rectangle section 95 x 60 mm, with cap.",
    material=mat("orange_plastic", lin("#f08a24"), 0.3, 30.0, roughness=0.4),
    density=700.0, friction=0.45,
)  # fmt: skip
def _bottle_detergent() -> Built:
    body = rounded_box((0.095, 0.06, 0.17), 0.014, max_edge=0.012).translated((0.0, 0.0, 0.085))
    neck = cylinder(15 * MM, 160 * MM, 186 * MM, 40)
    cap = revolve(from_mm([(0, 180), (19, 180), (19, 200), (17.5, 202), (0, 202)]), 40)
    mesh = union(body, neck, cap)
    kp = keypoints_mm(
        cap_top=(0, 0, 202), bottom_centre=(0, 0, 0), front_centre=(0, -30, 85),
        back_centre=(0, 30, 85), side=(47.5, 0, 85), shoulder=(30, 0, 170),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "jar",
    "Jam jar with a metal lid, 82 mm diameter, 115 mm tall.",
    material=mat("red_jam_glass", lin("#8c1c24"), 0.6, 80.0, roughness=0.06),
    density=1300.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _jar() -> Built:
    # fmt: off
    prof = from_mm([
        (0, 1.5), (30, 0.5), (36, 1.5), (39, 4), (40, 10),
        *[(40, z) for z in np.linspace(18, 74, 8)],
        (40, 80), (38.5, 86), (36, 90), (34, 93), (34, 96), (41, 96), (41, 106), (41, 113),
        (39.5, 115), (20, 115), (0, 115),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        lid_top=(0, 0, 115), bottom_centre=(0, 0, 1.5), side_front=(40, 0, 45),
        side_back=(-40, 0, 45), lid_edge=(0, 41, 105),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "mug",
    "Ceramic mug with a handle, 82 mm diameter, 96 mm tall.",
    material=mat("white_ceramic", lin("#ece8df"), 0.5, 60.0, roughness=0.12),
    density=2300.0, friction=0.6, tags=("nonconvex",),
)  # fmt: skip
def _mug(path_steps: int = 36, handle_segments: int = 16) -> Built:
    # The defaults of path_steps / handle_segments were chosen so that the union leaves no
    # sliver triangles (every altitude > 10 micrometres).
    # fmt: off
    prof = from_mm([
        (0, 0), (36, 0), (39.5, 1.2), (41, 4),
        *[(41, z) for z in np.linspace(12, 86, 8)],
        (41, 94), (40, 95.5), (38.5, 95.5), (37.5, 94.5), (37, 93),
        *[(37, z) for z in np.linspace(84, 18, 7)],
        (37, 11), (35.5, 8), (32, 7), (16, 7), (0, 7),
    ])
    # fmt: on
    cup = revolve(prof, SEG)
    # C-shaped handle in the x-z plane; both ends stop inside the 4 mm wall (x = 39 mm)
    t = np.linspace(0.0, np.pi, path_steps)
    path = np.stack([39 + 22 * np.sin(t), np.zeros_like(t), 50.5 + 24.5 * np.cos(t)], axis=1)
    handle = sweep_circle(path * MM, 6 * MM, handle_segments)
    mesh = union(cup, handle)
    kp = keypoints_mm(
        rim=(-39, 0, 95.5), handle=(61, 0, 50.5), bottom_centre=(0, 0, 0),
        inside_bottom=(0, 0, 7), side=(0, -41, 50),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "bowl",
    "Thick-walled ceramic bowl, 156 mm diameter.",
    material=mat("green_ceramic", lin("#6b9e78"), 0.5, 60.0, roughness=0.12),
    density=2300.0, friction=0.6, tags=("nonconvex",),
)  # fmt: skip
def _bowl() -> Built:
    a0 = -np.arccos(42 / 78)
    outer = ellipse_arc((0, 58), (78, 54), a0, 0, 16)
    inner = ellipse_arc((0, 58), (73, 50), 0, -np.pi / 2, 18)[:-1]
    # fmt: off
    prof = from_mm([
        (0, 0), (20, 0), (40, 0), (42, 2), *outer,
        (77.4, 59.6), (75.5, 60.2), (73.6, 59.6), *inner, (0, 8),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        rim_front=(75.5, 0, 60.2), rim_back=(-75.5, 0, 60.2), inside_bottom=(0, 0, 8),
        bottom_centre=(0, 0, 0), outer_side=(0, -70, 35),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "cup_black",
    "Black plastic cup, tapered, 86 mm rim diameter.",
    material=mat("black_plastic", BLACK, 0.3, 30.0, roughness=0.35),
    density=1100.0, friction=0.5, tags=("nonconvex", "black", "novel"),
)  # fmt: skip
def _cup_black() -> Built:
    s = np.linspace(0, 1, 10)
    outer = np.stack([30.5 + 11.5 * s, 1.5 + 86.5 * s], axis=1)
    inner = np.stack([39.6 - 12.1 * s, 88 - 84.5 * s], axis=1)
    # fmt: off
    prof = from_mm([
        (0, 0), (15, 0), (29, 0), *outer,
        (42.8, 89.3), (42.5, 90.5), (41, 90.8), (39.8, 89.5), *inner, (14, 3.5), (0, 3.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        rim_front=(41.5, 0, 90.8), rim_back=(-41.5, 0, 90.8), inside_bottom=(0, 0, 3.5),
        bottom_centre=(0, 0, 0), side=(0, -36, 45),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "pipe_straight",
    "Straight PVC pipe, 40 mm outer / 32 mm inner diameter, 200 mm long.",
    material=mat("grey_pvc", lin("#9a9ea3"), 0.3, 30.0, roughness=0.55),
    density=1400.0, friction=0.5, tags=("nonconvex", "cylindrical"),
)  # fmt: skip
def _pipe_straight() -> Built:
    zs = np.linspace(0, 200, 21)
    prof = from_mm([(20, z) for z in zs] + [(16, z) for z in zs[::-1]])
    mesh = revolve(prof, 48, closed=True)
    kp = keypoints_mm(
        end_a=(0, 0, 0), end_b=(0, 0, 200), rim_a=(18, 0, 0), rim_b=(-18, 0, 200),
        middle=(0, 20, 100),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "pipe_elbow",
    "90-degree PVC elbow, 40 mm outer diameter, 50 mm bend radius.",
    material=mat("white_pvc", lin("#e6e6e1"), 0.3, 30.0, roughness=0.55),
    density=1400.0, friction=0.5, tags=("nonconvex",),
)  # fmt: skip
def _pipe_elbow() -> Built:
    stub_a = np.stack([np.linspace(-30, 0, 6), np.zeros(6), np.zeros(6)], axis=1)
    a = np.linspace(0, np.pi / 2, 25)
    arc = np.stack([50 * np.sin(a), np.zeros_like(a), 50 - 50 * np.cos(a)], axis=1)
    stub_b = np.stack([np.full(6, 50.0), np.zeros(6), np.linspace(50, 80, 6)], axis=1)
    path = polyline(stub_a, arc, stub_b) * MM
    mesh = sweep_hollow(path, 20 * MM, 16 * MM, 32)
    c45 = np.cos(np.pi / 4)
    bend = (50 * c45 + 20 * c45, 0, 50 - 50 * c45 - 20 * c45)
    kp = keypoints_mm(
        end_a=(-30, 0, 0), end_b=(50, 0, 80), bend_outer=bend, rim_a=(-30, 0, 18),
        rim_b=(68, 0, 80),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "l_bracket",
    "Steel L-bracket, 80 x 60 x 40 mm, 4 mm plate, two holes.",
    material=mat("zinc_steel", lin("#b8bcc2"), 0.8, 80.0, roughness=0.4, metallic=1.0),
    density=7850.0, friction=0.4, tags=("nonconvex",),
)  # fmt: skip
def _l_bracket() -> Built:
    fillet = ellipse_arc((8, 8), (4, 4), -np.pi / 2, -np.pi, 7)
    outline = from_mm(
        [(0, 0), (40, 0), (80, 0), (80, 4), *fillet, (4, 34), (4, 60), (0, 60), (0, 30)]
    )
    plate = extrude(outline, height=40 * MM, layers=4)
    # the outline is drawn in the part's x-z plane: rotating +90 degrees about x sends the
    # drawing's y to z and the extrusion axis to -y; then centre the 40 mm width on y = 0
    plate = plate.transformed(rotation_matrix((1, 0, 0), np.pi / 2), (0.0, 20 * MM, 0.0))
    hole_a = cylinder(3.5 * MM, -5 * MM, 10 * MM, 32).translated((50 * MM, 0.0, 0.0))
    hole_b = cylinder(3.5 * MM, -5 * MM, 10 * MM, 32).transformed(
        rotation_matrix((0, 1, 0), np.pi / 2), (0.0, 0.0, 38 * MM)
    )
    mesh = ensure_min_faces(difference(plate, hole_a, hole_b), 300)
    kp = keypoints_mm(
        corner=(0, 0, 0), flange_tip=(80, 0, 2), upright_top=(2, 0, 60), hole_flange=(50, 0, 4),
        hole_upright=(4, 0, 38),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "hex_nut",
    "M16 steel hex nut, 24 mm across flats, 13 mm thick.",
    material=mat("steel", lin("#a7abb0"), 0.8, 80.0, roughness=0.18, metallic=1.0),
    density=7850.0, friction=0.4, tags=("nonconvex",),
)  # fmt: skip
def _hex_nut() -> Built:
    ang = np.arange(6) * (np.pi / 3)
    hexagon = np.stack([np.cos(ang), np.sin(ang)], axis=1) * (24.0 / np.sqrt(3.0))
    phi = np.arange(48) * (2 * np.pi / 48)
    hole = np.stack([np.cos(phi), np.sin(phi)], axis=1) * 8.0
    mesh = extrude(hexagon * MM, [hole * MM], height=13 * MM, layers=3)
    c30, s30 = np.cos(np.pi / 6), np.sin(np.pi / 6)
    kp = keypoints_mm(
        bore_top=(0, 0, 13), bore_bottom=(0, 0, 0), top_face=(0, 10.5, 13),
        flat=(12 * c30, 12 * s30, 6.5),
    )  # fmt: skip
    return Built(ensure_min_faces(mesh, 300), kp)


@_register(
    "clamp",
    "C-clamp: C-shaped frame, screw with pad and T-bar.",
    material=mat("red_cast_iron", lin("#b3261e"), 0.4, 40.0, roughness=0.5),
    density=4500.0, friction=0.5, tags=("nonconvex", "novel"),
)  # fmt: skip
def _clamp() -> Built:
    outline = from_mm(
        [(0, 0), (70, 0), (70, 16), (14, 16), (14, 84), (70, 84), (70, 100), (0, 100)]
    )
    frame = extrude(outline, height=14 * MM, layers=2)
    frame = frame.transformed(rotation_matrix((1, 0, 0), np.pi / 2), (0.0, 7 * MM, 0.0))
    screw = cylinder(5 * MM, -22 * MM, 55 * MM, 24, 6).translated((58 * MM, 0.0, 0.0))
    pad = cylinder(9 * MM, 55 * MM, 61 * MM, 32).translated((58 * MM, 0.0, 0.0))
    bar = cylinder(3.5 * MM, -25 * MM, 25 * MM, 16, 4).transformed(
        rotation_matrix((1, 0, 0), np.pi / 2), (58 * MM, 0.0, -18 * MM)
    )
    mesh = ensure_min_faces(union(frame, screw, pad, bar), 300)
    kp = keypoints_mm(
        screw_pad=(58, 0, 61), handle_end=(58, 25, -18), jaw=(58, 0, 84), back=(0, 0, 50),
        frame_top=(35, 0, 100),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "pear",
    "Pear-shaped fruit with a stem, 100 mm tall.",
    material=mat("pear_green", lin("#b5c64a"), 0.3, 25.0, roughness=0.45),
    density=980.0, friction=0.6,
)  # fmt: skip
def _pear(stem_steps: int = 10, stem_segments: int = 10) -> Built:
    # The defaults of stem_steps / stem_segments were chosen so that the union leaves no
    # sliver triangles (every altitude > 10 micrometres).
    h = 100.0
    t = np.linspace(0, np.pi, 42)[1:-1]
    z = h * (1 - np.cos(t)) / 2
    r = np.sin(t) * (36 - 24 * (z / h) ** 1.6)
    body = revolve(from_mm([(0, 0), *np.stack([r, z], axis=1), (0, h)]), 48)
    s = np.linspace(0, 1, stem_steps)
    stem_path = np.stack([3 * s**2, np.zeros_like(s), h - 4 + 18 * s], axis=1) * MM
    stem = sweep_circle(stem_path, 2.2 * MM, stem_segments)
    mesh = union(body, stem)
    k = int(np.argmax(r))
    kp = keypoints_mm(
        stem_tip=(3, 0, h + 14), bottom=(0, 0, 0), widest_front=(r[k], 0, z[k]),
        widest_back=(-r[k], 0, z[k]), neck=(0, 14, 82),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "tennis_ball",
    "Tennis ball, 67 mm diameter.",
    material=mat("felt_yellow", lin("#d4e83a"), 0.05, 5.0, roughness=0.95),
    density=360.0, friction=0.8,
)  # fmt: skip
def _tennis_ball() -> Built:
    mesh = superellipsoid((33.5 * MM,) * 3, steps=14)
    kp = keypoints_mm(top=(0, 0, 33.5), bottom=(0, 0, -33.5), side=(33.5, 0, 0))
    return Built(mesh, kp)


@_register(
    "marker_pen",
    "Marker pen with clip, 17 mm diameter, 142 mm long.",
    material=mat("marker_blue", lin("#1f4fb4"), 0.4, 40.0, roughness=0.3),
    density=600.0, friction=0.4, tags=("cylindrical",),
)  # fmt: skip
def _marker() -> Built:
    # fmt: off
    prof = from_mm([
        (0, 0), (1.2, 0.3), (2.2, 2), (2.4, 6), (4.5, 7), (6.5, 11), (7.5, 14),
        *[(7.5, z) for z in np.linspace(24, 94, 8)],
        (7.5, 100), (8.4, 100), *[(8.4, z) for z in np.linspace(110, 130, 3)], (8.4, 137),
        (7.8, 140), (6, 141.5), (0, 141.8),
    ])
    # fmt: on
    pen = revolve(prof, 48)
    clip = grid_box((2.3 * MM, 3 * MM, 34 * MM), max_edge=0.004, min_divisions=2)
    mesh = union(pen, clip.translated((9.05 * MM, 0.0, 121 * MM)))
    kp = keypoints_mm(
        tip=(0, 0, 0), cap_end=(0, 0, 141.8), clip=(10.2, 0, 121), grip=(-7.5, 0, 40),
        cap_edge=(0, 8.4, 100),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "cable_coil",
    "Black cable coiled in 3.5 turns, 6 mm cable, 86 mm coil diameter.",
    material=mat("black_rubber", BLACK, 0.2, 15.0, roughness=0.85),
    density=1800.0, friction=0.8, tags=("nonconvex", "black", "deformable", "novel"),
)  # fmt: skip
def _cable_coil() -> Built:
    turns, radius, pitch, r = 3.5, 40.0, 9.5, 3.0  # pitch > 2 r: turns do not touch
    t = np.linspace(0, turns * 2 * np.pi, int(turns * 48) + 1)
    helix = np.stack([radius * np.cos(t), radius * np.sin(t), pitch * t / (2 * np.pi)], axis=1)
    mesh = sweep_circle(helix * MM, r * MM, 10)
    top_z = pitch * turns
    kp = keypoints_mm(
        end_a=helix[0], end_b=helix[-1], coil_top=(-radius, 0, top_z - pitch / 2 + r),
        coil_outer=(0, radius + r, pitch / 4),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "wine_glass",
    "Clear wine glass, 80 mm bowl diameter, 166 mm tall.",
    material=CLEAR_GLASS, density=2500.0, friction=0.4, tags=("nonconvex", "transparent", "novel"),
)  # fmt: skip
def _wine_glass() -> Built:
    # bowl: outer ellipse (40 x 50 mm) and inner ellipse 1.5 mm inside it, same centre
    bowl_out = ellipse_arc((0, 135), (40, 50), np.deg2rad(-80), np.arcsin(0.6), 22)
    bowl_in = ellipse_arc((0, 135), (38.5, 48.5), np.arcsin(30 / 48.5), -np.pi / 2, 24)[:-1]
    rim = (0.5 * (bowl_out[-1][0] + bowl_in[0][0]), 165.9)
    # fmt: off
    prof = from_mm([
        (0, 0), (20, 0), (35, 0), (35, 2), (30, 3.5), (18, 5), (8, 6.5), (5, 9), (4, 14),
        *[(4, z) for z in np.linspace(24, 74, 6)],
        (4, 80), (5, 83.5), *bowl_out, rim, *bowl_in, (0, 86.5),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        rim=(rim[0], 0, 165.9), foot_centre=(0, 0, 0), foot_edge=(-35, 0, 1), stem=(0, 4, 45),
        bowl=(-40, 0, 135),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "bottle_clear",
    "Clear empty glass bottle with open mouth, 60 mm diameter, 200 mm tall.",
    material=CLEAR_GLASS, density=2500.0, friction=0.4,
    tags=("nonconvex", "transparent", "cylindrical", "novel"),
)  # fmt: skip
def _bottle_clear() -> Built:
    out_sh = ellipse_arc((12, 140), (18, 35), 0, np.pi / 2, 12)
    in_sh = ellipse_arc((10.5, 140), (17.5, 33), np.pi / 2, 0, 12)
    # fmt: off
    prof = from_mm([
        (0, 0), (20, 0), (27, 0.5), (29.5, 2.5), (30, 6),
        *[(30, z) for z in np.linspace(20, 130, 12)],
        *out_sh, (12, 185), (12, 194), (13.5, 195.5), (13.5, 199), (12.5, 200), (11, 200),
        (10.5, 198), (10.5, 186), *in_sh,
        *[(28, z) for z in np.linspace(130, 20, 12)],
        (28, 8), (27, 5.5), (20, 4.2), (0, 4),
    ])
    # fmt: on
    mesh = revolve(prof, SEG)
    kp = keypoints_mm(
        mouth=(0, 0, 200), bottom_centre=(0, 0, 0), side_front=(30, 0, 80),
        side_back=(-30, 0, 80), neck=(0, 12, 188),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "remote_control",
    "Black remote control, rounded 180 x 48 x 22 mm with buttons.",
    material=mat("black_abs", BLACK, 0.3, 30.0, roughness=0.3),
    density=800.0, friction=0.5, tags=("black",),
)  # fmt: skip
def _remote() -> Built:
    body = rounded_box((0.18, 0.048, 0.022), 0.007, max_edge=0.01)
    spots = [(-50, -11), (-50, 11), (-28, -11), (-28, 11), (-6, 0), (30, 0), (70, 0)]
    buttons = [
        cylinder(4 * MM, 9 * MM, 12.5 * MM, 24).translated((x * MM, y * MM, 0.0)) for x, y in spots
    ]
    mesh = union(body, *buttons)
    kp = keypoints_mm(
        top_centre=(0, 0, 11), bottom_centre=(0, 0, -11), end_front=(90, 0, 0),
        end_back=(-90, 0, 0), power_button=(70, 0, 12.5),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "sack",
    "Small filled sack (pillow-like, static shape), 200 x 140 x 64 mm.",
    material=mat("burlap", lin("#b79a6b"), 0.05, 5.0, roughness=0.95),
    density=600.0, friction=0.9, tags=("deformable", "novel"),
)  # fmt: skip
def _sack() -> Built:
    noise = smooth_noise(7, 0.05)
    mesh = superellipsoid((0.10, 0.07, 0.032), e1=0.35, e2=0.5, steps=24, noise=noise)
    v = mesh.vertices

    def extreme(axis: int, sign: float) -> tuple[float, float, float]:
        p = v[int(np.argmax(sign * v[:, axis]))]
        return (float(p[0]), float(p[1]), float(p[2]))

    kp = (
        ("top_centre", extreme(2, 1.0)),
        ("bottom_centre", extreme(2, -1.0)),
        ("end_a", extreme(0, 1.0)),
        ("end_b", extreme(0, -1.0)),
        ("side", extreme(1, 1.0)),
    )
    return Built(mesh, kp)


@_register(
    "sponge",
    "Kitchen sponge, 95 x 65 x 30 mm.",
    material=mat("sponge_yellow", lin("#f2d13a"), 0.05, 5.0, roughness=0.9),
    density=40.0, friction=1.0, tags=("deformable",),
)  # fmt: skip
def _sponge() -> Built:
    mesh = rounded_box((0.095, 0.065, 0.03), 0.006, max_edge=0.008)
    kp = keypoints_mm(
        top_centre=(0, 0, 15), bottom_centre=(0, 0, -15), end_a=(47.5, 0, 0),
        end_b=(-47.5, 0, 0), side=(0, 32.5, 0),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "toothpaste_tube",
    "Toothpaste tube with cap, flattened at the crimped end.",
    material=mat("tube_white", lin("#f4f6f8"), 0.4, 40.0, roughness=0.3),
    density=1100.0, friction=0.5, tags=("deformable",),
)  # fmt: skip
def _toothpaste() -> Built:
    # elliptic cross-sections: round shoulder (z 0..8 mm), then widening and flattening
    # towards the crimped seal (z 150..160 mm)
    zs = np.concatenate([np.linspace(0, 8, 6), np.linspace(8, 150, 40)[1:], [155.0, 160.0]])
    a = np.empty_like(zs)
    b = np.empty_like(zs)
    sh = zs <= 8
    a[sh] = b[sh] = 9 + 7 * np.sin(0.5 * np.pi * zs[sh] / 8)
    s = np.clip((zs[~sh] - 8) / 142, 0, 1)
    a[~sh] = 16 + 9 * s**1.5
    b[~sh] = 16 - 14.5 * s**0.8
    phi = np.arange(32) * (2 * np.pi / 32)
    rings = np.stack(
        [
            a[:, None] * np.cos(phi)[None, :],
            b[:, None] * np.sin(phi)[None, :],
            np.repeat(zs[:, None], 32, axis=1),
        ],
        axis=2,
    )
    tube = loft(rings * MM)
    cap = revolve(from_mm([(0, -18), (10, -18), (11, -17), (11, -8), (11, 1), (0, 1)]), 32)
    mesh = union(tube, cap)
    kp = keypoints_mm(
        cap_end=(0, 0, -18), crimp=(0, 0, 160), body_front=(0, -15.2, 40),
        body_back=(0, 15.2, 40), crimp_corner=(25, 0, 158),
    )  # fmt: skip
    return Built(mesh, kp)


@_register(
    "tape_roll",
    "Roll of packing tape, 110 mm outer / 76 mm inner diameter, 48 mm wide.",
    material=mat("tape_brown", lin("#a8763e"), 0.5, 50.0, roughness=0.25),
    density=1100.0, friction=0.6, tags=("nonconvex", "cylindrical"),
)  # fmt: skip
def _tape_roll() -> Built:
    c = 1.5  # corner radius of the rectangular section r 38..55 mm, z 0..48 mm
    # fmt: off
    prof = from_mm([
        *ellipse_arc((38 + c, c), (c, c), np.pi, 1.5 * np.pi, 4),
        *[(r, 0) for r in np.linspace(42, 51, 4)],
        *ellipse_arc((55 - c, c), (c, c), 1.5 * np.pi, 2 * np.pi, 4),
        *[(55, z) for z in np.linspace(8, 40, 5)],
        *ellipse_arc((55 - c, 48 - c), (c, c), 0, 0.5 * np.pi, 4),
        *[(r, 48) for r in np.linspace(51, 42, 4)],
        *ellipse_arc((38 + c, 48 - c), (c, c), 0.5 * np.pi, np.pi, 4),
        *[(38, z) for z in np.linspace(40, 8, 5)],
    ])
    # fmt: on
    mesh = revolve(prof, SEG, closed=True)
    kp = keypoints_mm(
        core_centre=(0, 0, 24), top_face=(46.5, 0, 48), outer_side=(0, -55, 24),
        inner_side=(-38, 0, 24), bottom_face=(0, 46.5, 0),
    )  # fmt: skip
    return Built(mesh, kp)
