"""Seeded random procedural objects (mgn.objects.random_shapes): closed, outward-wound,
within the asked size, reproducible, and refused settings named."""

from __future__ import annotations

import numpy as np
import pytest

from mgn.errors import InvalidArgumentError
from mgn.objects.random_shapes import (
    KINDS,
    MAX_MASS_KG,
    MIN_THICKNESS,
    random_shape,
    random_shape_source,
    random_shapes,
    random_shapes_from_source,
)
from mgn.pipeline.config import ConfigError, load_config

SIZE = (0.02, 0.25)
POOL = random_shapes(80, SIZE, 3, 31)


def _volume(v: np.ndarray, f: np.ndarray) -> float:
    """Enclosed volume by the divergence theorem, written out here (not the library's)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return float(np.sum(a * np.cross(b, c)) / 6.0)


def _edge_uses(f: np.ndarray) -> tuple[dict[tuple[int, int], int], dict[tuple[int, int], int]]:
    """Directed and undirected edge counts of a face list."""
    directed: dict[tuple[int, int], int] = {}
    undirected: dict[tuple[int, int], int] = {}
    for tri in f.tolist():
        for i in range(3):
            a, b = tri[i], tri[(i + 1) % 3]
            directed[(a, b)] = directed.get((a, b), 0) + 1
            key = (min(a, b), max(a, b))
            undirected[key] = undirected.get(key, 0) + 1
    return directed, undirected


@pytest.mark.parametrize("index", range(0, 80, 1))
def test_every_shape_is_closed_outward_and_within_size(index: int) -> None:
    spec = POOL[index]
    v, f = np.asarray(spec.vertices), np.asarray(spec.faces)
    # Closed 2-manifold with consistent winding, counted edge by edge: every undirected edge
    # is used by exactly two faces, in opposite directions.
    directed, undirected = _edge_uses(f)
    assert set(undirected.values()) == {2}, spec.description
    assert max(directed.values()) == 1, spec.description
    # The library's check agrees.
    report = spec.to_mesh().validate()
    assert report.is_watertight
    assert report.num_boundary_edges == 0
    assert _volume(v, f) > 0.0, f"{spec.name} ({spec.description}) is wound inward"
    ext = v.max(axis=0) - v.min(axis=0)
    assert SIZE[0] - 1e-9 <= ext.max() <= SIZE[1] + 1e-9, (spec.description, ext)
    assert ext.min() >= MIN_THICKNESS * 0.99, (spec.description, ext)
    # The object frame is the bounding-box centre.
    np.testing.assert_allclose(v.max(axis=0) + v.min(axis=0), 0.0, atol=1e-9)
    assert spec.density * _volume(v, f) <= MAX_MASS_KG * (1 + 1e-9)
    assert "random" in spec.tags
    assert spec.category_id == 31 + index
    assert spec.name == f"random_shape_{index:04d}"


def test_the_pool_holds_every_kind_and_a_spread_of_sizes() -> None:
    kinds = {s.description.split()[1].rstrip(",") for s in POOL}
    assert kinds == set(KINDS)
    sizes = np.array([np.ptp(s.vertices, axis=0).max() for s in POOL])
    # Uniform in 0.02-0.25 m: 80 draws reach both ends of the range.
    assert sizes.min() < 0.05
    assert sizes.max() > 0.22
    assert any("black" in s.tags for s in POOL)  # one in four is black or dark grey


@pytest.mark.parametrize("size", [(0.05, 0.05), (0.01, 0.03), (0.3, 0.6)])
def test_size_range_is_kept(size: tuple[float, float]) -> None:
    for spec in random_shapes(24, size, 0, 1):
        ext = np.ptp(spec.vertices, axis=0).max()
        assert size[0] - 1e-9 <= ext <= size[1] + 1e-9


def test_same_seed_same_meshes_other_seed_other_meshes() -> None:
    a = [random_shape(5, k, SIZE) for k in range(12)]
    b = [random_shape(5, k, SIZE) for k in range(12)]
    c = [random_shape(6, k, SIZE) for k in range(12)]
    for x, y in zip(a, b, strict=True):
        assert x.vertices.tobytes() == y.vertices.tobytes()
        assert x.faces.tobytes() == y.faces.tobytes()
        assert x.material == y.material
        assert x.density == y.density
    differ = sum(x.vertices.tobytes() != z.vertices.tobytes() for x, z in zip(a, c, strict=True))
    assert differ == 12
    # A larger pool starts with the same shapes.
    small, large = random_shapes(4, SIZE, 5, 1), random_shapes(9, SIZE, 5, 1)
    assert all(x == y for x, y in zip(small, large[:4], strict=False))


def test_dark_share_changes_colours_only() -> None:
    never = random_shapes(40, SIZE, 3, 31, 0.0)
    always = random_shapes(40, SIZE, 3, 31, 1.0)
    usual = POOL[:40]
    assert not any("black" in s.tags for s in never)
    # Black or dark grey: every linear channel below 0.05 (sRGB value <= 0.2 at low saturation).
    assert all(max(s.material.base_color[:3]) < 0.05 for s in always)
    for a, b, c in zip(never, always, usual, strict=True):
        assert a.vertices.tobytes() == b.vertices.tobytes() == c.vertices.tobytes()
        assert a.density == b.density == c.density
        assert a.friction == b.friction == c.friction
    dark_usual = sum("black" in s.tags for s in usual)
    assert 4 <= dark_usual <= 18  # about one in four of 40
    # The default share is not written into the source; another share is, and read back.
    assert "dark" not in random_shape_source(40, SIZE, 3, 31)
    src = random_shape_source(40, SIZE, 3, 31, 0.0)
    assert random_shapes_from_source(src)[5] == never[5]


def test_source_string_names_the_pool() -> None:
    source = random_shape_source(80, SIZE, 3, 31)
    again = random_shapes_from_source(source)
    assert [s.name for s in again] == [s.name for s in POOL]
    assert again[7] == POOL[7]
    with pytest.raises(InvalidArgumentError, match="malformed random-shapes source"):
        random_shapes_from_source("random-shapes:count=3")


@pytest.mark.parametrize(
    ("objects", "key"),
    [
        ({"random_shapes": -1}, "objects.random_shapes"),
        ({"random_shapes": 2.5}, "objects.random_shapes"),
        ({"random_shapes": 3, "random_shape_size": [0.2, 0.1]}, "objects.random_shape_size"),
        ({"random_shapes": 3, "random_shape_size": [0.001, 0.1]}, "objects.random_shape_size"),
        ({"random_shapes": 3, "random_shape_size": [0.05, 2.0]}, "objects.random_shape_size"),
        ({"random_shapes": 3, "random_shape_size": [0.05]}, "objects.random_shape_size"),
        ({"random_shapes": 3, "random_shape_size": [-0.05, 0.1]}, "objects.random_shape_size"),
        ({"random_shape_seed": -2}, "objects.random_shape_seed"),
        ({"random_shape_dark": 1.5}, "objects.random_shape_dark"),
        ({"random_shape_dark": -0.1}, "objects.random_shape_dark"),
    ],
)
def test_bad_settings_name_the_setting(objects: dict, key: str) -> None:
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_config({"objects": objects})


def test_bad_function_arguments_are_refused() -> None:
    with pytest.raises(InvalidArgumentError, match=r"objects\.random_shapes"):
        random_shapes(-1, SIZE)
    with pytest.raises(InvalidArgumentError, match=r"objects\.random_shape_size"):
        random_shape(0, 0, (0.3, 0.2))
    with pytest.raises(InvalidArgumentError, match="seed and index"):
        random_shape(-1, 0, SIZE)
