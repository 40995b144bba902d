"""`mgn suction compare`: the three seal models on the same points, agreement and pictures."""

import json

import numpy as np
import pytest
from PIL import Image

import mgn
from mgn.cli.main import main
from mgn.viz.suction_compare import (
    HIGH,
    LOW,
    compare_models,
    comparison_picture,
    pair_stats,
)


def test_pair_stats_counts_by_hand():
    a = np.array([0.1, 0.1, 0.9, 0.9, 0.5, 0.0])
    b = np.array([0.6, 0.1, 0.2, 0.9, 0.5, 1.0])
    p = pair_stats("a", "b", a, b)
    # a<0.2 with b sealing: points 0 and 5; a>0.8 with b failing: point 2.
    assert (p.low_vs_seal, p.high_vs_no_seal, p.controversial) == (2, 1, 3)
    # Same prediction (>= 0.5) on points 1, 3, 4.
    assert p.agreement == pytest.approx(3 / 6)
    with pytest.raises(ValueError, match="shape"):
        pair_stats("a", "b", a, b[:3])


def test_large_sphere_all_models_agree_everywhere():
    sphere = mgn.make_sphere(0.08, 128, 64)  # far larger than every cup: every model seals
    comp = compare_models(sphere, num_points=80, seed=3)
    for m, s in comp.scores.items():
        assert s.shape == (80,)
        assert np.all(s >= 0.9), m
    assert all(p.agreement == 1.0 and p.controversial == 0 for p in comp.pairs)
    assert not comp.controversial_mask().any()
    assert "controversial points (any pair): 0" in comp.format_table()


def test_mask_is_the_union_of_the_pair_counts():
    # A thin rod: the spring model (ring of 7 mm) fails where the others may differ.
    rod = mgn.make_cylinder(0.012, 0.12, 96)
    comp = compare_models(rod, num_points=120, seed=0)
    assert len(comp.pairs) == 6  # ordered pairs of 3 models
    mask = comp.controversial_mask()
    union = np.zeros(len(mask), bool)
    for p in comp.pairs:
        a, b = comp.scores[p.a], comp.scores[p.b]
        b_seal = b >= comp.seal_threshold
        low, high = (a < LOW) & b_seal, (a > HIGH) & ~b_seal
        assert (int(low.sum()), int(high.sum())) == (p.low_vs_seal, p.high_vs_no_seal)
        union |= low | high
    assert np.array_equal(mask, union)
    # Same seed, same scores.
    again = compare_models(rod, num_points=120, seed=0, num_threads=1)
    for m in comp.scores:
        assert np.array_equal(comp.scores[m], again.scores[m])


def test_picture_shows_green_points_on_a_sealing_sphere():
    sphere = mgn.make_sphere(0.08, 64, 32)
    comp = compare_models(sphere, num_points=60, seed=1)
    img = comparison_picture(sphere, comp, size=160)
    assert img.dtype == np.uint8
    assert img.shape[1] == 4 * 160
    green = (img[..., 1] > 180) & (img[..., 0] < 80) & (img[..., 2] < 80)
    assert green[:, :160].sum() > 50  # spring panel: scored points drawn in green
    magenta = (img[..., 0] > 180) & (img[..., 2] > 180) & (img[..., 1] < 80)
    assert magenta.sum() == 0  # no controversial points


def test_bad_arguments():
    box = mgn.make_box([0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="seal_threshold"):
        compare_models(box, num_points=10, seal_threshold=0.0)
    with pytest.raises(ValueError, match="at least two"):
        compare_models(box, num_points=10, models=("spring",))


def test_cli_writes_table_picture_and_json(tmp_path, capsys):
    stl = tmp_path / "ball.stl"
    import trimesh

    trimesh.creation.icosphere(subdivisions=4, radius=60.0).export(stl)  # mm
    png, js = tmp_path / "cmp.png", tmp_path / "cmp.json"
    args = ["suction", "compare", str(stl), "--scale", "0.001", "--num-points", "50"]
    assert main([*args, "--png", str(png), "--json", str(js)]) == 0
    out = capsys.readouterr().out
    assert "agree %" in out
    assert "controversial points" in out
    with Image.open(png) as im:
        assert im.size[0] == 4 * 360
    doc = json.loads(js.read_text())
    assert set(doc["scores"]) == {"spring", "strain", "smoothness"}
    assert all(len(v) == 50 for v in doc["scores"].values())
    pts = np.asarray(doc["points_m"])
    assert np.allclose(np.linalg.norm(pts, axis=1), 0.06, atol=1e-3)  # metres after --scale


def test_cli_unknown_mesh_names_the_built_in_objects(capsys):
    assert main(["suction", "compare", "no_such_thing"]) != 0
    err = capsys.readouterr().err
    assert "'no_such_thing' is neither a mesh file nor a built-in object" in err
    assert "mug" in err
