"""``mgn eval grasps``: matching, the labels' collision model, precision@k, pixel grasps, errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import mgn
from mgn.eval.grasps import evaluate_grasps, ground_truth_grasps
from mgn.io.scene_json import read_scene_json
from mgn.pipeline.label_scene import LabelOptions
from mgn.view_labels.grasps import SceneGraspModel

GROUP = {"suction": "suctioncup", "paralleljaw": "paralleljaw"}


def _views(root):
    ds = mgn.Dataset(root)
    return [(s, v) for s in ds.scenes() for v in s.views()]


def _model(root, scene_id: int) -> SceneGraspModel:
    """The scene's collision model rebuilt from the dataset, as the evaluation does."""
    from mgn.pipeline.config import Config

    ds = mgn.Dataset(root)
    cfg = Config.from_dict(ds.info["config"])
    scene = read_scene_json(ds.scene(scene_id).folder / "scene.json")
    n = len(scene.instances)
    return SceneGraspModel(
        scene, [None] * n, [None] * n, cfg.gripper, cfg.cup, offsets=LabelOptions().grasp_offsets
    )


def _labels(view, kind: str, colliding: bool = False):
    g = view.grasps(GROUP[kind], colliding=colliding)
    n = len(g.get("object_id", ()))
    poses = np.asarray(g.get("contact_poses_relative_to_camera", np.zeros((0, 4, 4))), np.float64)
    return g, poses.reshape(n, 4, 4)


def _pose_ok(X: np.ndarray) -> np.ndarray:
    Y = X.copy()
    u, _, vt = np.linalg.svd(Y[:3, :3])
    Y[:3, :3] = u @ vt
    return Y


# --------------------------------------------------------------------------------------------
# The collision query: same model, same answer


@pytest.mark.parametrize("kind", ["suction", "paralleljaw"])
def test_rebuilt_model_reproduces_the_stored_collision_groups(small_dataset, kind):
    """Every stored label of every view, checked again by the model rebuilt from scene.json: the
    non-colliding group is free and the colliding group collides (labels' semantics: the
    target is skipped at offset 0 for parallel-jaw grasps)."""
    core = "pj" if kind == "paralleljaw" else "suction"
    counts = [0, 0]
    for scene, view in _views(small_dataset):
        model = _model(small_dataset, scene.scene_id)
        X_WC = _pose_ok(view.X_WC)
        for colliding in (False, True):
            g, X = _labels(view, kind, colliding)
            if len(X) == 0:
                continue
            X_W = X_WC[None] @ np.array([_pose_ok(x) for x in X])
            w = g.get("contact_width", np.zeros(len(X)))
            r = model.collides(core, X_W, w, g["object_id"].astype(int))
            assert (r.colliding == colliding).all(), (scene, view, colliding)
            counts[colliding] += len(X)
    assert counts[0] > 20, counts  # both groups are exercised
    assert counts[1] > 20, counts


def test_collides_matches_the_placed_labels_and_finds_a_pose_inside_an_object(small_dataset):
    """On a model with object labels (the small dataset's scene 0 and tiny label sets), the
    query reproduces the constructor's flags and first hits exactly; a suction tool placed at
    the centre of another object collides with that object."""
    model = _model(small_dataset, 0)
    scene = read_scene_json(mgn.Dataset(small_dataset).scene(0).folder / "scene.json")
    n = len(scene.instances)
    rng = np.random.default_rng(3)
    from mgn.pj.labels import PjLabels
    from mgn.suction.labels import SuctionLabels

    pj, su = [], []
    for _ in range(n):
        m = 40
        v = rng.normal(size=(m, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        a = rng.normal(size=(m, 3))
        a -= (a * v).sum(1, keepdims=True) * v
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        w = rng.uniform(0, 0.07, m).astype(np.float32)
        p1 = rng.uniform(-0.05, 0.05, (m, 3))
        pj.append(
            PjLabels(
                approach=a.astype(np.float32),
                closing=v.astype(np.float32),
                p1=p1.astype(np.float32),
                width=w,
                quality_score=np.ones(m, np.float32),
                score_wrench=np.zeros(m, np.float32),
                quality_score_simulation=np.ones(m, np.float32),
                point_index=np.arange(m),
                point_score=np.ones(m, np.float32),
                num_points=m,
                num_colliding=0,
            )
        )
        pts = rng.uniform(-0.05, 0.05, (m, 3)).astype(np.float32)
        su.append(
            SuctionLabels(
                points=pts,
                approach=a.astype(np.float32),
                score=np.ones(m, np.float32),
                wrench=np.zeros(m, np.float32),
                reason=np.zeros(m, np.uint8),
                num_candidates=m,
                num_colliding=0,
            )
        )
    # approach_step=1.0: only the listed offsets, so that random grasps through the objects'
    # centres leave some collision-free (the whole-approach sweep blocks them all).
    labelled = SceneGraspModel(
        scene,
        pj,
        su,
        model.gripper,
        model.cup,
        offsets=LabelOptions().grasp_offsets,
        approach_step=1.0,
        num_threads=2,
    )
    for core, p in (("pj", labelled.pj), ("suction", labelled.suction)):
        r = labelled.collides(core, p.contact_poses, p.width, p.object_id)
        np.testing.assert_array_equal(r.colliding, p.colliding)
        np.testing.assert_array_equal(r.hit, p.hit)
        assert 0 < p.colliding.sum() < len(p)
    # Tool at the centre of object 1's bounding box (inside: boxes and cans), approach down.
    V = np.asarray(scene.mesh(1).vertices, np.float64)
    centre = scene.instances[1].X_WO @ np.append(0.5 * (V.min(0) + V.max(0)), 1.0)
    X = np.diag([1.0, -1.0, -1.0, 1.0])
    X[:3, 3] = centre[:3]
    r = model.collides("suction", X[None])
    assert r.colliding[0]
    assert r.hit[0, 0] == 2
    # The same tool 0.5 m above the tote collides with nothing.
    X[:3, 3] = (0.0, 0.0, 0.7)
    assert not model.collides("suction", X[None]).colliding[0]


def test_collides_bad_input(small_dataset):
    model = _model(small_dataset, 0)
    X = np.eye(4)[None]
    with pytest.raises(ValueError, match="kind must be"):
        model.collides("vacuum", X)
    with pytest.raises(ValueError, match="need width"):
        model.collides("pj", X)
    with pytest.raises(ValueError, match="width"):
        model.collides("pj", X, [0.5])
    with pytest.raises(ValueError, match="target_object"):
        model.collides("suction", X, target_object=[99])
    bad = X.copy()
    bad[0, 0, 0] = 2.0
    with pytest.raises(ValueError, match="proper rotation"):
        model.collides("suction", bad)


# --------------------------------------------------------------------------------------------
# Ground truth as predictions


@pytest.mark.parametrize("kind", ["suction", "paralleljaw"])
def test_ground_truth_gives_precision_one_at_every_threshold_it_allows(small_dataset, kind):
    tested = 0
    for t in (0.0, 0.2, 0.4, 0.6, 0.8):
        preds = [e for e in ground_truth_grasps(small_dataset, kind, min_score=t) if e["grasps"]]
        if not preds:
            continue
        res = evaluate_grasps(small_dataset, preds, kind=kind, thresholds=(t,), ks=(1, 5, 50))
        assert res.num_predictions == sum(len(e["grasps"]) for e in preds)
        assert res.matched == res.num_predictions
        assert res.rejected_by_collision == 0
        assert res.precision[t] == {1: 1.0, 5: 1.0, 50: 1.0}
        assert res.success_rate[t] == 1.0
        tested += 1
    assert tested >= 3


def test_ground_truth_with_low_scores_is_ranked_below_the_threshold(small_dataset):
    """All labels submitted: a label below the threshold is a failure; precision@1 counts
    only the best-scored grasp of each view."""
    preds = [e for e in ground_truth_grasps(small_dataset, "suction") if e["grasps"]]
    res = evaluate_grasps(small_dataset, preds, kind="suction", thresholds=(0.0, 0.6), ks=(1,))
    all_scores = np.concatenate([[g["score"] for g in e["grasps"]] for e in preds])
    assert res.success_rate[0.0] == 1.0
    assert res.success_rate[0.6] == pytest.approx((all_scores >= 0.6).mean())
    assert res.below_threshold[0.6] == int((all_scores < 0.6).sum())
    best = [max(g["score"] for g in e["grasps"]) for e in preds]
    assert res.precision[0.6][1] == pytest.approx(np.mean([b >= 0.6 for b in best]))


# --------------------------------------------------------------------------------------------
# Known errors


def _view_with_suction(root, need: int = 2):
    for scene, view in _views(root):
        g, X = _labels(view, "suction")
        s = np.asarray(g.get("score_analytical", ()), np.float64)
        good = np.flatnonzero(np.isfinite(s))
        if len(good) >= need and len(set(np.round(s[good], 3))) >= 2:
            _, Xc = _labels(view, "suction", colliding=True)
            if len(Xc):
                return scene, view, g, X, s, Xc
    raise AssertionError("the small dataset has no view with suction labels in both groups")


def test_known_errors_give_the_hand_computed_precision(small_dataset):
    scene, view, _g, X, s, Xc = _view_with_suction(small_dataset)
    image_id = scene.scene_id * 1000 + view.index
    # Two labels with different scores: a (higher), b (lower).
    order = np.argsort(-s, kind="stable")
    ia = order[0]
    ib = next(i for i in order if s[i] < s[ia] and np.isfinite(s[i]))
    _, Xall = _labels(view, "suction")
    allc = np.concatenate([Xall[:, :3, 3], Xc[:, :3, 3]])
    # A label moved 5 cm away from every label (checked), along one of a few directions.
    far = None
    for d in np.array([[0, 0, -1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], float):
        Y = X[ia].copy()
        Y[:3, 3] += 0.05 * d
        if np.linalg.norm(allc - Y[:3, 3], axis=1).min() > 0.02:
            far = Y
            break
    assert far is not None
    # A label pushed 8 mm into its own object along the approach: still matches (8 mm < 10 mm),
    # but the cup body (3 mm behind the lip) is now inside the object.
    inside = X[ib].copy()
    inside[:3, 3] += 0.008 * inside[:3, 2]
    preds = [
        {
            "image_id": image_id,
            "kind": "suction",
            "grasps": [
                {"pose": X[ia].tolist(), "score": 0.9},  # success
                {"pose": far.tolist(), "score": 0.8},  # unmatched
                {"pose": X[ib].tolist(), "score": 0.3},  # success
                {"pose": inside.tolist(), "score": 0.95},  # matched, colliding
            ],
        }
    ]
    t_mid = float(0.5 * (s[ia] + s[ib]))
    res = evaluate_grasps(
        small_dataset, preds, kind="suction", ks=(1, 2, 3, 4, 10), thresholds=(0.0, t_mid)
    )
    # Ranked by score: inside (fail), a (ok), far (fail), b (ok at 0 only).
    assert res.precision[0.0] == pytest.approx({1: 0.0, 2: 0.5, 3: 1 / 3, 4: 0.5, 10: 0.5})
    assert res.precision[t_mid] == pytest.approx({1: 0.0, 2: 0.5, 3: 1 / 3, 4: 0.25, 10: 0.25})
    assert res.views_short == {1: 0, 2: 0, 3: 0, 4: 0, 10: 1}
    assert (res.num_predictions, res.matched) == (4, 3)
    assert (res.rejected_by_matching, res.rejected_by_collision) == (1, 1)
    assert res.below_threshold == {0.0: 0, t_mid: 1}
    # A label of the colliding group matches itself and is rejected by collision.
    res = evaluate_grasps(
        small_dataset,
        [
            {
                "image_id": image_id,
                "kind": "suction",
                "grasps": [{"pose": Xc[0].tolist(), "score": 1.0}],
            }
        ],
        thresholds=(0.0,),
        ks=(1,),
    )
    assert (res.matched, res.rejected_by_collision, res.precision[0.0][1]) == (1, 1, 0.0)
    # JSON and table.
    d = res.to_dict()
    assert d["precision"]["0.0"]["P@1"] == 0.0
    assert d["rejected_by_collision"] == 1
    assert "P@1" in res.table()
    assert "suction" in res.table()


def test_tolerances_decide_the_match(small_dataset):
    scene, view, _g, X, s, _ = _view_with_suction(small_dataset)
    image_id = scene.scene_id * 1000 + view.index
    _, Xall = _labels(view, "suction")
    # Tilt a label's approach by 20 deg about its x axis: matches at 30 deg, not at 15 deg
    # unless another label is closer (checked against all labels).
    i = int(np.flatnonzero(np.isfinite(s))[0])
    c, sn = math.cos(math.radians(20)), math.sin(math.radians(20))
    Y = X[i].copy()
    Y[:3, :3] = Y[:3, :3] @ np.array([[1, 0, 0], [0, c, -sn], [0, sn, c]])
    pred = [
        {"image_id": image_id, "kind": "suction", "grasps": [{"pose": Y.tolist(), "score": 1.0}]}
    ]
    assert evaluate_grasps(small_dataset, pred, thresholds=(0.0,), ks=(1,)).matched == 1
    ang = np.degrees(np.arccos(np.clip(Xall[:, :3, 2] @ Y[:3, 2], -1, 1)))
    dist = np.linalg.norm(Xall[:, :3, 3] - Y[:3, 3], axis=1)
    expect = int(((ang <= 15) & (dist <= 0.01)).any())
    r = evaluate_grasps(
        small_dataset, pred, thresholds=(0.0,), ks=(1,), match_angle=math.radians(15)
    )
    assert r.matched == expect


# --------------------------------------------------------------------------------------------
# Pixel predictions and symmetry


def _project(K, p):
    return K.fx * p[0] / p[2] + K.cx, K.fy * p[1] / p[2] + K.cy


def test_suction_pixel_predictions_at_label_contacts_match(small_dataset):
    preds, expected = [], 0
    for scene, view in _views(small_dataset):
        g, X = _labels(view, "suction")
        K, depth, inst = view.intrinsics, view.depth_ideal, view.instances
        grasps = []
        for j, x in enumerate(X):
            u, v = _project(K, x[:3, 3])
            c, r = int(u), int(v)
            if not (2 <= c < K.width - 2 and 2 <= r < K.height - 2):
                continue
            win = inst[r - 2 : r + 3, c - 2 : c + 3]
            # Interior of the object's visible region, on the surface seen at that pixel.
            if (win != g["object_id"][j] + 1).any() or abs(depth[r, c] - x[2, 3]) > 0.003:
                continue
            # ... on a flat patch (the 5 x 5 pixels lie within 1 mm of the label's tangent
            # plane) that faces the camera (approach within 60 deg of the viewing ray): the
            # cases where a normal from depth pixels can be right.
            rows, cols = np.mgrid[r - 2 : r + 3, c - 2 : c + 3]
            z = depth[r - 2 : r + 3, c - 2 : c + 3].astype(np.float64)
            q = np.stack([(cols + 0.5 - K.cx) / K.fx * z, (rows + 0.5 - K.cy) / K.fy * z, z], -1)
            a = x[:3, 2]
            if np.abs((q - x[:3, 3]) @ a).max() > 0.001:
                continue
            if a @ x[:3, 3] / np.linalg.norm(x[:3, 3]) < math.cos(math.radians(60)):
                continue
            grasps.append({"uv": [u, v], "score": 1.0})
        expected += len(grasps)
        if grasps:
            preds.append(
                {
                    "image_id": scene.scene_id * 1000 + view.index,
                    "kind": "suction",
                    "grasps": grasps,
                }
            )
    assert expected >= 10
    res = evaluate_grasps(small_dataset, preds, thresholds=(0.0,), ks=(1,))
    assert res.num_predictions == expected
    assert res.matched == expected
    # Background pixels (instance 0: nothing but the tote) match no object label.
    scene, view = _views(small_dataset)[0]
    rr, cc = np.nonzero(view.instances == 0)
    far = [
        {"uv": [float(c) + 0.5, float(r) + 0.5], "score": 1.0}
        for r, c in zip(rr[:5], cc[:5], strict=True)
    ]
    res = evaluate_grasps(
        small_dataset,
        [{"image_id": scene.scene_id * 1000 + view.index, "kind": "suction", "grasps": far}],
        ks=(1,),
    )
    assert res.matched == 0
    assert res.rejected_by_matching == len(far)


def test_paralleljaw_pixel_predictions_at_label_centres_match(small_dataset):
    preds, expected = [], 0
    for scene, view in _views(small_dataset):
        K, depth = view.intrinsics, view.depth_ideal
        grasps = []
        for colliding in (False, True):  # predictions are matched against both label groups
            g, X = _labels(view, "paralleljaw", colliding=colliding)
            for j, x in enumerate(X):
                a, v, w = x[:3, 2], x[:3, 0], float(g["contact_width"][j])
                if a[2] < math.cos(math.radians(10)):  # nearly top-down in this camera only
                    continue
                centre = x[:3, 3] + 0.5 * w * v
                u, vv = _project(K, centre)
                c, r = int(u), int(vv)
                if not (0 <= c < K.width and 0 <= r < K.height) or not np.isfinite(depth[r, c]):
                    continue
                grasps.append(
                    {
                        "uv": [u, vv],
                        "angle": math.atan2(v[1], v[0]),
                        "width": w,
                        "depth": float(centre[2] - depth[r, c]),
                        "score": 1.0,
                    }
                )
        expected += len(grasps)
        if grasps:
            preds.append(
                {
                    "image_id": scene.scene_id * 1000 + view.index,
                    "kind": "paralleljaw",
                    "grasps": grasps,
                }
            )
    assert expected >= 5
    res = evaluate_grasps(small_dataset, preds, kind="paralleljaw", thresholds=(0.0,), ks=(1,))
    assert res.matched == expected


def test_paralleljaw_with_swapped_jaws_matches_the_same_label(small_dataset):
    preds = [
        e for e in ground_truth_grasps(small_dataset, "paralleljaw", min_score=0.2) if e["grasps"]
    ]
    swapped = []
    for e in preds:
        gs = []
        for g in e["grasps"]:
            X = np.asarray(g["pose"])
            Y = X @ np.diag([-1.0, -1.0, 1.0, 1.0])  # 180 deg about the approach
            Y[:3, 3] = X[:3, 3] + g["width"] * X[:3, 0]  # origin at the other contact
            gs.append({**g, "pose": Y.tolist()})
        swapped.append({**e, "grasps": gs})
    a = evaluate_grasps(small_dataset, preds, kind="paralleljaw", thresholds=(0.2,), ks=(1, 10))
    b = evaluate_grasps(small_dataset, swapped, kind="paralleljaw", thresholds=(0.2,), ks=(1, 10))
    assert b.matched == a.matched == a.num_predictions
    assert b.precision == a.precision == {0.2: {1: 1.0, 10: 1.0}}
    # Without the symmetry (p1 moved to the other jaw but the frame kept) nothing matches
    # whenever the width exceeds the tolerance.
    wide = [{**e, "grasps": [g for g in e["grasps"] if g["width"] > 0.025]} for e in preds]
    wide = [e for e in wide if e["grasps"]]
    shifted = [
        {
            **e,
            "grasps": [
                {
                    **g,
                    "pose": (
                        np.asarray(g["pose"])
                        @ np.array(
                            [[1, 0, 0, g["width"]], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]
                        )
                    ).tolist(),
                }
                for g in e["grasps"]
            ],
        }
        for e in wide
    ]
    if wide:
        r = evaluate_grasps(small_dataset, shifted, kind="paralleljaw", ks=(1,))
        assert r.matched == 0


# --------------------------------------------------------------------------------------------
# Errors and CLI


def _one(small_dataset, **grasp):
    scene, view = _views(small_dataset)[0]
    return [{"image_id": scene.scene_id * 1000 + view.index, "kind": "suction", "grasps": [grasp]}]


def test_bad_input_gives_clear_errors(small_dataset, tmp_path):
    ok = {"pose": np.eye(4).tolist(), "score": 1.0}
    with pytest.raises(ValueError, match="unknown image_id 99000"):
        evaluate_grasps(small_dataset, [{"image_id": 99000, "kind": "suction", "grasps": [ok]}])
    with pytest.raises(ValueError, match="unknown image_id 77"):
        evaluate_grasps(small_dataset, [{"image_id": 77, "kind": "suction", "grasps": [ok]}])
    with pytest.raises(ValueError, match="kind must be 'suction' or 'paralleljaw'"):
        evaluate_grasps(small_dataset, [{"image_id": 0, "kind": "vacuum", "grasps": [ok]}])
    with pytest.raises(ValueError, match="no 'paralleljaw' predictions"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok), kind="paralleljaw")
    with pytest.raises(ValueError, match="score: expected a finite number"):
        evaluate_grasps(small_dataset, _one(small_dataset, pose=ok["pose"], score=math.nan))
    nan_pose = np.eye(4)
    nan_pose[0, 3] = math.nan
    with pytest.raises(ValueError, match="NaN"):
        evaluate_grasps(small_dataset, _one(small_dataset, pose=nan_pose.tolist(), score=1.0))
    skew = np.eye(4)
    skew[0, 1] = 0.2
    with pytest.raises(ValueError, match="orthonormal"):
        evaluate_grasps(small_dataset, _one(small_dataset, pose=skew.tolist(), score=1.0))
    with pytest.raises(ValueError, match="belong to parallel-jaw"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok, width=0.02))
    with pytest.raises(ValueError, match="exactly one of 'pose'"):
        evaluate_grasps(small_dataset, _one(small_dataset, score=1.0))
    with pytest.raises(ValueError, match=r"uv\[0\]"):
        evaluate_grasps(small_dataset, _one(small_dataset, uv=[1e4, 3.0], score=1.0))
    pj = _one(small_dataset, **ok)
    pj[0]["kind"] = "paralleljaw"
    with pytest.raises(ValueError, match="needs 'width'"):
        evaluate_grasps(small_dataset, pj, kind="paralleljaw")
    pj[0]["grasps"][0]["width"] = 0.5
    with pytest.raises(ValueError, match=r"width: expected a finite number in \[0.0, 0.08"):
        evaluate_grasps(small_dataset, pj, kind="paralleljaw")
    with pytest.raises(ValueError, match="second 'suction' entry"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok) * 2)
    with pytest.raises(ValueError, match="ks must be"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok), ks=(0,))
    with pytest.raises(ValueError, match="thresholds must be"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok), thresholds=(1.5,))
    with pytest.raises(ValueError, match="label_score 'simulation' does not exist"):
        evaluate_grasps(small_dataset, _one(small_dataset, **ok), label_score="simulation")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="not readable JSON"):
        evaluate_grasps(small_dataset, bad)
    with pytest.raises(OSError, match="does not exist"):
        evaluate_grasps(small_dataset, tmp_path / "missing.json")


def test_cli_prints_the_table_and_writes_json(small_dataset, tmp_path, capsys):
    from mgn.cli.main import main

    preds = [e for e in ground_truth_grasps(small_dataset, "suction", min_score=0.4) if e["grasps"]]
    pred_path = tmp_path / "pred.json"
    pred_path.write_text(json.dumps(preds))
    out = tmp_path / "res.json"
    code = main(
        [
            "eval",
            "grasps",
            str(pred_path),
            "--dataset",
            str(small_dataset),
            "--out",
            str(out),
            "--k",
            "1",
            "5",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "P@1" in text
    assert "P@5" in text
    assert "0.4" in text
    doc = json.loads(out.read_text())
    assert doc["precision"]["0.4"] == {"P@1": 1.0, "P@5": 1.0}
    assert doc["num_predictions"] == sum(len(e["grasps"]) for e in preds)
    assert (
        main(["eval", "grasps", str(tmp_path / "none.json"), "--dataset", str(small_dataset)]) == 1
    )
    assert "does not exist" in capsys.readouterr().err
