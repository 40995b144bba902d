"""Layout labels (mgn.view_labels.layout.compute_layout) on hand-built label images with known
answers, and against a brute-force NumPy/SciPy re-implementation of the documented rules on random
stacks."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import ndimage

from mgn.errors import InvalidArgumentError
from mgn.io.order_files import read_order_csv, read_order_json
from mgn.view_labels.layout import Layout, compute_layout

# ----------------------------------------------------------------------------------------------
# Synthetic views: shapes at constant depths, rendered with a z-buffer written here.


def render(shapes: list[np.ndarray], z: list[float], H: int, W: int):
    """shapes: (H,W) bool amodal masks; z: depth of each (m). Returns visible, amodal, depth,
    occlusion."""
    n = len(shapes)
    amodal = np.stack(shapes) if n else np.zeros((0, H, W), bool)
    visible = np.zeros((H, W), np.int32)
    depth = np.zeros((H, W), np.float32)
    zbuf = np.full((H, W), np.inf)
    for i in range(n):
        closer = amodal[i] & (z[i] < zbuf)
        visible[closer] = i + 1
        zbuf[closer] = z[i]
        depth[closer] = z[i]
    occ = np.array(
        [1.0 - (visible == i + 1).sum() / max(1, amodal[i].sum()) for i in range(n)], np.float64
    )
    return visible, amodal, depth, occ


def rect(H: int, W: int, r0: int, c0: int, r1: int, c1: int) -> np.ndarray:
    m = np.zeros((H, W), bool)
    m[r0:r1, c0:c1] = True
    return m


def layout_of(shapes, z, H, W, categories=None, **kw) -> Layout:
    visible, amodal, depth, occ = render(shapes, z, H, W)
    n = len(shapes)
    cats = np.arange(1, n + 1) if categories is None else np.asarray(categories)
    return compute_layout(visible, amodal, depth, cats, ["no_rel"] * n, occlusion=occ, **kw)


# ----------------------------------------------------------------------------------------------
# Known answers


def test_side_by_side_rectangles_are_both_top_and_level_1():
    H, W = 40, 60
    L = layout_of([rect(H, W, 5, 5, 25, 25), rect(H, W, 5, 30, 25, 55)], [0.8, 0.8], H, W)
    assert np.array_equal(L.relation, np.zeros((2, 2)))
    assert L.layer.tolist() == [0, 0]
    assert L.difficulty == 1
    assert L.order.tolist() == [1, 2]
    assert L.parent_ids.size == 0


def test_rectangle_on_rectangle():
    H, W = 50, 60
    # A (id 1) at 0.8 m over B (id 2) at 0.9 m on 10 x 10 px.
    L = layout_of([rect(H, W, 20, 20, 40, 30), rect(H, W, 10, 10, 30, 50)], [0.8, 0.9], H, W)
    assert L.relation[1, 0] == -1
    assert L.relation[0, 1] == 1
    assert L.layer.tolist() == [0, 1]
    assert L.parents(2) == [(1, pytest.approx(0.1, abs=1e-6), 30)]
    assert L.children(1) == [(2, pytest.approx(0.1, abs=1e-6), 30)]
    assert L.total_covered_edge.tolist() == [30, 0]  # A covers B along 30 px
    assert L.seen_px.tolist() == [100]
    assert L.order.tolist() == [1, 2]
    assert L.max_occlusion == pytest.approx(0.125)
    assert L.difficulty == 2  # 12.5 % occlusion > 5 %
    assert L.num_layers == 2


def test_paper_example_layers_0_1_3():
    H, W = 80, 80
    shapes = [rect(H, W, 30, 30, 50, 50), rect(H, W, 20, 20, 45, 45), rect(H, W, 10, 10, 70, 70)]
    L = layout_of(shapes, [0.7, 0.8, 0.9], H, W)
    assert L.layer.tolist() == [0, 1, 3]
    assert [p[0] for p in L.parents(3)] == [1, 2]
    assert L.order.tolist() == [1, 2, 3]


def test_split_object_is_incomplete_level_3():
    H, W = 40, 60
    L = layout_of([rect(H, W, 0, 25, 40, 35), rect(H, W, 15, 5, 25, 55)], [0.7, 0.8], H, W)
    assert L.num_regions.tolist() == [1, 2]
    assert L.complete.tolist() == [True, False]
    assert L.difficulty == 3


def test_repeated_class_levels_4_and_5():
    H, W = 40, 60
    side = [rect(H, W, 5, 5, 25, 25), rect(H, W, 5, 30, 25, 55)]
    L = layout_of(side, [0.8, 0.8], H, W, categories=[3, 3])
    assert not L.classes_unique
    assert L.difficulty == 4
    cross = [rect(H, W, 0, 25, 40, 35), rect(H, W, 15, 5, 25, 55)]
    assert layout_of(cross, [0.7, 0.8], H, W, categories=[3, 3]).difficulty == 5


def test_two_cycle_is_interlock():
    # A (rows 10..19, cols 10..29) and B (rows 10..19, cols 20..39) cross in cols 20..29: A
    # rises over B in the top half of the crossing (rows 10..14, depth 0.75 m), B over A in the
    # bottom half; elsewhere both lie at 0.8 m. A's own stretch over B: B's pixels in column 30
    # beside A's raised part (rows 10..14: 5 px, 0.8 - 0.75 = 5 cm); B's over A: A's pixels in
    # column 19, rows 15..19 (5 px, 5 cm). Where the raised parts meet (row 14 / 15) both are at
    # 0.75 m: neither is in front, and no pixel counts for both directions.
    H, W = 40, 60
    a, b = rect(H, W, 10, 10, 20, 30), rect(H, W, 10, 20, 20, 40)
    visible, amodal, depth, _ = render([a, b], [0.8, 0.8], H, W)
    both = a & b
    visible[both] = np.where(np.arange(H)[:, None] < 15, 1, 2).repeat(W, 1)[both]
    depth[both] = 0.75
    occ = np.array([0.3, 0.2])
    L = compute_layout(visible, amodal, depth, [1, 2], ["edge", "corner"], occlusion=occ)
    assert L.relation.tolist() == [[0, -1], [-1, 0]]
    assert L.layer.tolist() == [2, 2]
    assert L.order.tolist() == [2, 1]  # cycle broken at the smaller occlusion
    assert L.bin_relations == ("edge", "corner")
    assert L.parents(1) == [(2, pytest.approx(0.05), 5)]
    assert L.parents(2) == [(1, pytest.approx(0.05), 5)]
    order = L.order_json()
    assert order["1"]["parents"] == [{"id": 2, "depth_diff": pytest.approx(5.0), "edge_size": 5}]


def test_mutual_pair_counts_each_boundary_once_and_drops_a_parent_behind_its_child():
    # B (a bowl rim, rows 10..29 x cols 10..39 at 0.7 m) with A inside it (rows 15..24 x cols
    # 15..34): A hides B's floor (B's amodal mask includes its inside) and B's front rim (rows
    # 25..29 at 0.68 m) hides A's lower part (A's amodal reaches row 29). A at 0.75 m lies
    # in front of B's floor (0.8 m) but behind the rim. Counting the whole boundary for both
    # directions gives B over A the median of A's top and sides (40 px at 0.75 - 0.8 = -5 cm)
    # and the rim (20 px at +7 cm): -5 cm, a parent behind its child. Each direction on its own
    # stretch: A over B beside A's top and sides (+5 cm), B over A along the rim (+7 cm).
    H, W = 40, 50
    vis = np.zeros((H, W), np.int32)
    depth = np.zeros((H, W), np.float32)
    vis[10:30, 10:40] = 2
    depth[10:30, 10:40] = 0.8
    vis[15:25, 15:35] = 1
    depth[15:25, 15:35] = 0.75
    depth[25:30, 10:40] = 0.68  # the front rim
    amodal = np.zeros((2, H, W), bool)
    amodal[0, 15:30, 15:35] = True
    amodal[1, 10:30, 10:40] = True
    occ = np.array([1 - 200 / 300, 1 - (600 - 200) / 600])
    L = compute_layout(vis, amodal, depth, [1, 2], ["no_rel"] * 2, occlusion=occ)
    assert L.relation.tolist() == [[0, -1], [-1, 0]]  # nested: both directions hold
    (a_over_b,) = L.parents(2)
    (b_over_a,) = L.parents(1)
    assert a_over_b[0] == 1
    assert a_over_b[1] == pytest.approx(0.05)
    assert b_over_a[0] == 2
    assert b_over_a[1] == pytest.approx(0.07)
    # A over B: B's pixels beside A's top row (20), its sides (2 x 10) -> 40; B over A: A's
    # bottom row (20).
    assert (a_over_b[2], b_over_a[2]) == (40, 20)
    assert all(dd > 0 for dd in L.depth_diff)
    # Without the rim in front (the rim at the floor's depth), A is in front everywhere it
    # meets B: B hides A's lower part by the masks, but lies behind A on their whole contour,
    # so B is no parent of A.
    depth[25:30, 10:40] = 0.8
    L = compute_layout(vis, amodal, depth, [1, 2], ["no_rel"] * 2, occlusion=occ)
    assert L.relation.tolist() == [[0, 1], [-1, 0]]
    assert L.layer.tolist() == [0, 1]


def test_invisible_object_keeps_its_row():
    H, W = 40, 40
    L = layout_of([rect(H, W, 5, 5, 30, 30), rect(H, W, 10, 10, 20, 20)], [0.7, 0.8], H, W)
    assert L.visible.tolist() == [True, False]
    assert L.layer.tolist() == [0, 3]
    assert L.order.tolist() == [1]
    assert L.relation.shape == (2, 2)
    assert not L.relation.any()
    j = L.order_json()
    assert j["2"]["parents"] == [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}]
    assert L.layout_json()["objects"]["2"]["visible"] is False


# ----------------------------------------------------------------------------------------------
# Serialisation


def stack_layout(seed: int, n: int = 6, H: int = 96, W: int = 96):
    rng = np.random.default_rng(seed)
    shapes, z = [], []
    yy, xx = np.mgrid[0:H, 0:W]
    for _ in range(n):
        if rng.random() < 0.5:
            r0, c0 = rng.integers(0, H - 20, 2)
            h, w = rng.integers(10, 40, 2)
            shapes.append(rect(H, W, r0, c0, r0 + h, c0 + w))
        else:
            cy, cx = rng.uniform(10, H - 10, 2)
            ay, ax = rng.uniform(6, 25, 2)
            shapes.append(((yy - cy) / ay) ** 2 + ((xx - cx) / ax) ** 2 <= 1.0)
        z.append(float(rng.uniform(0.5, 1.0)))
    return shapes, z


def test_order_json_and_csv_agree_and_round_trip(tmp_path):
    H = W = 96
    shapes, z = stack_layout(7, n=8)
    visible, amodal, depth, occ = render(shapes, z, H, W)
    bins = ["no_rel", "edge", "corner", "no_rel", "edge", "no_rel", "no_rel", "corner"]
    L = compute_layout(visible, amodal, depth, np.arange(8), bins, occlusion=occ)
    assert L.parent_ids.size > 0
    (tmp_path / "0_order.json").write_text(json.dumps(L.order_json()))
    (tmp_path / "0_order.csv").write_text(L.order_csv())
    g = read_order_json(tmp_path / "0_order.json")
    m = read_order_csv(tmp_path / "0_order.csv")
    assert np.array_equal(m, g.relation)
    assert np.array_equal(m, L.relation)
    assert np.array_equal(g.layer, L.layer)
    assert np.allclose(g.occlusion, occ, rtol=0, atol=5e-5)  # written to 4 decimals
    assert g.bin_relations == tuple(bins)
    child, parent = L.child_ids - 1, L.parent_ids - 1
    assert np.allclose(g.depth_diff[child, parent], np.nan_to_num(L.depth_diff), atol=1e-8)
    assert np.array_equal(g.edge_size[child, parent], L.edge_size)
    # CSV: only -1 and 0 are written.
    stored = np.loadtxt(tmp_path / "0_order.csv", delimiter=",", ndmin=2)
    assert set(np.unique(stored)) <= {-1.0, 0.0}
    assert np.array_equal(stored == -1, L.relation == -1)
    lj = L.layout_json()
    assert lj["difficulty"] == L.difficulty
    assert lj["order"] == L.order.tolist()
    json.dumps(lj)  # serialisable


def test_order_json_layout_matches_format_md():
    H, W = 50, 60
    L = layout_of([rect(H, W, 20, 20, 40, 30), rect(H, W, 10, 10, 30, 50)], [0.8, 0.9], H, W)
    j = L.order_json()
    assert list(j) == ["1", "2"]
    assert j["1"]["parents"] == [{"id": 0, "depth_diff": 0.0, "edge_size": 0.0}]
    assert j["1"]["children"] == [{"id": 2, "depth_diff": pytest.approx(10.0), "edge_size": 30}]
    assert j["2"]["parents"] == [{"id": 1, "depth_diff": pytest.approx(10.0), "edge_size": 30}]
    assert set(j["2"]) == {
        "id",
        "occlusion",
        "layer",
        "parents",
        "children",
        "total_covered_edge",
        "bin_rel",
    }
    assert L.order_csv() == "0,0\n-1,0\n"


def test_readers_reject_bad_files(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("0,-1\n0\n")
    with pytest.raises(InvalidArgumentError, match="N x N"):
        read_order_csv(p)
    q = tmp_path / "bad.json"
    q.write_text(json.dumps({"1": {"id": 1}}))
    with pytest.raises(InvalidArgumentError, match="occlusion"):
        read_order_json(q)
    with pytest.raises(OSError, match=r"missing\.json"):
        read_order_json(tmp_path / "missing.json")


# ----------------------------------------------------------------------------------------------
# Against a brute-force implementation of the documented rules


def brute_force(visible, amodal, depth, occ, min_px=10, frac=0.1):
    n = amodal.shape[0]
    vis_px = np.array([(visible == i + 1).sum() for i in range(n)])
    S = np.array([[((visible == a + 1) & amodal[b]).sum() for b in range(n)] for a in range(n)])
    parent = np.zeros((n, n), bool)  # parent[b, a]: a occludes b
    for a in range(n):
        for b in range(n):
            if a != b and vis_px[a] and vis_px[b]:
                parent[b, a] = S[a, b] >= min_px and S[a, b] >= frac * (S[a, b] + S[b, a])
    H, W = visible.shape
    edge = {}
    for b, a in np.argwhere(parent):
        # a's own stretch over b: b's pixels beside a pixel of a that lies in b's amodal mask and
        # in front (depths here are all valid where something is seen).
        diffs, count, contour = [], 0, 0
        for r, c in np.argwhere(visible == b + 1):
            nb = [(r + dr, c + dc) for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1))]
            nb = [(y, x) for y, x in nb if 0 <= y < H and 0 <= x < W and visible[y, x] == a + 1]
            nb = [(y, x) for y, x in nb if amodal[b][y, x]]
            contour += bool(nb)
            front = [depth[y, x] for y, x in nb if depth[y, x] < depth[r, c]]
            if front:
                count += 1
                diffs.append(depth[r, c] - np.mean(front))
        if contour and not count:
            parent[b, a] = False  # behind its child wherever they meet
            continue
        edge[(a + 1, b + 1)] = (count, float(np.median(diffs)) if diffs else np.nan)

    # MetaGraspNet's total_covered_edge: the sum of the edge sizes of the object's children.
    covered = [sum(cnt for (a, _b), (cnt, _d) in edge.items() if a == i + 1) for i in range(n)]
    regions = [
        ndimage.label(visible == i + 1, structure=np.ones((3, 3)))[1] if vis_px[i] else 0
        for i in range(n)
    ]
    return parent, edge, regions, covered


@pytest.mark.parametrize("seed", range(12))
def test_random_stacks_match_brute_force_and_order_respects_parents(seed):
    H = W = 64
    shapes, z = stack_layout(seed, n=7, H=H, W=W)
    visible, amodal, depth, occ = render(shapes, z, H, W)
    L = compute_layout(
        visible,
        amodal,
        depth,
        np.arange(7),
        ["no_rel"] * 7,
        occlusion=occ,
        min_region_px=1,
        min_region_fraction=0,
    )
    parent, edge, regions, covered = brute_force(visible, amodal, depth, occ)
    assert np.array_equal(L.relation == -1, parent)
    got = {
        (int(p), int(c)): (int(e), float(d))
        for p, c, e, d in zip(L.parent_ids, L.child_ids, L.edge_size, L.depth_diff, strict=True)
    }
    assert got.keys() == edge.keys()
    for k, (count, dd) in edge.items():
        assert got[k][0] == count
        assert np.isnan(dd) == np.isnan(got[k][1])
        if not np.isnan(dd):
            assert got[k][1] == pytest.approx(dd, abs=1e-6)
            assert dd == pytest.approx(z[k[1] - 1] - z[k[0] - 1], abs=1e-6)  # child - parent
    assert L.num_regions.tolist() == regions
    assert L.total_covered_edge.tolist() == covered
    # Order: every visible object once, each after all its parents (z-order stacks are acyclic).
    vis = np.flatnonzero(L.visible) + 1
    assert sorted(L.order.tolist()) == vis.tolist()
    pos = {int(i): k for k, i in enumerate(L.order)}
    for b, a in np.argwhere(parent):
        assert pos[a + 1] < pos[b + 1]
    # The same result with any number of threads.
    L1 = compute_layout(
        visible,
        amodal,
        depth,
        np.arange(7),
        ["no_rel"] * 7,
        occlusion=occ,
        min_region_px=1,
        min_region_fraction=0,
        num_threads=1,
    )
    assert np.array_equal(L1.relation, L.relation)
    assert np.array_equal(L1.order, L.order)


# ----------------------------------------------------------------------------------------------
# Input checks


def test_zero_and_single_object():
    L0 = compute_layout(
        np.zeros((4, 5), np.int32),
        np.zeros((0, 4, 5), bool),
        np.zeros((4, 5), np.float32),
        [],
        [],
        occlusion=[],
    )
    assert L0.num_objects == 0
    assert L0.order.size == 0
    assert L0.difficulty == 1
    assert L0.order_json() == {}
    assert L0.order_csv() == ""
    L1 = layout_of([rect(10, 10, 2, 2, 8, 8)], [0.8], 10, 10)
    assert L1.layer.tolist() == [0]
    assert L1.order.tolist() == [1]
    assert L1.difficulty == 1


def test_float_ids_as_in_npz_files_are_accepted():
    H, W = 50, 60
    visible, amodal, depth, occ = render(
        [rect(H, W, 20, 20, 40, 30), rect(H, W, 10, 10, 30, 50)], [0.8, 0.9], H, W
    )
    L = compute_layout(
        visible.astype(np.float32), amodal, depth, [1, 2], ["no_rel"] * 2, occlusion=occ
    )
    assert L.relation[1, 0] == -1


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda a: {**a, "visible": a["visible"][:, :-1]}, "amodal: expected shape"),
        (lambda a: {**a, "depth": a["depth"][:-1]}, "depth: expected shape"),
        (lambda a: {**a, "categories": [1]}, "categories"),
        (lambda a: {**a, "occlusion": [0.1]}, "occlusion: expected shape"),
        (lambda a: {**a, "occlusion": [0.1, 1.5]}, r"occlusion\[1\]"),
        (lambda a: {**a, "bin_relations": ["no_rel"]}, "bin_relations"),
        (lambda a: {**a, "bin_relations": ["no_rel", "wall"]}, "unknown values"),
        (lambda a: {**a, "visible": np.where(a["visible"] == 2, 3, a["visible"])}, r"\[0, 2\]"),
        (lambda a: {**a, "visible": a["visible"] - 1}, "ids must be >= 0"),
        (lambda a: {**a, "visible": a["visible"] + 0.5}, "integer instance ids"),
        (lambda a: {**a, "amodal": a["amodal"][0]}, "amodal: expected shape"),
        (lambda a: {**a, "min_overlap_px": 0}, "min_overlap_px"),
        (lambda a: {**a, "num_threads": -2}, "num_threads"),
    ],
)
def test_bad_input_fails_clearly(change, match):
    H, W = 50, 60
    visible, amodal, depth, occ = render(
        [rect(H, W, 20, 20, 40, 30), rect(H, W, 10, 10, 30, 50)], [0.8, 0.9], H, W
    )
    args = {
        "visible": visible,
        "amodal": amodal,
        "depth": depth,
        "categories": [1, 2],
        "bin_relations": ["no_rel", "edge"],
        "occlusion": occ,
    }
    args = change(args)
    with pytest.raises(InvalidArgumentError, match=match):
        compute_layout(**args)


def test_result_is_read_only():
    L = layout_of([rect(10, 10, 2, 2, 8, 8)], [0.8], 10, 10)
    with pytest.raises(ValueError, match="read-only"):
        L.layer[0] = 2
