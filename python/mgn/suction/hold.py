"""Does a sealed suction cup hold the object through the shake? (docs/models.md §3a)

The suction counterpart of the parallel-jaw shake test (docs/models.md §5): a quasi-static wrench
check of each contact over the same S x S grid of (friction, density factor) settings and under
the same hand motion. The cup points down (the object hangs below it, gravity along the
approach), translates back and forth along its approach axis and then rotates back and forth about
an axis perpendicular to it through the contact, with the accelerations of the shake schedule
(:class:`ShakeLoads`, read from the shake test's defaults). The object is rigid and at rest in the
hand; at every load case the cup must apply the wrench that gives its centre of mass the hand's
acceleration against gravity (and its rotation the hand's angular acceleration):

    f = m (a_com - g),    tau_c = r x f + I alpha + omega x (I omega)

(per contact, contact frame C: z = approach into the surface; r = centre of mass - contact).

The cup's wrench limits (the suction contact model of Mahler et al., Dex-Net 3.0, ICRA 2018):

- vacuum: the lip is pressed on with N = V + f_z >= 0, V = dp * pi * r_cup^2 (the seal model's
  pressure force);
- friction and torsion of the lip ring: the ellipsoidal limit surface
  (|f_t| / (mu N))^2 + (|tau_z| / (mu r_cup N))^2 <= 1 (Dex-Net 3.0 uses the box inscribed in
  it, factors sqrt(3));
- bending: |(tau_x, tau_y)| <= tau_max = k * r_cup * pi * sqrt(2), the limit of the suction
  wrench score (§3).

Every load scales with the mass m (inertia scales with it too), so for each load case and friction
mu the limits give the largest mass held in closed form; a cell (mu_i, density factor d_j) holds
when d_j * m is at most the smallest of them over the load cases. The hold score is the share of
held cells, non-increasing in the density by construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mgn import _core
from mgn.errors import InvalidArgumentError
from mgn.hardware import SuctionCup

_SHAKE = _core.grasp.ShakeOptions()

#: Load cases of the rotational shake: axis directions (in the plane normal to the approach) and
#: phases of the rotation's period; together with the two extremes of the translation.
HOLD_AXES = 16
HOLD_PHASES = 16


@dataclass(frozen=True)
class ShakeLoads:
    """The hand motion of the shake test as loads (defaults: the shake test's, docs/models.md §5).

    Attributes:
        gravity: m/s^2, along the approach while the cup points down.
        translation_acceleration: peak hand acceleration of the translational shake along the
            approach, m/s^2: shake_speed * 2 pi n / T (n cycles in T = shake_steps * dt); 3.14 at
            the defaults.
        rotation_angle: peak angle of the rotational shake, rad: the largest the shake test draws
            (angle_max, 0.3).
        rotation_frequency: angular frequency of the rotational shake, rad/s: 2 pi n / T
            (n cycles in T = rotate_steps * dt); 4.19 at the defaults (peak angular acceleration
            0.3 * 4.19^2 = 5.26 rad/s^2, peak rate 1.26 rad/s).
        friction: the S friction values of the grid (lip against the object surface).
        density: the S density (mass) factors of the grid.
    """

    gravity: float
    translation_acceleration: float
    rotation_angle: float
    rotation_frequency: float
    friction: tuple[float, ...]
    density: tuple[float, ...]

    @classmethod
    def from_shake(
        cls, grid: int = _SHAKE.grid, options: _core.grasp.ShakeOptions | None = None
    ) -> ShakeLoads:
        """The loads of the shake test's schedule (``options``: default the shake test's
        defaults) on a ``grid`` x ``grid`` (friction, density) grid (MetaGraspNet: 10)."""
        o = options if options is not None else _core.grasp.ShakeOptions()
        if not isinstance(grid, int) or isinstance(grid, bool) or grid < 1:
            raise InvalidArgumentError(f"ShakeLoads: grid must be an integer >= 1, got {grid!r}")
        w_t = 2.0 * math.pi * o.shake_cycles / (o.shake_steps * o.dt)
        w_r = 2.0 * math.pi * o.rotate_cycles / (o.rotate_steps * o.dt)
        return cls(
            gravity=float(o.gravity),
            translation_acceleration=float(o.shake_speed * w_t),
            rotation_angle=float(o.angle_max),
            rotation_frequency=float(w_r),
            friction=tuple(float(v) for v in np.linspace(o.friction_min, o.friction_max, grid)),
            density=tuple(float(v) for v in np.linspace(o.density_min, o.density_max, grid)),
        )


def vacuum_force(cup: SuctionCup) -> float:
    """V = dp * 1e5 * pi * r^2, N: the force the vacuum presses the lip on with (10.8 N for the
    default cup)."""
    return float(cup.pressure_difference * 1e5 * math.pi * cup.radius**2)


def bending_limit(cup: SuctionCup) -> float:
    """tau_max = k * r * pi * sqrt(2), N m: the largest bending torque the cup resists (0.485 N m
    for the default cup)."""
    return float(cup.bending_k * cup.radius * math.pi * math.sqrt(2.0))


def frames_z_to(n: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations whose z column is the unit vector n (branch-free basis)."""
    sign = np.where(n[:, 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    u = np.stack([1 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    v = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return np.stack([u, v, n], axis=2)


def contact_frames(approach: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(N, 3, 3) contact frames (columns: axes in the object frame): z = the unit ``approach``,
    x = the part of ``offset`` (centre of mass - contact) normal to it, when that is longer than
    1e-9 m (else the branch-free basis of :func:`frames_z_to`). The rotational load cases are
    placed relative to this x axis, so they do not depend on how the contact was sampled."""
    R = frames_z_to(approach)
    lat = np.einsum("nji,nj->ni", R, offset)[:, :2]  # offset in (x, y) of the basis
    length = np.hypot(lat[:, 0], lat[:, 1])
    ok = length > 1e-9
    cos = np.where(ok, lat[:, 0] / np.where(ok, length, 1.0), 1.0)
    sin = np.where(ok, lat[:, 1] / np.where(ok, length, 1.0), 0.0)
    x = cos[:, None] * R[:, :, 0] + sin[:, None] * R[:, :, 1]
    y = -sin[:, None] * R[:, :, 0] + cos[:, None] * R[:, :, 1]
    return np.stack([x, y, R[:, :, 2]], axis=2)


def load_cases(
    loads: ShakeLoads, axes: int = HOLD_AXES, phases: int = HOLD_PHASES
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The load cases in the contact frame (:func:`contact_frames`: z = approach, gravity +z
    at rest; the cup points down), per kg of object.

    Returns (L = 2 + axes * phases cases): ``g`` (L, 3) gravity in the hand frame (m/s^2),
    ``acc`` (L, 3) the hand's linear acceleration (m/s^2), ``alpha`` (L, 3) its angular
    acceleration (rad/s^2) and ``omega`` (L, 3) its angular velocity (rad/s). Cases 0 and 1:
    the translation's extremes (+-a_T along z); then the rotation theta = tm sin(ph) about the
    axes u at angles 2 pi i / ``axes`` from x, through the contact, at the phases
    ph = 2 pi k / ``phases`` of its period.
    """
    g0 = np.array([0.0, 0.0, loads.gravity])
    at = loads.translation_acceleration
    gs = [g0, g0]
    accs = [np.array([0.0, 0.0, at]), np.array([0.0, 0.0, -at])]
    alphas = [np.zeros(3), np.zeros(3)]
    omegas = [np.zeros(3), np.zeros(3)]
    tm, wr = loads.rotation_angle, loads.rotation_frequency
    for i in range(axes):
        beta = 2.0 * math.pi * i / axes
        u = np.array([math.cos(beta), math.sin(beta), 0.0])
        w = np.cross(u, [0.0, 0.0, 1.0])  # u x z
        for k in range(phases):
            ph = 2.0 * math.pi * k / phases
            theta = tm * math.sin(ph)
            # gravity in the hand frame: z rotated by -theta about u
            gs.append(
                loads.gravity * (math.cos(theta) * np.array([0.0, 0.0, 1.0]) - math.sin(theta) * w)
            )
            accs.append(np.zeros(3))
            alphas.append(-tm * wr * wr * math.sin(ph) * u)
            omegas.append(tm * wr * math.cos(ph) * u)
    return np.array(gs), np.array(accs), np.array(alphas), np.array(omegas)


@dataclass(frozen=True)
class HoldResult:
    """Hold test of N contacts.

    Attributes:
        score: (N,) float32 share of the S x S (friction, density) cells in which the cup holds.
        max_mass: (N, S) float64 the largest object mass held at each friction value, kg.
        held: (N, S, S) bool, [contact, friction index, density index].
    """

    score: npt.NDArray[np.float32]
    max_mass: npt.NDArray[np.float64]
    held: npt.NDArray[np.bool_]


def suction_hold_scores(
    contacts: npt.ArrayLike,
    approach: npt.ArrayLike,
    *,
    mass: float,
    com: npt.ArrayLike,
    inertia: npt.ArrayLike | None = None,
    cup: SuctionCup | None = None,
    loads: ShakeLoads | None = None,
    axes: int = HOLD_AXES,
    phases: int = HOLD_PHASES,
    chunk: int = 512,
) -> HoldResult:
    """Hold score of each contact: see the module docstring. Deterministic.

    Args:
        contacts: (N, 3) contact points, m (object frame).
        approach: (N, 3) unit approach directions into the surface.
        mass: object mass at density factor 1, kg (> 0).
        com: centre of mass, m (object frame).
        inertia: (3, 3) inertia about the centre of mass at density factor 1, kg m^2 (None:
            the rotational inertia terms are left out).
        cup: the cup (default: MetaGraspNet's).
        loads: the shake loads and grid (default: :meth:`ShakeLoads.from_shake`).
        axes, phases: load cases of the rotational shake (>= 1 each).
        chunk: contacts per vectorised block (results do not depend on it).
    """
    cup = cup if cup is not None else SuctionCup()
    loads = loads if loads is not None else ShakeLoads.from_shake()
    c = np.asarray(contacts, np.float64).reshape(-1, 3)
    a = np.asarray(approach, np.float64).reshape(-1, 3)
    if c.shape != a.shape:
        raise InvalidArgumentError(
            f"suction_hold_scores: contacts {c.shape} and approach {a.shape} must have the "
            "same shape (N, 3)"
        )
    if not (np.isfinite(c).all() and np.isfinite(a).all()):
        raise InvalidArgumentError("suction_hold_scores: contacts and approach must be finite")
    norm = np.linalg.norm(a, axis=1)
    if len(a) and (norm.min() < 1e-9):
        raise InvalidArgumentError("suction_hold_scores: approach directions must be non-zero")
    if not (isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0):
        raise InvalidArgumentError(
            f"suction_hold_scores: mass must be a finite number > 0 kg, got {mass!r}"
        )
    com_v = np.asarray(com, np.float64).reshape(3)
    inv_m_inertia = (
        np.zeros((3, 3))
        if inertia is None
        else np.asarray(inertia, np.float64).reshape(3, 3) / mass
    )
    for name, v in (("axes", axes), ("phases", phases), ("chunk", chunk)):
        if not isinstance(v, int) or v < 1:
            raise InvalidArgumentError(
                f"suction_hold_scores: {name} must be an integer >= 1, got {v!r}"
            )
    a = a / norm[:, None]
    g, acc, alpha, omega = load_cases(loads, axes, phases)
    # Per kg: a_com = acc + A r, A = [alpha]x + [omega]x [omega]x; the inertia torque
    # I alpha + omega x (I omega) = M vec(I / m) with
    # M[l, i, 3 j + k] = d_ij alpha_k + [omega]x_ij omega_k.
    wx = _skew(omega)
    A = _skew(alpha) + wx @ wx  # (L, 3, 3)
    b = acc - g  # (L, 3)
    M = np.einsum("ij,lk->lijk", np.eye(3), alpha) + np.einsum("lij,lk->lijk", wx, omega)
    M = M.reshape(len(g), 3, 9)
    mu = np.asarray(loads.friction, np.float64)
    dens = np.asarray(loads.density, np.float64)
    V = vacuum_force(cup)
    tau_b = bending_limit(cup)
    n = len(c)
    max_mass = np.empty((n, len(mu)), np.float64)
    for s in range(0, n, chunk):
        R = contact_frames(a[s : s + chunk], com_v[None, :] - c[s : s + chunk])
        r = np.einsum("nji,nj->ni", R, com_v[None, :] - c[s : s + chunk])  # (n, 3) in C
        J = np.einsum("nji,jk,nkl->nil", R, inv_m_inertia, R).reshape(-1, 9)  # I/m in C
        phi = np.einsum("lij,nj->nli", A, r) + b[None, :, :]  # force per kg on the object
        psi = np.einsum("lim,nm->nli", M, J)  # torque per kg about the contact: + r x phi
        rx, ry, rz = r[:, None, 0], r[:, None, 1], r[:, None, 2]
        px, py, pz = phi[..., 0], phi[..., 1], phi[..., 2]
        psi[..., 0] += ry * pz - rz * py
        psi[..., 1] += rz * px - rx * pz
        psi[..., 2] += rx * py - ry * px
        max_mass[s : s + chunk] = _max_mass(phi, psi, mu, V, tau_b, cup.radius)
    held = dens[None, None, :] * mass <= max_mass[:, :, None]
    score = held.reshape(n, -1).mean(axis=1).astype(np.float32)
    return HoldResult(score, max_mass, held)


def _skew(v: np.ndarray) -> np.ndarray:
    """(L, 3, 3) cross-product matrices [v]x of (L, 3) vectors."""
    z = np.zeros(len(v))
    return np.stack(
        [
            np.stack([z, -v[:, 2], v[:, 1]], axis=1),
            np.stack([v[:, 2], z, -v[:, 0]], axis=1),
            np.stack([-v[:, 1], v[:, 0], z], axis=1),
        ],
        axis=1,
    )


def _limit(V: float, worst: np.ndarray) -> np.ndarray:
    """V / worst where worst > 0, else inf (no limit)."""
    return np.where(worst > 0, V / np.where(worst > 0, worst, 1.0), np.inf)


def _max_mass(
    phi: np.ndarray, psi: np.ndarray, mu: np.ndarray, V: float, tau_b: float, r_cup: float
) -> np.ndarray:
    """(n, S) largest mass held at each friction: the minimum over the load cases of the three
    limits, each linear in the mass m. phi, psi: (n, L, 3) force and torque per kg.

    vacuum V + m fz >= 0; bending m |(psi_x, psi_y)| <= tau_b; friction and torsion
    m q <= mu (V + m fz) with q = |(phi_x, phi_y, psi_z / r_cup)|. Each is m * w <= V' with a
    per-case w, so the smallest limit over the cases is V' / (the largest w)."""
    fz = phi[..., 2]
    m_vac = _limit(V, (-fz).max(axis=1))
    m_bend = _limit(tau_b, np.hypot(psi[..., 0], psi[..., 1]).max(axis=1))
    q = np.sqrt(phi[..., 0] ** 2 + phi[..., 1] ** 2 + (psi[..., 2] / r_cup) ** 2)
    m_fric = np.stack([_limit(m * V, (q - m * fz).max(axis=1)) for m in mu], axis=1)
    out: np.ndarray = np.minimum(np.minimum(m_vac, m_bend)[:, None], m_fric)
    return out
