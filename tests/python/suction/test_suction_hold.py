"""The suction hold test (docs/models.md §3a) against hand-computed limits and a brute-force
second implementation; the physics score in the object labels, their file and the scene."""

import math

import h5py
import numpy as np
import pytest

import mgn
from mgn.errors import InvalidArgumentError
from mgn.hardware import SuctionCup
from mgn.io.grasp_file import create_labels_file, write_suction_labels
from mgn.objects import get_object
from mgn.suction import label_object
from mgn.suction.hold import (
    HOLD_PHASES,
    ShakeLoads,
    bending_limit,
    suction_hold_scores,
    vacuum_force,
)
from mgn.view_labels.grasps import SceneGraspModel

CUP = SuctionCup()
LOADS = ShakeLoads.from_shake()
G = 9.81


def test_the_loads_are_the_shake_schedules():
    # Translation: 2 cycles in 800 steps of 1/400 s at a peak speed of 0.5 m/s: 0.5 * 2 pi.
    assert LOADS.translation_acceleration == pytest.approx(0.5 * 2 * math.pi)
    # Rotation: one cycle in 600 steps of 1/400 s, up to 0.3 rad.
    assert LOADS.rotation_frequency == pytest.approx(2 * math.pi / 1.5)
    assert LOADS.rotation_angle == 0.3
    assert LOADS.friction == pytest.approx(tuple(np.linspace(0.5, 2.0, 10)))
    assert LOADS.density == pytest.approx(tuple(np.linspace(0.25, 1.0, 10)))
    # The default cup: 0.7 bar on a 7 mm ring; k = 15.6.
    assert vacuum_force(CUP) == pytest.approx(0.7e5 * math.pi * 0.007**2)
    assert bending_limit(CUP) == pytest.approx(15.6 * 0.007 * math.pi * math.sqrt(2))


def top_centre_limit(mu, d, k_lat):
    """Largest mass held at the top centre of an object whose centre of mass lies d below the
    contact and whose lateral inertia per kg is k_lat (m^2), derived by hand.

    Translation: the cup pulls m (g + a_T) along the axis (vacuum and friction both give
    V / (g + a_T)). Rotation by theta = tm sin(ph) about a horizontal axis u: per kg, the lateral
    force is g sin(theta) - tm w^2 d sin(ph), the axial pull g cos(theta) + (tm w cos(ph))^2 d,
    the bending torque d * lateral - k_lat tm w^2 sin(ph); no torsion."""
    V, tb = vacuum_force(CUP), bending_limit(CUP)
    a_t, tm, w = LOADS.translation_acceleration, LOADS.rotation_angle, LOADS.rotation_frequency
    limits = [V / (G + a_t)]
    for k in range(HOLD_PHASES):
        ph = 2 * math.pi * k / HOLD_PHASES
        th = tm * math.sin(ph)
        lateral = G * math.sin(th) - tm * w * w * d * math.sin(ph)
        pull = G * math.cos(th) + (tm * w * math.cos(ph)) ** 2 * d
        bend = abs(d * lateral - k_lat * tm * w * w * math.sin(ph))
        limits.append(V / pull)
        limits.append(mu * V / (abs(lateral) + mu * pull))
        if bend > 0:
            limits.append(tb / bend)
    return min(limits)


@pytest.mark.parametrize("shape", ["cube", "cylinder"])
def test_top_centre_holding_limit_by_hand(shape):
    if shape == "cube":
        s = 0.05
        mass, half = 1.0, s / 2  # 8000 kg/m^3: the vacuum and the lip friction limit it
        k_lat = s * s / 6
        k_ax = k_lat
    else:
        radius, h = 0.03, 0.08
        mass, half = 0.9, h / 2
        k_lat = (3 * radius**2 + h**2) / 12
        k_ax = radius**2 / 2
    inertia = mass * np.diag([k_lat, k_lat, k_ax])
    res = suction_hold_scores(
        [[0, 0, half]], [[0, 0, -1]], mass=mass, com=[0, 0, 0], inertia=inertia
    )
    want = np.array([top_centre_limit(mu, half, k_lat) for mu in LOADS.friction])
    np.testing.assert_allclose(res.max_mass[0], want, rtol=1e-9)
    # At mu = 0.5 the lip slides first; at mu = 2 the vacuum lets go first.
    assert (
        want[0]
        < vacuum_force(CUP) / (G + LOADS.translation_acceleration)
        == pytest.approx(want[-1])
    )
    held = np.array([[d * mass <= m for d in LOADS.density] for m in want])
    np.testing.assert_array_equal(res.held[0], held)
    assert res.score[0] == pytest.approx(held.mean())
    assert 0 < res.score[0] < 1


def test_off_centre_the_bending_torque_exceeds_the_limit():
    # A 40 x 4 x 4 cm bar of 0.8 kg, picked on its top face.
    mass, half = 0.8, 0.02
    ends = [[0.0, 0, half], [0.10, 0, half], [0.19, 0, half]]
    res = suction_hold_scores(ends, [[0, 0, -1]] * 3, mass=mass, com=[0, 0, 0])
    assert res.score[0] > 0.5  # at the centre only the vacuum and the lip friction limit it
    tb = bending_limit(CUP)
    pull = G + LOADS.translation_acceleration
    for i, x in ((1, 0.10), (2, 0.19)):
        # The translation's pull alone bends the cup by m (g + a_T) x.
        assert res.max_mass[i].max() <= tb / (pull * x) * (1 + 1e-12)
    # 0.19 m off: even the lightest cell (0.2 kg) bends the cup past 0.485 N m.
    assert 0.25 * mass * pull * 0.19 > tb
    assert res.score[0] > res.score[1] > 0
    assert res.score[2] == 0.0
    # Without the rotation the bending limit of the translation is exact (no friction load).
    still = ShakeLoads(G, LOADS.translation_acceleration, 0.0, 0.0, LOADS.friction, LOADS.density)
    r = suction_hold_scores(ends[1:2], [[0, 0, -1]], mass=mass, com=[0, 0, 0], loads=still)
    np.testing.assert_allclose(r.max_mass[0], tb / (pull * 0.10), rtol=1e-12)
    want = np.mean([d * mass <= tb / (pull * 0.10) for d in LOADS.density])
    assert r.score[0] == pytest.approx(want)
    assert 0 < want < 1


def test_the_score_falls_with_density_and_rises_with_friction():
    spec = get_object("box_cereal")
    mesh = spec.to_mesh()
    p = mgn.mass_properties(mesh, spec.density)
    s = mgn.sample_surface(mesh, 300, method="even", seed=4)
    previous = None
    for factor in (0.5, 1.0, 2.0, 4.0):
        r = suction_hold_scores(
            s.points,
            -s.normals,
            mass=p.mass * factor,
            com=p.center_of_mass,
            inertia=np.asarray(p.inertia) * factor,
        )
        # Within the grid: fewer held cells at higher density, more at higher friction.
        assert (np.diff(r.held.astype(int), axis=2) <= 0).all()
        assert (np.diff(r.held.astype(int), axis=1) >= 0).all()
        if previous is not None:
            assert (r.score <= previous).all()
        previous = r.score
    assert previous is not None
    assert previous.mean() < 0.2


def brute_force_held(point, approach, mass, com, inertia, loads, axes, phases):
    """The held grid by a second implementation: the hand's motion is written as poses in time,
    the centre of mass's acceleration and the angular momentum's rate come from finite
    differences, and the cup's wrench is tested against the limits inequality by inequality."""
    a = np.asarray(approach, float) / np.linalg.norm(approach)
    # The rotation axes are placed from the centre of mass's lateral offset (x of the frame).
    off = np.asarray(com, float) - point
    x = off - (off @ a) * a
    x /= np.linalg.norm(x)
    Rc = np.stack([x, np.cross(a, x), a], axis=1)
    r = Rc.T @ (np.asarray(com, float) - point)
    Ic = Rc.T @ np.asarray(inertia, float) @ Rc / mass  # per kg
    g_w = np.array([0.0, 0.0, G])
    cases = []  # (force per kg, torque per kg) in the hand frame
    for sign in (1, -1):
        f = sign * loads.translation_acceleration * np.array([0, 0, 1.0]) - g_w
        cases.append((f, np.cross(r, f)))
    tm, w = loads.rotation_angle, loads.rotation_frequency
    h = 1e-4
    for i in range(axes):
        beta = 2 * math.pi * i / axes
        u = np.array([math.cos(beta), math.sin(beta), 0.0])

        def rot(t, u=u):
            th = tm * math.sin(w * t)
            K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
            return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K

        def momentum(t, u=u, rot=rot):
            R = rot(t)
            return R @ Ic @ R.T @ (tm * w * math.cos(w * t) * u)

        for k in range(phases):
            t = 2 * math.pi * k / phases / w
            R = rot(t)
            acc = (rot(t + h) @ r - 2 * R @ r + rot(t - h) @ r) / h**2
            dL = (momentum(t + h) - momentum(t - h)) / (2 * h)
            f_w = acc - g_w
            tau_w = np.cross(R @ r, f_w) + dL
            cases.append((R.T @ f_w, R.T @ tau_w))
    V, tb = vacuum_force(CUP), bending_limit(CUP)
    held = np.zeros((len(loads.friction), len(loads.density)), bool)
    for i, mu in enumerate(loads.friction):
        for j, d in enumerate(loads.density):
            m = d * mass
            ok = True
            for f, tau in cases:
                f, tau = m * f, m * tau
                normal = V + f[2]
                ok &= normal >= 0
                ok &= math.hypot(tau[0], tau[1]) <= tb
                ok &= (math.hypot(f[0], f[1]) / mu) ** 2 + (tau[2] / (mu * CUP.radius)) ** 2 <= (
                    normal**2
                )
            held[i, j] = ok
    return held


def test_the_held_grid_equals_a_brute_force_second_implementation():
    rng = np.random.default_rng(7)
    mass = 0.6
    com = np.array([0.01, -0.02, 0.005])
    A = rng.normal(size=(3, 3))
    inertia = 2e-3 * (A @ A.T + np.eye(3))  # a full, asymmetric inertia
    points = rng.uniform(-0.06, 0.06, (12, 3))
    approach = rng.normal(size=(12, 3))
    res = suction_hold_scores(
        points, approach, mass=mass, com=com, inertia=inertia, axes=6, phases=8
    )
    assert 0.05 < res.score.mean() < 0.95  # the case has both held and dropped cells
    for k in range(len(points)):
        want = brute_force_held(points[k], approach[k], mass, com, inertia, LOADS, 6, 8)
        margin = np.abs(np.asarray(LOADS.density)[None, :] * mass - res.max_mass[k][:, None])
        agree = (res.held[k] == want) | (margin < 1e-6)  # finite differences at the boundary
        assert agree.all(), k


def test_bad_input_names_the_argument():
    with pytest.raises(InvalidArgumentError, match="mass"):
        suction_hold_scores([[0, 0, 0]], [[0, 0, 1]], mass=0.0, com=[0, 0, 0])
    with pytest.raises(InvalidArgumentError, match="same shape"):
        suction_hold_scores([[0, 0, 0]], [[0, 0, 1], [0, 0, 1]], mass=1.0, com=[0, 0, 0])
    with pytest.raises(InvalidArgumentError, match="grid"):
        ShakeLoads.from_shake(0)
    with pytest.raises(InvalidArgumentError, match="bending_k"):
        SuctionCup(bending_k=0.0)


def test_object_labels_carry_the_physics_score_into_the_file_and_the_scene(tmp_path):
    spec = get_object("box_tea")
    mesh = spec.to_mesh()
    p = mgn.mass_properties(mesh, spec.density)
    heavy = p.mass * 8  # a tea box of lead-like density: the cup drops some of it
    lab = label_object(
        mesh,
        mass=heavy,
        com=p.center_of_mass,
        inertia=np.asarray(p.inertia) * 8,
        num_points=300,
        seed=1,
    )
    hold = suction_hold_scores(
        lab.points,
        lab.approach,
        mass=heavy,
        com=p.center_of_mass,
        inertia=np.asarray(p.inertia) * 8,
    )
    assert lab.simulation is not None
    np.testing.assert_array_equal(lab.simulation, lab.score * hold.score)
    assert ((lab.simulation >= 0) & (lab.simulation <= 1)).all()
    assert (lab.simulation[lab.score == 0] == 0).all()  # never sealed: never held
    assert (lab.simulation < lab.score).any()
    assert (lab.simulation == lab.score).any()
    assert lab.metadata["suction_physics"]["grid"] == 10
    # The object file: MetaGraspNet's keys unchanged (its visualize_labels.py reads the seal
    # score, quality_score, for suction), the physics score next to it.
    h5_path = tmp_path / "textured.obj.hdf5"
    create_labels_file(h5_path)
    write_suction_labels(h5_path, lab)
    with h5py.File(h5_path, "r") as h5:
        g = h5["grasps/suctioncup"]
        np.testing.assert_array_equal(g["quality_score"][:], lab.score)
        sim = g["quality_score_simulation"][:]
        assert sim.dtype == np.float32
        assert len(sim) == len(lab.score)
        assert np.isfinite(sim).all()
        assert sim.min() >= 0
        assert sim.max() <= 1
    # The scene: the object's score is carried to its scene grasps, in the label order.
    X = np.eye(4)
    X[2, 3] = 0.2
    floor = mgn.make_box([0.8, 0.8, 0.01])
    model = SceneGraspModel.from_meshes(
        [mesh],
        X[None],
        [heavy],
        [p.center_of_mass],
        [None],
        [lab],
        floor,
        np.eye(4),
        num_threads=1,
    )
    np.testing.assert_array_equal(model.suction.score_simulation, lab.simulation)
    np.testing.assert_array_equal(model.suction.score_analytical, lab.score)


def test_config_dump_shows_the_cups_bending_limit():
    from mgn.pipeline.config import dump_config, load_config

    text = dump_config()
    assert "bending_k: 15.6" in text
    assert "bending limit" in text
    cfg = load_config({"cup": {"bending_k": 20.0}})
    assert cfg.cup.bending_k == 20.0
    assert bending_limit(cfg.cup) == pytest.approx(20.0 * 0.007 * math.pi * math.sqrt(2))
