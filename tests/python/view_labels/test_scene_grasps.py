"""Scene grasp labels: collisions in the scene, approach offsets, visibility, gravity, errors."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
from conftest import translation

import mgn
from mgn.geometry.mesh import make_box, make_cylinder, mass_properties
from mgn.hardware import ParallelJawGripper, SuctionCup
from mgn.pj.labels import PjLabels
from mgn.pj.labels import label_object as pj_label_object
from mgn.pj.sampler import gripper_meshes, pj_wrench_scores
from mgn.scene import Scene, SceneInstance
from mgn.scene.cameras import CameraView, Intrinsics, look_at
from mgn.suction.labels import CUP_BODY_CLEARANCE, SuctionLabels
from mgn.suction.labels import label_object as suction_label_object
from mgn.suction.seal import suction_wrench_scores
from mgn.view_labels.grasps import SceneGraspModel

BOX = (0.04, 0.06, 0.05)
FLOOR = make_box((0.8, 0.8, 0.01))
FLOOR_POSE = translation(0, 0, -0.005)


def pj_labels(p1, closing, approach, width) -> PjLabels:
    n = len(width)
    return PjLabels(
        approach=np.asarray(approach, np.float32).reshape(-1, 3),
        closing=np.asarray(closing, np.float32).reshape(-1, 3),
        p1=np.asarray(p1, np.float32).reshape(-1, 3),
        width=np.asarray(width, np.float32),
        quality_score=np.linspace(0.2, 1.0, n).astype(np.float32),
        score_wrench=np.zeros(n, np.float32),
        quality_score_simulation=np.full(n, 0.5, np.float32),
        point_index=np.arange(n),
        point_score=np.ones(n, np.float32),
        num_points=n,
        num_colliding=0,
    )


def suction_labels(points, approach) -> SuctionLabels:
    n = len(points)
    return SuctionLabels(
        points=np.asarray(points, np.float32).reshape(-1, 3),
        approach=np.asarray(approach, np.float32).reshape(-1, 3),
        score=np.linspace(0.1, 0.9, n).astype(np.float32),
        wrench=np.zeros(n, np.float32),
        reason=np.zeros(n, np.uint8),
        num_candidates=n,
        num_colliding=0,
    )


def across_x() -> PjLabels:
    """Top-down grasp across x of the box: p1 on the -x face, half-way up."""
    return pj_labels([[-0.02, 0, 0]], [[1, 0, 0]], [[0, 0, -1]], [0.04])


def model(objects, pj, suction, **kw) -> SceneGraspModel:
    """objects: list of (mesh, X_WO); mass 0.2 kg at an off-centre com."""
    kw.setdefault("num_threads", 1)
    return SceneGraspModel.from_meshes(
        [m for m, _ in objects],
        np.array([X for _, X in objects]).reshape(-1, 4, 4),
        [0.2] * len(objects),
        np.tile([0.005, -0.01, 0.002], (len(objects), 1)),
        pj,
        suction,
        FLOOR,
        FLOOR_POSE,
        **kw,
    )


def top_down(height: float = 1.0) -> CameraView:
    return CameraView(Intrinsics.mgn_synthetic(), look_at((0, 0, height), (0, 0, 0), (0, 1, 0)))


# ------------------------------------------------------------------------------ collisions


def test_suction_on_the_bottom_face_hits_the_floor_and_on_the_top_face_does_not():
    box = (make_box(BOX), translation(0, 0, 0.025))
    su = suction_labels([[0, 0, 0.025], [0, 0, -0.025]], [[0, 0, -1], [0, 0, 1]])
    m = model([box], [None], [su])
    assert m.suction.colliding.tolist() == [False, True]
    assert m.suction.hit[1, 0] == 0  # the tote, at the grasp
    # Tool pose: same axes as the contact frame, body_height + shaft behind the contact.
    assert np.allclose(m.suction.contact_poses[0][:3, 2], [0, 0, -1])
    # MetaGraspNet: tool origin 2 cm (cup) + 11.21 cm (tool) behind the contact.
    assert np.allclose(m.suction.tool_poses[0][:3, 3], [0, 0, 0.05 + 0.02 + 0.1121], atol=1e-6)
    c = m.collisions("suction")
    assert (c.total, c.colliding, c.by_obstacle) == (2, 1, {"tote": 1})
    assert np.isnan(m.suction.score_simulation).all()
    assert np.allclose(m.suction.score_analytical, su.score)


def test_a_finger_entering_a_neighbour_collides_and_not_once_it_is_removed():
    box = (make_box(BOX), translation(0, 0, 0.025))
    # +x finger at opening min(0.04 + 0.03, 0.08) = 0.07 spans x in [0.035, 0.045].
    neighbour = (make_box(BOX), translation(0.052, 0, 0.025))
    with_n = model([box, neighbour], [across_x(), None], [None, None])
    assert with_n.pj.colliding.tolist() == [True]
    assert with_n.pj.hit[0, 0] == 2
    alone = model([box], [across_x()], [None])
    assert alone.pj.colliding.tolist() == [False]
    assert alone.collisions("pj").at_offset == {0.0: 0, 0.1: 0}
    # Scores are carried over.
    assert alone.pj.score_analytical[0] == pytest.approx(0.2)
    assert alone.pj.score_simulation[0] == pytest.approx(0.5)


def test_the_approach_offset_matters_under_an_overhanging_plate():
    box = (make_box(BOX), translation(0, 0, 0.025))
    # The tool reaches 0.23 m at the grasp and 0.33 m 100 mm back; the plate is at 0.245-0.255.
    plate = (make_box((0.2, 0.2, 0.01)), translation(0, 0, 0.25))
    su = suction_labels([[0, 0, 0.025]], [[0, 0, -1]])
    m = model([box, plate], [None, None], [su, None])
    assert m.suction.hit.tolist() == [[-1, 2]]
    assert m.suction.colliding.tolist() == [True]
    assert model([box, plate], [None, None], [su, None], offsets=(0.0,)).suction.colliding[0] == 0


def _fcl_object(mesh, X) -> fcl.CollisionObject:
    bvh = fcl.BVHModel()
    bvh.beginModel(len(mesh.vertices), len(mesh.faces))
    bvh.addSubModel(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int32))
    bvh.endModel()
    return fcl.CollisionObject(bvh, fcl.Transform(X[:3, :3], X[:3, 3]))


def _fcl_hits(parts, obstacles) -> bool:
    for mesh, X in parts:
        a = _fcl_object(mesh, X)
        for b in obstacles:
            if fcl.collide(a, b, fcl.CollisionRequest(), fcl.CollisionResult()) > 0:
                return True
    return False


def _back(X: np.ndarray, d: float) -> np.ndarray:
    Y = X.copy()
    Y[:3, 3] -= d * X[:3, 2]
    return Y


def _builtin_scene(names: list[str]) -> Scene:
    """Objects resting on the tote floor side by side (hand-made poses, no simulation)."""
    from mgn.objects import get_object

    instances = []
    xs = np.linspace(-0.1, 0.1, len(names))
    for i, name in enumerate(names):
        spec = get_object(name)
        X = translation(xs[i], 0.02 * (-1) ** i, -float(np.min(spec.vertices[:, 2])) + 1e-4)
        instances.append(SceneInstance(i + 1, name, spec.category_id, "builtin", X))
    return Scene(instances=tuple(instances), tote=mgn.objects.ToteSpec(), seed=0)


@pytest.fixture(scope="module")
def real_scene():
    names = sorted(mgn.objects.object_names())[:3]
    scene = _builtin_scene(names)
    pj, su = [], []
    for i in range(len(names)):
        mesh = scene.mesh(i)
        props = mass_properties(mesh, scene.object_spec(i).density)
        kw = {"mass": props.mass, "com": props.center_of_mass, "seed": i, "num_threads": 2}
        pj.append(pj_label_object(mesh, num_points=40, **kw))
        su.append(suction_label_object(mesh, num_points=40, **kw))
    return scene, pj, su


def test_collisions_agree_with_python_fcl_on_a_real_scene(real_scene):
    scene, pj, su = real_scene
    # approach_step 1 m: only the listed offsets are checked, each compared with FCL here (the
    # path between them is tested in test_approach_path.py).
    m = SceneGraspModel(scene, pj, su, num_threads=2, approach_step=1.0)
    assert len(m.pj) == sum(len(p) for p in pj) > 0
    from mgn.objects import tote_mesh

    n = len(scene.instances)
    obstacles = [_fcl_object(scene.mesh(i), scene.instances[i].X_WO) for i in range(n)]
    obstacles.append(_fcl_object(tote_mesh(scene.tote), np.eye(4)))
    g = ParallelJawGripper()
    rng = np.random.default_rng(0)
    for r in rng.choice(len(m.pj), size=min(40, len(m.pj)), replace=False):
        palm, left, right = gripper_meshes(g, g.collision_opening(float(m.pj.width[r])))
        own = int(m.pj.object_id[r])
        for k, d in enumerate(m.offsets):
            X = _back(m.pj.tool_poses[r], d)
            others = [o for j, o in enumerate(obstacles) if not (d == 0.0 and j == own)]
            expected = _fcl_hits([(palm, X), (left, X), (right, X)], others)
            assert (m.pj.hit[r, k] >= 0) == expected, (r, k)
    cup = SuctionCup()
    body = cup.body_height - CUP_BODY_CLEARANCE
    tool = [
        (
            make_cylinder(cup.outer_radius, body, 32),
            translation(0, 0, -CUP_BODY_CLEARANCE - body / 2),
        ),
        (make_cylinder(0.015, 0.15, 32), translation(0, 0, -cup.body_height - 0.075)),
    ]
    num_colliding = 0
    for r in rng.choice(len(m.suction), size=min(40, len(m.suction)), replace=False):
        for k, d in enumerate(m.offsets):
            X = _back(m.suction.contact_poses[r], d)
            expected = _fcl_hits([(mesh, X @ T) for mesh, T in tool], obstacles)
            assert (m.suction.hit[r, k] >= 0) == expected, (r, k)
            num_colliding += expected
    assert num_colliding > 0  # suction points under the objects hit the floor


def test_first_collision_only_keeps_the_labels_and_skips_the_later_offsets(real_scene):
    scene, pj, su = real_scene
    offsets = (0.0, 0.03, 0.1)
    full = SceneGraspModel(scene, pj, su, offsets=offsets, num_threads=2)
    for threads in (1, 2):
        first = SceneGraspModel(
            scene, pj, su, offsets=offsets, num_threads=threads, first_collision_only=True
        )
        for kind in ("pj", "suction"):
            a, b = getattr(full, kind), getattr(first, kind)
            assert np.array_equal(a.colliding, b.colliding)
            assert np.array_equal(a.collision_part, b.collision_part)
            assert np.array_equal(a.collision_obstacle, b.collision_obstacle)
            skipped = 0
            for r in range(len(a)):
                hits = np.flatnonzero(a.hit[r] >= 0)
                k = int(hits[0]) if len(hits) else len(offsets) - 1
                assert np.array_equal(a.hit[r, : k + 1], b.hit[r, : k + 1]), (kind, r)
                assert np.all(b.hit[r, k + 1 :] == -2), (kind, r)
                skipped += len(offsets) - 1 - k
            assert skipped > 0, kind  # some grasp collides before the last offset
    assert not full.pj.colliding.all() or not full.suction.colliding.all()


def _contains(mesh, points) -> np.ndarray:
    """Ray parity (Moller-Trumbore on every triangle, one skew direction): inside a closed mesh."""
    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    d = np.array([0.5773, 0.5774, 0.5775])
    e1, e2 = b - a, c - a
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    out = []
    for p in np.asarray(points, np.float64).reshape(-1, 3):
        s = p - a
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ij,ij->i", s, h) / det
            q = np.cross(s, e1)
            v = (q @ d) / det
            t = np.einsum("ij,ij->i", e2, q) / det
        hits = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        out.append(int(hits.sum()) % 2 == 1)
    return np.array(out, bool)


def test_near_miss_hand_poses_agree_with_brute_force_fcl_on_every_pair(real_scene):
    """Hands placed close around the objects (most part boxes overlap an object's box, many
    without contact: the box, oriented-box and k-DOP pre-tests decide those) against python-fcl
    on every part-obstacle pair, plus containment of a part vertex in an object or of an object
    vertex in a part (trimesh)."""
    scene, _, _ = real_scene
    n = len(scene.instances)
    m = SceneGraspModel(scene, [None] * n, [None] * n, offsets=(0.0,), num_threads=2)
    from mgn.objects import tote_mesh

    meshes = [scene.mesh(i) for i in range(n)]
    poses = [scene.instances[i].X_WO for i in range(n)]
    obstacles = [_fcl_object(meshes[i], poses[i]) for i in range(n)]
    obstacles.append(_fcl_object(tote_mesh(scene.tote), np.eye(4)))
    g = ParallelJawGripper()
    rng = np.random.default_rng(7)
    contact_poses, widths = [], []
    for _ in range(300):
        i = int(rng.integers(n))
        centre = poses[i][:3, :3] @ np.asarray(meshes[i].vertices).mean(axis=0) + poses[i][:3, 3]
        u = rng.normal(size=3)
        u[2] = abs(u[2]) + 0.3  # from above: the hand (behind the contact) away from the floor
        X = np.eye(4)
        X[:3, 3] = centre + u / np.linalg.norm(u) * rng.uniform(0.04, 0.1)
        z = centre - X[:3, 3] + rng.normal(size=3) * 0.02
        z = z / np.linalg.norm(z) if np.linalg.norm(z) > 1e-6 else np.array([0.0, 0.0, -1.0])
        x = np.cross(z, rng.normal(size=3))
        x /= np.linalg.norm(x)
        X[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        contact_poses.append(X)
        widths.append(float(rng.uniform(0.0, g.max_opening)))
    got = m.collides("pj", np.array(contact_poses), np.array(widths))
    near_misses = 0
    for r, (X, w) in enumerate(zip(contact_poses, widths, strict=True)):
        X_WH = X.copy()
        X_WH[:3, 3] += X[:3, :3] @ [0.5 * w, 0.0, -g.flange_to_contact]
        parts = gripper_meshes(g, g.collision_opening(w))
        expected = _fcl_hits([(p, X_WH) for p in parts], obstacles)
        for p in parts:
            pv = np.asarray(p.vertices, np.float64) @ X_WH[:3, :3].T + X_WH[:3, 3]
            for mesh, X_WO in zip(meshes, poses, strict=True):
                inv = np.linalg.inv(X_WO)
                if _contains(mesh, pv[:1] @ inv[:3, :3].T + inv[:3, 3]).any():
                    expected = True
                ov = np.asarray(mesh.vertices[:1], np.float64) @ X_WO[:3, :3].T + X_WO[:3, 3]
                if _contains(p, (ov - X_WH[:3, 3]) @ X_WH[:3, :3]).any():
                    expected = True
        assert bool(got.colliding[r]) == expected, r
        if not expected:
            # Some part's world box overlaps some object's world box: a pre-test said clear.
            for p in parts:
                pv = np.asarray(p.vertices, np.float64) @ X_WH[:3, :3].T + X_WH[:3, 3]
                for mesh, X_WO in zip(meshes, poses, strict=True):
                    ov = np.asarray(mesh.vertices, np.float64) @ X_WO[:3, :3].T + X_WO[:3, 3]
                    if np.all(pv.min(0) <= ov.max(0)) and np.all(ov.min(0) <= pv.max(0)):
                        near_misses += 1
    assert 0 < got.colliding.sum() < len(contact_poses)
    assert near_misses >= 30  # pairs the pre-tests or FCL must call clear


def test_view_grasps_of_a_real_scene_are_consistent(real_scene):
    scene, pj, su = real_scene
    m = SceneGraspModel(scene, pj, su, num_threads=2)
    view = top_down(0.8)
    out = m.view_grasps(view, np.ones(len(scene.instances), bool))
    X_CW = np.linalg.inv(view.X_WC)
    for group, want in ((out.non_colliding, False), (out.colliding, True)):
        p = group.paralleljaw
        assert np.all(m.pj.colliding[p.index] == want)
        assert np.allclose(p.franka_poses, X_CW @ m.pj.tool_poses[p.index])
        assert np.allclose(p.contact_poses, X_CW @ m.pj.contact_poses[p.index])
        assert np.array_equal(p.object_id, m.pj.object_id[p.index])
        s = group.suctioncup
        assert np.allclose(s.suction_poses, X_CW @ m.suction.tool_poses[s.index])
    kept = len(out.non_colliding.suctioncup) + len(out.colliding.suctioncup)
    # Seen from above: some suction contacts (top faces) are kept, those underneath are not.
    assert 0 < kept < len(m.suction)
    paths = out.datasets()
    assert paths["colliding_grasps/suctioncup/object_id"].dtype == np.int32
    # 7 parallel-jaw and 6 suction datasets per group, plus why each colliding grasp collides.
    assert len(paths) == 2 * (7 + 6) + 2 * 2
    assert paths["colliding_grasps/paralleljaw/collision_part"].dtype == np.uint8
    # Nothing seen: nothing kept.
    none = m.view_grasps(view, np.zeros(len(scene.instances), bool))
    assert len(none.non_colliding.paralleljaw) == len(none.colliding.suctioncup) == 0


# ------------------------------------------------------------------------------ visibility


def test_a_contact_hidden_under_another_object_is_not_kept_from_above():
    box = (make_box(BOX), translation(0, 0, 0.025))
    bar = (make_box((0.02, 0.1, 0.01)), translation(0, 0, 0.056))  # over the top face's middle
    su = suction_labels([[0, 0, 0.025], [0.015, 0, 0.025]], [[0, 0, -1], [0, 0, -1]])
    covered = model([box, bar], [None, None], [su, None])
    out = covered.view_grasps(top_down(), [True, True])
    # The off-centre one is kept (its tool shaft touches the bar: in the colliding group).
    assert out.non_colliding.suctioncup.index.tolist() == []
    assert out.colliding.suctioncup.index.tolist() == [1]
    open_ = model([box], [None], [su])
    out = open_.view_grasps(top_down(), [True])
    assert out.non_colliding.suctioncup.index.tolist() == [0, 1]
    # Camera-frame contact: 1 m camera height minus the 5 cm box top.
    assert out.non_colliding.suctioncup.contact_poses[0][2, 3] == pytest.approx(0.95)
    # The visibility test itself: a point inside the box is hidden, one above it is seen.
    assert open_.visible(top_down(), [[0, 0, 0.02], [0, 0, 0.1]]).tolist() == [False, True]


# ------------------------------------------------------------------------------ gravity


def _rotation(axis, angle) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    X = translation(0, 0, 0.2)
    X[:3, :3] = Rotation.from_rotvec(
        np.asarray(axis, float) / np.linalg.norm(axis) * angle
    ).as_matrix()
    return X


@pytest.mark.parametrize(
    ("axis", "angle"), [((1, 0, 0), np.pi), ((0, 1, 0), np.pi / 2), ((0.3, 1, 0.2), 0.7)]
)
def test_wrench_scores_use_the_scene_gravity_in_the_object_frame(axis, angle):
    pj = pj_labels(
        [[-0.02, 0.01, 0.005], [-0.02, -0.02, 0.0]],
        [[1, 0, 0]] * 2,
        [[0, 1, 0], [0, 0, -1]],
        [0.04] * 2,
    )
    su = suction_labels([[0, 0, 0.025], [0.02, 0.01, 0.0]], [[0, 0, -1], [-1, 0, 0]])
    X = _rotation(axis, angle)
    m = model([(make_box(BOX), X)], [pj], [su], offsets=(0.0,))
    g_O = X[:3, :3].T @ [0, 0, -1]
    com = [0.005, -0.01, 0.002]
    kw = {"mass": 0.2, "com": com, "gravity_direction": g_O}
    assert np.array_equal(m.pj.score_wrench, pj_wrench_scores(pj.p1, pj.closing, pj.width, **kw))
    assert np.array_equal(
        m.suction.score_wrench,
        suction_wrench_scores(su.points, su.approach, cup_radius=0.007, **kw),
    )
    if angle == np.pi:  # upside down: gravity +z in the object frame
        assert np.allclose(g_O, [0, 0, 1])


def test_a_side_pose_changes_the_suction_wrench_score():
    su = suction_labels([[0.02, 0.01, 0.0]], [[-1, 0, 0]])
    upright = model([(make_box(BOX), translation(0, 0, 0.2))], [None], [su]).suction.score_wrench
    side = model(
        [(make_box(BOX), _rotation((0, 1, 0), np.pi / 2))], [None], [su]
    ).suction.score_wrench
    assert upright[0] != pytest.approx(side[0], abs=1e-3)


# ------------------------------------------------------------------------------ threads, errors


def test_one_and_two_threads_give_identical_results(real_scene):
    scene, pj, su = real_scene
    a = SceneGraspModel(scene, pj, su, num_threads=1)
    b = SceneGraspModel(scene, pj, su, num_threads=2)
    for kind in ("pj", "suction"):
        pa, pb = getattr(a, kind), getattr(b, kind)
        assert np.array_equal(pa.hit, pb.hit)
        assert np.array_equal(pa.tool_poses, pb.tool_poses)
        assert np.array_equal(pa.score_wrench, pb.score_wrench)


def test_bad_input_is_a_clear_error():
    box = (make_box(BOX), translation(0, 0, 0.025))
    with pytest.raises(mgn.InvalidArgumentError, match="pj_labels has 2 entries; expected one"):
        model([box], [None, None], [None])
    with pytest.raises(mgn.InvalidArgumentError, match="no objects"):
        model([], [], [])
    bad = translation(0, 0, 0.025)
    bad[0, 3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        model([(make_box(BOX), bad)], [None], [None])
    nan_grasp = pj_labels([[np.nan, 0, 0]], [[1, 0, 0]], [[0, 0, -1]], [0.04])
    with pytest.raises(mgn.InvalidArgumentError, match="grasp 0"):
        model([box], [nan_grasp], [None])
    with pytest.raises(mgn.InvalidArgumentError, match="offsets"):
        model([box], [None], [None], offsets=(-0.1,))
    m = model([box], [across_x()], [None])
    with pytest.raises(mgn.InvalidArgumentError, match=r"seen must have shape \(1,\)"):
        m.view_grasps(top_down(), [True, False])
    with pytest.raises(mgn.InvalidArgumentError, match="kind"):
        m.collisions("vacuum")
