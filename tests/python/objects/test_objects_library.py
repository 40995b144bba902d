"""Tests of the procedural object library and the tote (mgn.objects).

Geometry is checked independently of the library's own code: with trimesh (watertightness,
winding, volume, convex hull), and with small numpy routines written here (self-intersections,
winding numbers).
"""

from __future__ import annotations

import hashlib
import math
import re

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from mgn.objects import (  # noqa: E402
    ALLOWED_TAGS,
    Keypoint,
    MaterialSpec,
    ObjectSpec,
    ToteSpec,
    builtin_objects,
    default_tote,
    get_object,
    make_tote,
    object_names,
)

NAMES = object_names()
TOTE_INNER = (0.400, 0.300, 0.150)


def _welded(obj_vertices: np.ndarray, obj_faces: np.ndarray) -> trimesh.Trimesh:
    mesh = trimesh.Trimesh(
        vertices=np.array(obj_vertices), faces=np.array(obj_faces), process=False
    )
    mesh.merge_vertices()
    return mesh


@pytest.fixture(scope="module")
def objects() -> tuple[ObjectSpec, ...]:
    return builtin_objects()


@pytest.fixture(scope="module")
def welded(objects: tuple[ObjectSpec, ...]) -> dict[str, trimesh.Trimesh]:
    return {o.name: _welded(o.vertices, o.faces) for o in objects}


# ------------------------------------------------------------------------------------------------
# Independent geometry helpers
# ------------------------------------------------------------------------------------------------


def _candidate_pairs(tri: np.ndarray) -> np.ndarray:
    """Pairs (i < j) of triangles whose bounding boxes share a cell of a uniform grid."""
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    h = max(float(np.median((hi - lo).max(axis=1))) * 2.0, 1e-6)
    lo_c = np.floor(lo / h).astype(np.int64)
    hi_c = np.floor(hi / h).astype(np.int64)
    span = hi_c - lo_c + 1
    cnt = span.prod(axis=1)
    tid = np.repeat(np.arange(len(tri)), cnt)
    local = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    sp = span[tid]
    cell = lo_c[tid] + np.stack(
        [local % sp[:, 0], (local // sp[:, 0]) % sp[:, 1], local // (sp[:, 0] * sp[:, 1])], axis=1
    )
    cell -= cell.min(axis=0)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    key, tid = key[order], tid[order]
    _, run = np.unique(key, return_counts=True)
    pairs = []
    for k in range(1, int(run.max())):
        same = key[k:] == key[:-k]
        pairs.append(np.stack([tid[:-k][same], tid[k:][same]], axis=1))
    if not pairs:
        return np.zeros((0, 2), dtype=np.int64)
    p = np.sort(np.concatenate(pairs), axis=1)
    p = p[p[:, 0] != p[:, 1]]
    return np.unique(p, axis=0)


def _segments_cross_triangles(p0: np.ndarray, p1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Strict segment/triangle crossing (Moller-Trumbore), vectorised over rows."""
    d = p1 - p0
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    pv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pv)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tv = p0 - t[:, 0]
    u = np.einsum("ij,ij->i", tv, pv) * inv
    qv = np.cross(tv, e1)
    v = np.einsum("ij,ij->i", d, qv) * inv
    s = np.einsum("ij,ij->i", e2, qv) * inv
    eps = 1e-9
    return ok & (u > eps) & (v > eps) & (u + v < 1 - eps) & (s > eps) & (s < 1 - eps)


def _count_self_intersections(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Number of pairs of non-adjacent triangles whose interiors cross."""
    tri = vertices[faces]
    pairs = _candidate_pairs(tri)
    if len(pairs) == 0:
        return 0
    fa, fb = faces[pairs[:, 0]], faces[pairs[:, 1]]
    shares = (fa[:, :, None] == fb[:, None, :]).any(axis=(1, 2))
    pairs = pairs[~shares]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    overlap = np.all(
        (lo[pairs[:, 0]] <= hi[pairs[:, 1]]) & (lo[pairs[:, 1]] <= hi[pairs[:, 0]]), axis=1
    )
    pairs = pairs[overlap]
    hit = np.zeros(len(pairs), dtype=bool)
    for a, b in ((0, 1), (1, 0)):
        ta, tb = tri[pairs[:, a]], tri[pairs[:, b]]
        for i, j in ((0, 1), (1, 2), (2, 0)):
            hit |= _segments_cross_triangles(ta[:, i], ta[:, j], tb)
    return int(hit.sum())


def _winding_number(vertices: np.ndarray, faces: np.ndarray, point: np.ndarray) -> float:
    """Generalised winding number of a closed mesh about a point (1 inside, 0 outside)."""
    t = vertices[faces] - np.asarray(point, dtype=np.float64)
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (
        la * lb * lc
        + np.einsum("ij,ij->i", a, b) * lc
        + np.einsum("ij,ij->i", b, c) * la
        + np.einsum("ij,ij->i", c, a) * lb
    )
    return float(np.sum(2.0 * np.arctan2(num, den)) / (4.0 * np.pi))


def test_self_intersection_checker_detects_crossing() -> None:
    """The helper itself: two crossing tetrahedra are found, two disjoint ones are not."""
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    other = box.copy()
    other.apply_translation((0.5, 0.3, 0.2))
    both = trimesh.util.concatenate([box, other])
    assert _count_self_intersections(both.vertices, both.faces) > 0
    other.apply_translation((3.0, 0.0, 0.0))
    apart = trimesh.util.concatenate([box, other])
    assert _count_self_intersections(apart.vertices, apart.faces) == 0


# ------------------------------------------------------------------------------------------------
# Catalogue-level checks
# ------------------------------------------------------------------------------------------------


def test_catalogue_ids_and_names(objects: tuple[ObjectSpec, ...]) -> None:
    assert len(objects) >= 26
    assert [o.category_id for o in objects] == list(range(1, len(objects) + 1))
    names = [o.name for o in objects]
    assert len(set(names)) == len(names)
    assert names == NAMES
    for n in names:
        assert re.fullmatch(r"[a-z][a-z0-9_]*", n), n


def test_catalogue_covers_required_kinds(objects: tuple[ObjectSpec, ...]) -> None:
    by_name = {o.name: o for o in objects}
    printed_boxes = [o for o in objects if {"box", "textured"} <= o.tags]
    assert len(printed_boxes) >= 4
    assert sum("transparent" in o.tags for o in objects) >= 2
    assert sum("black" in o.tags for o in objects) >= 2
    assert sum("deformable" in o.tags for o in objects) >= 1
    for required in (
        "mug",
        "bowl",
        "pipe_straight",
        "pipe_elbow",
        "l_bracket",
        "clamp",
        "cable_coil",
        "wine_glass",
    ):
        assert "nonconvex" in by_name[required].tags, required
    for required in (
        "can_soda",
        "can_food",
        "bottle_water",
        "bottle_detergent",
        "pear",
        "marker_pen",
        "sack",
    ):
        assert required in by_name


def test_builtin_objects_is_cached(objects: tuple[ObjectSpec, ...]) -> None:
    assert builtin_objects() is builtin_objects()


def _digest(objs: tuple[ObjectSpec, ...]) -> str:
    h = hashlib.sha256()
    for o in objs:
        h.update(o.name.encode())
        h.update(o.vertices.tobytes())
        h.update(o.faces.tobytes())
        if o.uvs is not None:
            h.update(o.uvs.tobytes())
            h.update(o.material.texture.tobytes())
        for k in o.keypoints:
            h.update(np.asarray(k.position).tobytes())
    return h.hexdigest()


def test_build_is_deterministic() -> None:
    first = builtin_objects()
    digest = _digest(first)
    builtin_objects.cache_clear()
    second = builtin_objects()
    assert second is not first
    assert _digest(second) == digest
    for a, b in zip(first, second, strict=True):
        assert a == b
        assert np.array_equal(a.vertices, b.vertices)
        assert np.array_equal(a.faces, b.faces)


def test_get_object_lookup(objects: tuple[ObjectSpec, ...]) -> None:
    mug = get_object("mug")
    assert mug.name == "mug"
    assert get_object(mug.category_id) is mug
    assert get_object(str(mug.category_id)) is mug
    assert get_object(np.int64(mug.category_id)) is mug
    with pytest.raises(KeyError, match="no_such_thing") as err:
        get_object("no_such_thing")
    assert "mug" in str(err.value)
    assert "box_cereal" in str(err.value)
    for bad_id in (0, len(objects) + 1, -3):
        with pytest.raises(KeyError, match=str(bad_id)):
            get_object(bad_id)
    for bad in (None, 2.5, True, ["mug"]):
        with pytest.raises(TypeError):
            get_object(bad)  # type: ignore[arg-type]


def test_arrays_are_read_only(objects: tuple[ObjectSpec, ...]) -> None:
    o = objects[0]
    with pytest.raises(ValueError, match="read-only"):
        o.vertices[0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        o.faces[0, 0] = 0
    with pytest.raises(ValueError, match="read-only"):
        o.material.texture[0, 0, 0] = 0


def test_material_and_spec_validation(objects: tuple[ObjectSpec, ...]) -> None:
    with pytest.raises(ValueError, match="opacity"):
        MaterialSpec("m", (1.0, 1.0, 1.0, 1.0), opacity=0.0)
    with pytest.raises(ValueError, match="base_color"):
        MaterialSpec("m", (1.5, 1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="texture"):
        MaterialSpec("m", (1.0, 1.0, 1.0, 1.0), texture=np.zeros((4, 4), dtype=np.uint8))
    # texture is excluded from equality and hashing
    a = MaterialSpec("m", (1.0, 1.0, 1.0, 1.0), texture=np.zeros((2, 2, 3), dtype=np.uint8))
    b = MaterialSpec("m", (1.0, 1.0, 1.0, 1.0), texture=np.full((2, 2, 3), 9, dtype=np.uint8))
    assert a == b
    assert hash(a) == hash(b)
    mug = get_object("mug")
    kps = (Keypoint(1, "a", (0.0, 0.0, 0.0)), Keypoint(2, "b", (0.0, 0.0, 0.01)))
    common = {
        "category_id": 99,
        "name": "t",
        "description": "",
        "vertices": mug.vertices,
        "faces": mug.faces,
        "uvs": None,
        "material": mug.material,
        "friction": 0.5,
        "keypoints": kps,
        "tags": frozenset(),
    }
    with pytest.raises(ValueError, match="density"):
        ObjectSpec(density=-1.0, **common)
    with pytest.raises(ValueError, match="tags"):
        ObjectSpec(density=1.0, **{**common, "tags": frozenset({"shiny"})})
    with pytest.raises(ValueError, match="keypoint"):
        ObjectSpec(density=1.0, **{**common, "keypoints": kps[:1]})
    with pytest.raises(ValueError, match="uvs"):
        ObjectSpec(density=1.0, **{**common, "uvs": np.zeros((len(mug.vertices), 2))})


# ------------------------------------------------------------------------------------------------
# Per-object checks
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_mesh_closed_outward_single_body(name: str, welded: dict[str, trimesh.Trimesh]) -> None:
    o = get_object(name)
    assert o.vertices.dtype == np.float64
    assert o.vertices.shape[1] == 3
    assert o.faces.dtype == np.int32
    assert o.faces.shape[1] == 3
    assert 300 <= len(o.faces) <= 20000, len(o.faces)
    assert np.all(np.isfinite(o.vertices))
    assert len(np.unique(o.faces)) == len(o.vertices), "unreferenced vertices"
    m = welded[name]
    assert m.is_watertight
    assert m.is_winding_consistent
    assert m.volume > 0
    assert m.body_count == 1
    # every edge is shared by exactly two faces (manifold), checked directly as well
    edges = np.sort(m.edges, axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)
    assert math.isclose(o.volume, m.volume, rel_tol=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_no_degenerate_faces(name: str, welded: dict[str, trimesh.Trimesh]) -> None:
    m = welded[name]
    t = m.vertices[m.faces]
    area2 = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    longest = np.max(np.linalg.norm(t - np.roll(t, 1, axis=1), axis=2), axis=1)
    assert area2.min() > 2e-12, "zero-area face"
    assert (area2 / longest).min() > 1e-7, "needle triangle (altitude below 0.1 micrometre)"
    # no two faces on the same three vertices
    assert len(np.unique(np.sort(m.faces, axis=1), axis=0)) == len(m.faces)


@pytest.mark.parametrize("name", NAMES)
def test_no_self_intersections(name: str, welded: dict[str, trimesh.Trimesh]) -> None:
    m = welded[name]
    assert _count_self_intersections(np.asarray(m.vertices), np.asarray(m.faces)) == 0


@pytest.mark.parametrize("name", NAMES)
def test_size_and_frame(name: str) -> None:
    o = get_object(name)
    lo, hi = o.vertices.min(axis=0), o.vertices.max(axis=0)
    np.testing.assert_allclose((lo + hi) / 2, 0.0, atol=1e-12)  # origin at the bbox centre
    ext = hi - lo
    assert 0.015 <= ext.max() <= 0.250, ext
    assert ext.min() >= 0.005, ext
    assert np.all(np.sort(ext) <= np.sort(TOTE_INNER)), "does not fit the tote"


@pytest.mark.parametrize("name", NAMES)
def test_keypoints(name: str) -> None:
    o = get_object(name)
    assert 2 <= len(o.keypoints) <= 8
    assert [k.id for k in o.keypoints] == list(range(1, len(o.keypoints) + 1))
    assert len({k.name for k in o.keypoints}) == len(o.keypoints)
    lo, hi = o.vertices.min(axis=0) - 0.005, o.vertices.max(axis=0) + 0.005
    for k in o.keypoints:
        p = np.asarray(k.position, dtype=np.float64)
        assert p.shape == (3,), k
        assert np.all(np.isfinite(p)), k
        assert np.all(p >= lo), k
        assert np.all(p <= hi), k
        assert re.fullmatch(r"[a-z][a-z0-9_]*", k.name)


@pytest.mark.parametrize("name", NAMES)
def test_texture_and_uvs(name: str) -> None:
    o = get_object(name)
    tex = o.material.texture
    assert (o.uvs is None) == (tex is None)
    assert ("textured" in o.tags) == (tex is not None)
    if tex is None:
        return
    assert tex.dtype == np.uint8
    assert tex.ndim == 3
    assert tex.shape[2] == 3
    assert 16 <= tex.shape[0] <= 1024
    assert 16 <= tex.shape[1] <= 1024
    assert tex.std() > 5.0, "texture is a flat colour"
    assert o.uvs.dtype == np.float32
    assert o.uvs.shape == (len(o.vertices), 2)
    assert np.all(o.uvs >= 0.0)
    assert np.all(o.uvs <= 1.0)
    # the UV layout is used: no triangle is degenerate in texture space for a printed box
    if "box" in o.tags:
        uv = o.uvs[o.faces].astype(np.float64)
        e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
        area = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        assert area.min() > 0
        # each of the six atlas cells holds one face of the box
        cells = np.floor(uv.mean(axis=1) * [3, 2]).astype(int)
        assert len({tuple(c) for c in cells}) == 6


@pytest.mark.parametrize("name", NAMES)
def test_tags_are_honest(name: str, welded: dict[str, trimesh.Trimesh]) -> None:
    o = get_object(name)
    assert o.tags <= ALLOWED_TAGS
    mat = o.material
    assert ("transparent" in o.tags) == (mat.opacity < 0.5)
    if "transparent" in o.tags:
        assert 0.1 <= mat.opacity <= 0.2
    assert ("black" in o.tags) == (max(mat.base_color[:3]) <= 0.05)
    ext = o.extents
    assert ("small" in o.tags) == (ext.max() <= 0.070)
    assert ("large" in o.tags) == (ext.max() >= 0.180)
    assert ("thin" in o.tags) == (ext.min() <= 0.025)
    m = welded[name]
    solidity = m.volume / m.convex_hull.volume
    assert ("nonconvex" in o.tags) == (solidity < 0.7), solidity
    if "box" in o.tags:
        assert m.volume / np.prod(ext) > 0.98


@pytest.mark.parametrize("name", NAMES)
def test_physical_properties(name: str) -> None:
    o = get_object(name)
    assert 20.0 <= o.density <= 8000.0
    assert 0.3 <= o.friction <= 1.0
    assert 0.001 <= o.mass <= 3.0, o.mass
    assert all(0.0 <= c <= 1.0 for c in o.material.base_color)
    assert 0.0 < o.material.opacity <= 1.0


# ------------------------------------------------------------------------------------------------
# Tote
# ------------------------------------------------------------------------------------------------


def _tote_volume(s: ToteSpec) -> float:
    return (s.inner_length + 2 * s.wall_thickness) * (s.inner_width + 2 * s.wall_thickness) * (
        s.inner_height + s.floor_thickness
    ) - s.inner_length * s.inner_width * s.inner_height


@pytest.mark.parametrize(
    "spec",
    [
        ToteSpec(),
        ToteSpec(0.6, 0.4, 0.2, 0.005, 0.004),
        ToteSpec(inner_length=0.25, inner_width=0.25, inner_height=0.05),
    ],
)
def test_tote_mesh(spec: ToteSpec) -> None:
    v, f = make_tote(spec)
    assert v.dtype == np.float64
    assert v.shape == (16, 3)
    assert f.dtype == np.int32
    assert f.shape[1] == 3
    m = trimesh.Trimesh(vertices=v, faces=f, process=False)
    assert m.is_watertight
    assert m.is_winding_consistent
    assert math.isclose(m.volume, _tote_volume(spec), rel_tol=1e-9)
    assert _count_self_intersections(v, f) == 0
    # extents in the tote frame
    np.testing.assert_allclose(
        v.min(axis=0),
        [
            -spec.inner_length / 2 - spec.wall_thickness,
            -spec.inner_width / 2 - spec.wall_thickness,
            -spec.floor_thickness,
        ],
    )
    np.testing.assert_allclose(
        v.max(axis=0),
        [
            spec.inner_length / 2 + spec.wall_thickness,
            spec.inner_width / 2 + spec.wall_thickness,
            spec.inner_height,
        ],
    )
    # the inner floor: upward faces at z = 0 covering exactly the cavity footprint
    normals = m.face_normals
    floor = (np.abs(v[f][:, :, 2]).max(axis=1) < 1e-15) & (normals[:, 2] > 0.999)
    assert math.isclose(
        m.area_faces[floor].sum(), spec.inner_length * spec.inner_width, rel_tol=1e-12
    )
    # material where it should be, air in the cavity
    hx, hy = spec.inner_length / 2, spec.inner_width / 2
    assert abs(_winding_number(v, f, (0.0, 0.0, spec.inner_height / 2))) < 1e-9
    assert abs(_winding_number(v, f, (0.3 * hx, -0.2 * hy, 1e-4))) < 1e-9
    assert math.isclose(
        _winding_number(v, f, (0.0, 0.0, -spec.floor_thickness / 2)), 1.0, abs_tol=1e-9
    )
    assert math.isclose(
        _winding_number(v, f, (hx + spec.wall_thickness / 2, 0.0, spec.inner_height / 2)),
        1.0,
        abs_tol=1e-9,
    )
    assert math.isclose(
        _winding_number(v, f, (0.0, -hy - spec.wall_thickness / 2, 0.01)), 1.0, abs_tol=1e-9
    )
    assert abs(_winding_number(v, f, (0.0, 0.0, spec.inner_height + 0.01))) < 1e-9


def test_tote_defaults() -> None:
    assert default_tote() == ToteSpec()
    s = default_tote()
    assert (s.inner_length, s.inner_width, s.inner_height) == TOTE_INNER
    v, f = make_tote()
    v2, f2 = make_tote(s)
    assert np.array_equal(v, v2)
    assert np.array_equal(f, f2)


@pytest.mark.parametrize(
    "field", ["inner_length", "inner_width", "inner_height", "wall_thickness", "floor_thickness"]
)
@pytest.mark.parametrize("value", [0.0, -0.1, float("nan"), float("inf")])
def test_tote_rejects_bad_spec(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        ToteSpec(**{field: value})


def test_tote_rejects_bad_color() -> None:
    with pytest.raises(ValueError, match="color"):
        ToteSpec(color=(0.2, 0.3, 2.0, 1.0))
    with pytest.raises(ValueError, match="color"):
        ToteSpec(color=(0.2, 0.3, 0.5))  # type: ignore[arg-type]


def test_objects_fit_the_default_tote_footprint(objects: tuple[ObjectSpec, ...]) -> None:
    s = default_tote()
    inner = np.sort([s.inner_length, s.inner_width, s.inner_height])
    for o in objects:
        assert np.all(np.sort(o.extents) <= inner), o.name


# ------------------------------------------------------------------------------------------------
# Mesh builders (mgn.objects.shapes) against closed-form volumes
# ------------------------------------------------------------------------------------------------


def _check_closed(v: np.ndarray, f: np.ndarray) -> trimesh.Trimesh:
    m = _welded(v, f)
    assert m.is_watertight
    assert m.is_winding_consistent
    assert m.volume > 0
    return m


def test_revolve_cylinder_volume_and_uv_seams() -> None:
    from mgn.objects import shapes

    n, r, h = 24, 0.03, 0.1
    prof = [(0.0, 0.0), (r, 0.0), (r, h / 2), (r, h), (0.0, h)]
    exact = 0.5 * n * r * r * math.sin(2 * math.pi / n) * h  # inscribed n-gon prism
    plain = shapes.revolve(prof, n)
    textured = shapes.revolve(prof, n, with_uv=True)
    for mesh in (plain, textured):
        m = _check_closed(mesh.vertices, mesh.faces)
        assert math.isclose(m.volume, exact, rel_tol=1e-12)
    assert len(textured.vertices) > len(plain.vertices)  # seam and pole copies
    assert np.all((textured.uvs >= 0) & (textured.uvs <= 1))
    ring = shapes.revolve([(0.02, 0.0), (0.03, 0.0), (0.03, 0.01), (0.02, 0.01)], n, closed=True)
    ring_uv = shapes.revolve(
        [(0.02, 0.0), (0.03, 0.0), (0.03, 0.01), (0.02, 0.01)], n, closed=True, with_uv=True
    )
    ring_exact = 0.5 * n * math.sin(2 * math.pi / n) * (0.03**2 - 0.02**2) * 0.01
    for mesh in (ring, ring_uv):
        m = _check_closed(mesh.vertices, mesh.faces)
        assert math.isclose(m.volume, ring_exact, rel_tol=1e-12)
    with pytest.raises(ValueError, match="open profile"):
        shapes.revolve([(0.01, 0.0), (0.02, 0.0), (0.0, 0.01)], n)  # open profile off the axis


def test_extrude_with_hole_and_layers() -> None:
    from mgn.objects import shapes

    outer = [(0.0, 0.0), (0.05, 0.0), (0.05, 0.04), (0.0, 0.04)]
    hole = [(0.01, 0.01), (0.02, 0.01), (0.02, 0.02), (0.01, 0.02)]
    for layers in (1, 3):
        mesh = shapes.extrude(outer[::-1], [hole], height=0.02, layers=layers)
        m = _check_closed(mesh.vertices, mesh.faces)
        assert math.isclose(m.volume, (0.05 * 0.04 - 0.01 * 0.01) * 0.02, rel_tol=1e-12)
        assert m.euler_number == 0  # one through-hole: genus 1


def test_grid_and_rounded_box_volumes() -> None:
    from mgn.objects import shapes

    box = shapes.grid_box((0.03, 0.04, 0.05), max_edge=0.01, with_uv=True)
    m = _check_closed(box.vertices, box.faces)
    assert math.isclose(m.volume, 0.03 * 0.04 * 0.05, rel_tol=1e-12)
    a, b, c, r = 0.06, 0.05, 0.04, 0.008
    ai, bi, ci = a - 2 * r, b - 2 * r, c - 2 * r
    exact = (
        ai * bi * ci
        + 2 * r * (ai * bi + bi * ci + ai * ci)
        + math.pi * r * r * (ai + bi + ci)
        + 4 / 3 * math.pi * r**3
    )
    rb = shapes.rounded_box((a, b, c), r, round_steps=8)
    m = _check_closed(rb.vertices, rb.faces)
    assert m.volume < exact
    assert math.isclose(m.volume, exact, rel_tol=5e-3)
    np.testing.assert_allclose(m.extents, (a, b, c), rtol=1e-12)
    with pytest.raises(ValueError, match="radius"):
        shapes.rounded_box((a, b, c), 0.03)


def test_sweeps_and_subdivision() -> None:
    from mgn.objects import shapes

    n, length = 20, 0.1
    path = np.stack([np.zeros(5), np.zeros(5), np.linspace(0, length, 5)], axis=1)
    k = 0.5 * n * math.sin(2 * math.pi / n)
    solid = shapes.sweep_circle(path, 0.01, n)
    hollow = shapes.sweep_hollow(path, 0.01, 0.006, n)
    assert math.isclose(
        _check_closed(solid.vertices, solid.faces).volume, k * 0.01**2 * length, rel_tol=1e-12
    )
    assert math.isclose(
        _check_closed(hollow.vertices, hollow.faces).volume,
        k * (0.01**2 - 0.006**2) * length,
        rel_tol=1e-12,
    )
    finer = shapes.subdivide(hollow)
    assert len(finer.faces) == 4 * len(hollow.faces)
    assert math.isclose(
        _check_closed(finer.vertices, finer.faces).volume, hollow.signed_volume, rel_tol=1e-12
    )
    with pytest.raises(ValueError, match="inner_radius < outer_radius"):
        shapes.sweep_hollow(path, 0.01, 0.02, n)


def test_booleans_and_blob() -> None:
    from mgn.objects import shapes

    cube = shapes.grid_box((0.04, 0.04, 0.04), max_edge=0.02)
    shifted = cube.translated((0.02, 0.0, 0.0))
    u = shapes.union(cube, shifted)
    d = shapes.difference(cube, shifted)
    assert math.isclose(_check_closed(u.vertices, u.faces).volume, 0.06 * 0.04 * 0.04, rel_tol=1e-9)
    assert math.isclose(_check_closed(d.vertices, d.faces).volume, 0.02 * 0.04 * 0.04, rel_tol=1e-9)
    sphere = shapes.superellipsoid((0.02, 0.02, 0.02), steps=16)
    m = _check_closed(sphere.vertices, sphere.faces)
    assert math.isclose(m.volume, 4 / 3 * math.pi * 0.02**3, rel_tol=0.02)
    np.testing.assert_allclose(np.linalg.norm(sphere.vertices, axis=1), 0.02, rtol=1e-12)
