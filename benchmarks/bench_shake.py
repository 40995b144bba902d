"""Physics shake test: mgn.pj.physics.shake_scores against the same trial driven from pybullet.

One trial = one grasp × one (friction, density factor) setting, the full close – translational
shake – rotational shake sequence on mgn's default schedule (``ShakeOptions``: dt 1/400 s, up to
800 + 800 + 600 steps; MetaGraspNet's phases last as long at 1/200 s). mgn runs every trial in
C++ (one small Bullet world each, trials on threads); the peer is the same trial written with
pybullet as a user would: the object as a convex mesh, the two fingers as boxes held by fixed
constraints that follow the hand path, soft pads (contact stiffness and damping), the same
grip-force controller, time step and step counts (read from ``ShakeOptions``) and the same
early-exit rules (settling, lost contact; not the held-load windows, so the peer row runs mgn
with ``hold_tolerance=0``), in a Python loop.

Besides trials/s (mgn's defaults, held-load windows on), the rows report simulated steps/s, the
share of trials that ended early, how many outcomes change when mgn runs the full step counts
(no settle shortcut, no early exit, no held-load window), and trials/s and outcome agreement of
the faster GJK contact mode.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .common import (
    PEER_NOT_INSTALLED,
    Row,
    load_average,
    measure_alternating,
    percent,
    thread_counts,
)

GRIP_FORCE = 20.0
# The peer gets mgn's inertia floor m R^2 and more solver iterations for light objects (see
# cpp/include/mgn/grasp/shake_trial.hpp). It stays in metres (L = 1): pybullet's own Bullet build
# and mesh margins handle centimetre contacts there, and it misses the ball in decimetres.
L = 1.0
# The faster contact mode, measured beside the defaults: GJK contact points gathered over steps
# instead of Bullet's polyhedral clipping (a whole contact patch per step).
GJK = {"polyhedral_contacts": False}
FINGER_MASS = 1.0  # kg; the fingers are dynamic bodies held by fixed constraints
MAX_FORCE = 1e4  # N, force limit of those constraints


def load_peer() -> tuple[Any | None, str]:
    try:
        import pybullet  # optional on purpose
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (pybullet: {exc})"
    return pybullet, ""


def objects(mgn: Any) -> list[tuple[str, Any, float, np.ndarray]]:
    """(name, mesh, mass, inertia): centred shapes, principal axes along x, y, z."""
    out = []
    box = mgn.make_box([0.04, 0.05, 0.06])
    ball = mgn.make_sphere(0.03, 32, 16)
    block = mgn.make_box([0.05, 0.06, 0.08])
    for name, mesh, density in (
        ("box 40x50x60 mm, 60 g", box, 500.0),
        ("ball r=30 mm, 34 g", ball, 300.0),
        ("steel block 50x60x80 mm, 1.9 kg", block, 7800.0),
    ):
        mp = mgn.mass_properties(mesh, density)
        out.append((name, mesh, float(mp.mass), np.asarray(mp.inertia)))
    return out


def grasps_for(width: float, n: int) -> np.ndarray:
    """n grasps [a, v, p1, w] from above, closing along x, at slightly different heights."""
    rows = []
    for i in range(n):
        dz = 0.004 * (i - (n - 1) / 2)
        rows.append([0, 0, -1, 1, 0, 0, -width / 2, 0.0, dz, width])
    return np.asarray(rows, dtype=np.float64)


# ----------------------------------------------------------------------------------------------
# The pybullet peer: the same trial, step by step from Python.


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    x, y, z = axis
    c, s, t = np.cos(angle), np.sin(angle), 1 - np.cos(angle)
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )


def _quat(R: np.ndarray) -> list[float]:
    """(x, y, z, w) of a rotation matrix."""
    w = np.sqrt(max(1e-12, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    return [
        (R[2, 1] - R[1, 2]) / (4 * w),
        (R[0, 2] - R[2, 0]) / (4 * w),
        (R[1, 0] - R[0, 1]) / (4 * w),
        w,
    ]


class PeerTrial:
    """One shake trial in a fresh pybullet world (DIRECT), on the schedule of ``opts`` (mgn's
    ``ShakeOptions``: time step, step counts of each phase, settle and lost-contact counts,
    finger speed limit and the force controller's gain)."""

    def __init__(
        self, pb: Any, gripper: Any, mesh: Any, mass: float, inertia: np.ndarray, opts: Any
    ):
        self.pb, self.g, self.o = pb, gripper, opts
        self.vertices = np.asarray(mesh.vertices, dtype=np.float64)
        radius = float(np.linalg.norm(self.vertices, axis=1).max())
        self.mass = mass
        self.inertia = np.maximum(np.diag(inertia), mass * radius**2)

    def run(self, grasp: np.ndarray, friction: float, density: float, angle: float, phi: float):
        pb = self.pb
        cid = pb.connect(pb.DIRECT)
        try:
            return self._run(cid, grasp, friction, density, angle, phi)
        finally:
            pb.disconnect(cid)

    def _run(self, cid, grasp, friction, density, angle, phi):
        pb, g, o = self.pb, self.g, self.o
        dt = o.dt
        pb.setTimeStep(dt, physicsClientId=cid)
        boost = int(np.clip(np.ceil(GRIP_FORCE / (150 * self.mass * density * 9.81)), 1, 8))
        pb.setPhysicsEngineParameter(numSolverIterations=10 * boost, physicsClientId=cid)
        pb.setGravity(0, 0, 0, physicsClientId=cid)
        a, v, p1, w = grasp[0:3], grasp[3:6], grasp[6:9], grasp[9]
        R_OH = np.stack([v, np.cross(a, v), a], axis=1)
        depth = g.flange_to_tip - g.contact_from_tip
        t_OH = p1 + 0.5 * w * v - depth * a
        R_WH0 = _rot_x(np.pi)
        R_WO = R_WH0 @ R_OH.T
        t_WO = L * (R_WH0 @ (-R_OH.T @ t_OH))
        shape = pb.createCollisionShape(
            pb.GEOM_MESH, vertices=(L * self.vertices).tolist(), physicsClientId=cid
        )
        obj = pb.createMultiBody(
            self.mass * density,
            shape,
            basePosition=t_WO.tolist(),
            baseOrientation=_quat(R_WO),
            physicsClientId=cid,
        )
        pb.changeDynamics(
            obj,
            -1,
            lateralFriction=friction,
            restitution=0.0,
            localInertiaDiagonal=(L * L * self.inertia * density).tolist(),
            physicsClientId=cid,
        )
        f = np.asarray(g.finger_size)
        fz = g.flange_to_tip - 0.5 * f[2]
        box = pb.createCollisionShape(
            pb.GEOM_BOX, halfExtents=(0.5 * f).tolist(), physicsClientId=cid
        )
        d = 0.5 * min(w + g.collision_margin, g.max_opening)

        def finger_pose(R_WH, t_WH, side, dd):
            local = np.array([(-1 if side == 0 else 1) * (dd + 0.5 * f[0]), 0.0, fz])
            return (L * (t_WH + R_WH @ local)).tolist(), _quat(R_WH)

        fingers, cons = [], []
        for side in (0, 1):
            pos, orn = finger_pose(R_WH0, np.zeros(3), side, d)
            b = pb.createMultiBody(
                FINGER_MASS, box, basePosition=pos, baseOrientation=orn, physicsClientId=cid
            )
            pb.changeDynamics(
                b,
                -1,
                lateralFriction=1.0,
                contactStiffness=1e4,
                contactDamping=20.0,
                physicsClientId=cid,
            )
            c = pb.createConstraint(
                b,
                -1,
                -1,
                -1,
                pb.JOINT_FIXED,
                [0, 0, 0],
                [0, 0, 0],
                pos,
                childFrameOrientation=orn,
                physicsClientId=cid,
            )
            pb.changeConstraint(c, pos, orn, maxForce=MAX_FORCE, physicsClientId=cid)
            fingers.append(b)
            cons.append(c)

        def sense():
            touch, force = [False, False], [0.0, 0.0]
            for side in (0, 1):
                for cp in pb.getContactPoints(obj, fingers[side], physicsClientId=cid):
                    if cp[8] < L * 1e-3:
                        touch[side] = True
                    force[side] += cp[9] / L
            return touch, force

        def move(R_WH, t_WH, dd):
            for side in (0, 1):
                pos, orn = finger_pose(R_WH, t_WH, side, dd)
                pb.changeConstraint(cons[side], pos, orn, maxForce=MAX_FORCE, physicsClientId=cid)

        steps, vmax = 0, o.close_speed * dt
        touch, force = [False, False], [0.0, 0.0]
        settled = 0
        gain = o.controller_stiffness  # per 1/400 s: a step dt moves dt * 400/s times as far
        if dt != 1.0 / 400.0:
            gain *= (1.0 / 400.0) / dt
        for _ in range(o.close_steps):  # close, gravity off
            if not any(touch):
                d = max(0.0, d - vmax)
            else:
                d += float(np.clip((0.5 * sum(force) - GRIP_FORCE) / gain, -vmax, vmax))
            move(R_WH0, np.zeros(3), d)
            pb.stepSimulation(physicsClientId=cid)
            steps += 1
            touch, force = sense()
            ok = all(touch) and abs(0.5 * sum(force) - GRIP_FORCE) < 0.05 * GRIP_FORCE
            settled = settled + 1 if ok else 0
            if settled >= o.settle_steps:
                break
            if not any(touch) and d <= 0.0:
                return False, True, steps
        pb.setGravity(0, 0, -9.81 * L, physicsClientId=cid)
        omega_s = 2 * np.pi * o.shake_cycles / (o.shake_steps * dt)
        omega_r = 2 * np.pi * o.rotate_cycles / (o.rotate_steps * dt)
        amp = o.shake_speed / omega_s
        axis = np.array([np.cos(phi), np.sin(phi), 0.0])
        centre = np.array([0.0, 0.0, depth])
        lost = [0, 0]
        for phase, n in ((1, o.shake_steps), (2, o.rotate_steps)):
            for k in range(n):
                t = (k + 1) * dt
                if phase == 1:
                    R_WH, t_WH = R_WH0, R_WH0 @ np.array([0, 0, amp * np.sin(omega_s * t)])
                else:
                    R_HH = _axis_angle(axis, angle * np.sin(omega_r * t))
                    R_WH, t_WH = R_WH0 @ R_HH, R_WH0 @ (centre - R_HH @ centre)
                if any(touch):
                    d += float(np.clip((0.5 * sum(force) - GRIP_FORCE) / gain, -vmax, vmax))
                move(R_WH, t_WH, d)
                pb.stepSimulation(physicsClientId=cid)
                steps += 1
                touch, force = sense()
                lost = [0 if touch[i] else lost[i] + 1 for i in (0, 1)]
                if max(lost) >= o.lost_contact_steps:
                    return False, True, steps
        return all(touch), False, steps


def peer_scores(pb, gripper, mesh, mass, inertia, grasps, frictions, densities, seed_angles, opts):
    trial = PeerTrial(pb, gripper, mesh, mass, inertia, opts)
    out = []
    k = 0
    for grasp in grasps:
        for fr in frictions:
            for de in densities:
                angle, phi = seed_angles[k]
                out.append(trial.run(grasp, fr, de, angle, phi))
                k += 1
    return out


# ----------------------------------------------------------------------------------------------


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    threads = thread_counts()
    pb, peer_status = load_peer()
    rows: list[Row] = []
    if mgn is None:
        return [
            Row(
                group="physics",
                case="shake test",
                n=0,
                unit="trials/s",
                peer_name="pybullet",
                mgn_status=mgn_status,
                peer_status=peer_status,
            )
        ]
    from mgn.hardware import default_gripper

    gripper = default_gripper()
    rng = np.random.default_rng(7)
    for name, mesh, mass, inertia in objects(mgn):
        rows += _object_rows(
            name, mesh, mass, inertia, gripper, rng, pb, peer_status, quick, repeats, threads, log
        )
    return rows


def _object_rows(
    name: str,
    mesh: Any,
    mass: float,
    inertia: np.ndarray,
    gripper: Any,
    rng: np.random.Generator,
    pb: Any | None,
    peer_status: str,
    quick: bool,
    repeats: int,
    threads: list[int],
    log: Callable[[str], None],
) -> list[Row]:
    from mgn.pj.physics import ShakeOptions, shake_scores

    rows: list[Row] = []
    width = float(np.ptp(np.asarray(mesh.vertices)[:, 0]))
    # (a) MetaGraspNet's grid: 5 grasps (quick: 2) x 10 x 10 settings, mgn only.
    n_grasps = 2 if quick else 5
    grasps = grasps_for(width, n_grasps)
    cases = {
        f"mgn/{t}": (
            lambda t=t: shake_scores(
                mesh, mass, np.zeros(3), inertia, grasps, gripper, ShakeOptions(num_threads=t)
            )
        )
        for t in threads
    }
    # The faster contact mode (see GJK): its speed and how many outcomes it changes.
    cases["gjk/1"] = lambda: shake_scores(
        mesh, mass, np.zeros(3), inertia, grasps, gripper, ShakeOptions(num_threads=1, **GJK)
    )
    results = {k: fn() for k, fn in cases.items()}
    timings = measure_alternating(cases, repeats)
    r = results[f"mgn/{threads[-1]}"]
    full = shake_scores(
        mesh,
        mass,
        np.zeros(3),
        inertia,
        grasps,
        gripper,
        ShakeOptions(
            settle_steps=0, lost_contact_steps=0, hold_tolerance=0.0, num_threads=threads[-1]
        ),
    )
    row = Row(
        group="physics",
        case=f"{name}, {n_grasps} grasps x 10x10 settings (MetaGraspNet grid)",
        n=r.num_trials,
        unit="trials/s",
        peer_name="— (mgn only)",
        mgn={t: timings[f"mgn/{t}"] for t in threads},
        peer_status="not run on the full grid (see the next row)",
    )
    steps_rate = r.total_steps / timings[f"mgn/{threads[-1]}"].median
    d = ShakeOptions()
    full_steps = d.close_steps + d.shake_steps + d.rotate_steps
    same = float(np.mean(r.trial_success == full.trial_success))
    t1 = timings["mgn/1"]
    per_cpu_s = r.num_trials / float(np.median(t1.cpu))
    row.notes += [
        f"{per_cpu_s:,.0f} trials per CPU-second with 1 thread (what a free core gives; "
        f"the machine was shared: load average {load_average()})",
        f"{steps_rate:,.0f} simulated steps/s with {threads[-1]} threads; "
        f"{r.total_steps / r.num_trials:.0f} steps per trial (full sequence: {full_steps:,})",
        f"{percent(r.early_fraction)} of trials ended early; scores {np.round(r.score, 2)}",
        f"outcomes equal to the full step counts (no shortcuts): {percent(same)}",
    ]
    gjk = results["gjk/1"]
    gjk_cpu = float(np.median(timings["gjk/1"].cpu))
    row.notes.append(
        f"GJK contacts (ShakeOptions(polyhedral_contacts=False)): {gjk.num_trials / gjk_cpu:,.0f} "
        f"trials per CPU-second with 1 thread ({gjk.num_trials / gjk_cpu / per_cpu_s:.2f}x the "
        f"default); outcomes equal {percent(float(np.mean(gjk.trial_success == r.trial_success)))}"
        f", scores identical {percent(float(np.mean(gjk.score == r.score)))}"
    )
    if len(threads) > 1:
        same_t = np.array_equal(results["mgn/1"].trial_success, r.trial_success)
        row.notes.append(f"1 and {threads[-1]} threads {'identical' if same_t else 'DIFFER'}")
    rows.append(row)
    log(f"  shake: {row.case}")

    # (b) Small grid, mgn against the pybullet trial.
    S = 2 if quick else 3
    g2 = grasps_for(width, 2)
    # The pybullet loop runs the whole schedule (closing until settled, lost-contact exits, no
    # held-load windows), so mgn runs the same: hold_tolerance 0.
    opts = ShakeOptions(grid=S, num_threads=1, hold_tolerance=0.0)
    fr, de = np.linspace(0.5, 2.0, S), np.linspace(0.25, 1.0, S)
    angles = [(rng.uniform(0.2, 0.3), rng.uniform(0, 2 * np.pi)) for _ in range(len(g2) * S * S)]
    cases2: dict[str, Callable[[], object]] = {
        "mgn/1": lambda: shake_scores(mesh, mass, np.zeros(3), inertia, g2, gripper, opts)
    }
    if pb is not None:
        cases2["peer"] = lambda: peer_scores(
            pb, gripper, mesh, mass, inertia, g2, fr, de, angles, opts
        )
    res2 = {k: fn() for k, fn in cases2.items()}
    t2 = measure_alternating(cases2, max(1, min(repeats, 3)))
    row2 = Row(
        group="physics",
        case=f"{name}, 2 grasps x {S}x{S} settings, 1 thread",
        n=len(g2) * S * S,
        unit="trials/s",
        peer_name="the same trial with pybullet (Python loop)",
        mgn={1: t2["mgn/1"]},
        peer=t2.get("peer"),
        peer_status=peer_status,
    )
    m2 = res2["mgn/1"]
    if pb is not None:
        p_ok = np.array([o[0] for o in res2["peer"]])
        p_early = np.array([o[1] for o in res2["peer"]])
        p_steps = sum(o[2] for o in res2["peer"])
        agree = float(np.mean(p_ok == m2.trial_success.reshape(-1)))
        row2.agreement = f"outcome {percent(agree)}"
        row2.notes.append(
            f"pybullet: {p_steps / t2['peer'].median:,.0f} steps/s, "
            f"{percent(float(p_early.mean()))} ended early, success {percent(float(p_ok.mean()))}; "
            f"mgn success {percent(float(m2.trial_success.mean()))}"
        )
    rows.append(row2)
    log(f"  shake: {row2.case}")
    return rows
