"""The spring-mass suction seal model (MODELS.md §1) written the straightforward way: NumPy +
trimesh's Embree ray intersector (embreex), the implementation a Python user would otherwise write.

It follows mgn's C++ (cpp/src/grasp/seal_model.cpp) step by step, so that both give the same
answer on the same candidates:

- the ring of N mass points at angles (k + 1/2) 2π/N in the tangent frame of Duff et al. (2017),
  lifted by the approach height, plus the centre; projection rays along -n;
- obstruction (a ray from the lifted ring along +n hits, or the centre ray stops more than h above
  the contact point), hill, hole (the centre ray misses, or a ray of a deterministic 1000-point
  Vogel spiral over the disc misses);
- compression springs k_c (δ - d_k), ring springs to the first, second and opposite neighbour
  (each unordered pair once, equal and opposite forces), the local equilibrium test;
- the on-surface check of the candidates (a ray along the normal within ±1 mm must hit);
- the trial perturbations drawn from mgn's random stream (seed, candidate index), re-implemented
  here (SplitMix64 seeding xoshiro256**, Box-Muller), so both run the very same trials.

NumPy vectorises over the ring (and the disc) of one trial; candidates and trials are a Python
loop. Every batch of rays is cast whole (the checks return early between batches, not inside one);
the rays cast are counted. The rays mgn casts for the same trial are counted too: mgn traces
packets of 16 and stops the obstruction and hole checks at the first packet that decides them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import trimesh

# Failure codes, as in mgn (SealFailure): the order of the checks.
NONE, MISS, OBSTRUCTION, HILL, HOLE, FORCE = range(6)
FAILURE_NAMES = ("none", "miss", "obstruction", "hill", "hole", "force")

PACKET = 16  # mgn casts its parallel rays in Embree packets of 16

# ----------------------------------------------------------------------------------------------
# mgn's random stream (cpp/src/core/rng.cpp): SplitMix64 seeding xoshiro256**, Box-Muller.

_M64 = (1 << 64) - 1


def _mix64(x: int) -> int:
    x = (x + 0x9E3779B97F4A7C15) & _M64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _M64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _M64
    return x ^ (x >> 31)


def _rotl(x: int, k: int) -> int:
    return ((x << k) | (x >> (64 - k))) & _M64


class MgnStream:
    """The random stream mgn gives item `index` of a job seeded with `seed`."""

    def __init__(self, seed: int, index: int):
        x = _mix64(seed & _M64) ^ _mix64((index + 0x632BE59BD9B4E019) & _M64)
        self.s = []
        for _ in range(4):
            x = _mix64(x)
            self.s.append(x)
        if not any(self.s):
            self.s[0] = 1

    def next_u64(self) -> int:
        s0, s1, s2, s3 = self.s
        result = (_rotl((s1 * 5) & _M64, 7) * 9) & _M64
        t = (s1 << 17) & _M64
        s2 ^= s0
        s3 ^= s1
        s1 ^= s2
        s0 ^= s3
        s2 ^= t
        s3 = _rotl(s3, 45)
        self.s = [s0, s1, s2, s3]
        return result

    def uniform(self) -> float:
        return (self.next_u64() >> 11) * 2.0**-53

    def normal(self, mu: float, sigma: float) -> float:
        u1 = 1.0 - self.uniform()
        u2 = self.uniform()
        return mu + sigma * (math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2))


# ----------------------------------------------------------------------------------------------
# Geometry helpers


def tangent_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal u, v with (u, v, n) right-handed (Duff et al. 2017, as mgn)."""
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    u = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    v = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return u, v


def unit_ring(num_points: int) -> np.ndarray:
    """(N + 1, 2): N points on the unit circle at angles (k + 1/2) 2π/N, then the centre."""
    phi = (np.arange(num_points) + 0.5) * 2.0 * np.pi / num_points
    ring = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    return np.vstack([ring, [0.0, 0.0]])


def _spread_bits(v: np.ndarray) -> np.ndarray:
    v = v & 0xFFFF
    v = (v | (v << 8)) & 0x00FF00FF
    v = (v | (v << 4)) & 0x0F0F0F0F
    v = (v | (v << 2)) & 0x33333333
    return (v | (v << 1)) & 0x55555555


def disc_pattern(n: int) -> np.ndarray:
    """(n, 2) points over the unit disc: a Vogel (sunflower) spiral, ordered along a Z-curve
    (Morton code of the coordinates quantised to 16 bits), as mgn's hole check."""
    i = np.arange(n)
    golden = np.pi * (3.0 - np.sqrt(5.0))
    rho = np.sqrt((i + 0.5) / n)
    p = np.stack([rho * np.cos(i * golden), rho * np.sin(i * golden)], axis=1)
    q = ((p + 1.0) * 32767.0).astype(np.uint32).astype(np.uint64)  # truncation, as C++
    key = _spread_bits(q[:, 0]) | (_spread_bits(q[:, 1]) << np.uint64(1))
    return p[np.argsort(key, kind="stable")]


def euler_zyx(ax: float, ay: float, az: float) -> np.ndarray:
    """R = Rz(az) Ry(ay) Rx(ax)."""
    cx, sx, cy, sy, cz, sz = (
        math.cos(ax),
        math.sin(ax),
        math.cos(ay),
        math.sin(ay),
        math.cos(az),
        math.sin(az),
    )
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _packets_until(decided: np.ndarray) -> int:
    """Rays mgn traces before it stops: whole packets of 16 up to and including the packet with
    the first deciding ray, else all of them (valid lanes only)."""
    idx = np.flatnonzero(decided)
    if idx.size == 0:
        return int(decided.size)
    return min(int(decided.size), (int(idx[0]) // PACKET + 1) * PACKET)


# ----------------------------------------------------------------------------------------------


class PeerSealModel:
    """The spring seal model of one mesh (metres) for one cup, NumPy + trimesh + embreex.

    Ring-spring stiffness k_i = E·1e6·π·c2·u / (N·L_i) with L_i in metres and u =
    `ring_length_unit`: 0.01 (default) is mgn's C++ (Cup::ring_stiffness: c2 as MetaGraspNet fitted
    it, with rest lengths in centimetres); 1.0 is the pure-SI formula of MODELS.md §1.

    Attributes updated by every call: `rays_cast` (rays this implementation cast) and
    `mgn_rays` (rays mgn casts for the same trials, given the same ray results).
    """

    def __init__(
        self,
        vertices: np.ndarray,
        faces: np.ndarray,
        *,
        radius: float = 0.007,
        num_points: int = 128,
        youngs_modulus: float = 0.02,
        pressure_difference: float = 0.7,
        compensable_height: float = 0.007,
        approach_height: float = 0.030,
        c1: float = 0.03768,
        c2: float = 0.06241,
        hole_rays: int = 1000,
        ring_length_unit: float = 0.01,
    ):
        from trimesh.ray.ray_pyembree import RayMeshIntersector

        self.mesh = trimesh.Trimesh(
            np.asarray(vertices, np.float64), np.asarray(faces, np.int64), process=False
        )
        self.intersector = RayMeshIntersector(self.mesh)
        self.face_normals = np.asarray(self.mesh.face_normals)
        self.face_origins = np.asarray(self.mesh.triangles[:, 0, :])
        self.r = radius
        self.N = num_points
        self.E = youngs_modulus * 1e6
        self.h = compensable_height
        self.a = approach_height
        self.c2 = c2
        self.ring_length_unit = ring_length_unit
        self.F_p = pressure_difference * 1e5 * math.pi * radius**2
        self.k_c = self.E * math.pi * c1 / num_points
        self.ring = unit_ring(num_points)
        self.disc = disc_pattern(hole_rays)
        self.rays_cast = 0
        self.mgn_rays = 0
        self.trial_mgn_rays: list[tuple[int, int]] = []  # (failure, mgn rays) of every trial

    # -- rays ------------------------------------------------------------------------------

    def _first_hits(self, origins: np.ndarray, directions: np.ndarray):
        """First hits: (hit, distance, face normal); the distance in float64 from the plane of
        the triangle hit. `directions` is one unit vector (parallel rays) or one per ray."""
        directions = np.broadcast_to(directions, origins.shape)
        tri = self.intersector.intersects_first(origins, directions)
        self.rays_cast += len(origins)
        hit = tri >= 0
        face = np.where(hit, tri, 0)
        m = self.face_normals[face]
        along = np.einsum("ij,ij->i", directions, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.einsum("ij,ij->i", self.face_origins[face] - origins, m) / along
        return hit, np.where(hit, t, np.inf), m

    def _any_hit(self, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
        dirs = np.broadcast_to(direction, origins.shape)
        self.rays_cast += len(origins)
        return self.intersector.intersects_any(origins, dirs)

    # -- one trial -------------------------------------------------------------------------

    def trial(self, c: np.ndarray, n: np.ndarray) -> int:
        """Failure code of one deterministic trial at contact point c with unit normal n."""
        failure, rays = self._trial(c, n)
        self.mgn_rays += rays
        self.trial_mgn_rays.append((failure, rays))
        return failure

    def _trial(self, c: np.ndarray, n: np.ndarray) -> tuple[int, int]:
        N, r, h = self.N, self.r, self.h
        u, v = tangent_frame(n)
        base = c + self.a * n
        # 1-2. Ring and centre projected along -n.
        origins = base + r * (self.ring[:, :1] * u + self.ring[:, 1:] * v)
        hit, t, m = self._first_hits(origins, -n)
        rays = N + 1
        if not hit[:N].all():
            return MISS, rays
        x = origins[:N] - t[:N, None] * n
        s = x @ n
        centre_hit = bool(hit[N])
        s_c = base @ n - t[N]

        # 3a. Obstruction: material above the ring, or a roof standing more than h above c.
        up = self._any_hit(origins[:N], n)
        rays += _packets_until(up)
        if up.any():
            return OBSTRUCTION, rays
        if centre_hit and s_c - c @ n > h:
            return OBSTRUCTION, rays
        # 3b. Hill.
        if centre_hit and s_c - s.min() > h:
            return HILL, rays
        # 3c. Hole: the centre and every ray over the disc must hit.
        if not centre_hit:
            return HOLE, rays
        disc = base + r * (self.disc[:, :1] * u + self.disc[:, 1:] * v)
        down = self._any_hit(disc, -n)
        rays += _packets_until(~down)
        if not down.all():
            return HOLE, rays

        # 4. Compression springs: sum_k k_c (delta - d_k) = F_p.
        d = s.max() - s
        delta = (self.F_p / self.k_c + d.sum()) / N
        elastic = self.k_c * (delta - d)

        # 5. Ring springs: neighbour, second neighbour, opposite point; each pair once.
        F = self.ring_forces(x)

        # 6. Local equilibrium: the lip must reach (elastic >= 0) and the ring force along the
        #    surface normal must not beat the elastic force along it.
        m_ring = m[:N]
        lift = np.einsum("ij,ij->i", F, m_ring)
        press = elastic * (m_ring @ n)
        if (elastic < 0.0).any() or (lift > press).any():
            return FORCE, rays
        return NONE, rays

    def ring_forces(self, x: np.ndarray) -> np.ndarray:
        """(N, 3) summed ring-spring forces on the projected ring points x (N, 3), N."""
        N, r = self.N, self.r
        F = np.zeros((N, 3))
        for j in (1, 2, N // 2):
            rest = 2.0 * r * math.sin(math.pi * j / N)
            k_spring = self.E * math.pi * self.c2 * self.ring_length_unit / (N * rest)
            k = np.arange(N // 2 if 2 * j == N else N)
            l = (k + j) % N  # noqa: E741
            chord = x[l] - x[k]
            length = np.linalg.norm(chord, axis=1)
            with np.errstate(divide="ignore", invalid="ignore"):
                f = np.where(
                    (length > 0)[:, None],
                    (k_spring * (length - rest) / length)[:, None] * chord,
                    0.0,
                )
            F[k] += f  # k and l are each free of repeats: plain fancy-index updates suffice
            F[l] -= f
        return F

    def projected_ring(self, c: np.ndarray, n: np.ndarray) -> np.ndarray | None:
        """(N, 3) ring points projected along -n, or None if a ring ray misses (for tests)."""
        u, v = tangent_frame(n)
        base = c + self.a * n
        origins = base + self.r * (self.ring[: self.N, :1] * u + self.ring[: self.N, 1:] * v)
        hit, t, _ = self._first_hits(origins, -n)
        return origins - t[:, None] * n if hit.all() else None

    # -- batch -----------------------------------------------------------------------------

    def check_on_surface(self, points: np.ndarray, normals: np.ndarray, tol: float = 1e-3):
        """Raises ValueError if a candidate has no surface within tol along its normal."""
        o = points + tol * normals
        hit, t, _ = self._first_hits(o, -normals)
        self.mgn_rays += len(points)
        bad = np.flatnonzero(~hit | (t > 2.0 * tol))
        if bad.size:
            raise ValueError(f"candidate {bad[0]} is not on the mesh surface")

    def evaluate(
        self,
        points: np.ndarray,
        normals: np.ndarray,
        *,
        num_trials: int = 10,
        angle_sigma: float = 0.1,
        position_sigma: float | None = None,
        perturb: bool = True,
        seed: int = 0,
        first_index: int = 0,
        indices: Sequence[int] | None = None,
    ) -> dict[str, np.ndarray]:
        """Robust score of candidates (points (N,3) and normals (N,3) as float32, like mgn).

        `indices` are the candidates' indices in mgn's job (their random streams), default
        0..N-1 (+ first_index). Returns score (N,), reason (N,) (most frequent failure of the
        failed trials, ties to the earlier check) and trial_reason (N, T).
        """
        points = np.asarray(points, np.float32)
        normals = np.asarray(normals, np.float32)
        unit = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        self.check_on_surface(points.astype(np.float64), unit.astype(np.float64))
        if indices is None:
            indices = range(len(points))
        T = num_trials if perturb else 1
        pos_sigma = self.r / 4.0 if position_sigma is None else position_sigma
        trial_reason = np.zeros((len(points), T), np.uint8)
        for i, index in enumerate(indices):
            c0 = points[i].astype(np.float64)
            n0 = unit[i].astype(np.float64)
            rng = MgnStream(seed, first_index + int(index))
            for t in range(T):
                c, n = c0, n0
                if perturb:
                    ax = rng.normal(0.0, angle_sigma)
                    ay = rng.normal(0.0, angle_sigma)
                    az = rng.normal(0.0, angle_sigma)
                    n = euler_zyx(ax, ay, az) @ n0
                    n = n / np.linalg.norm(n)
                    jx = rng.normal(0.0, pos_sigma)
                    jy = rng.normal(0.0, pos_sigma)
                    jz = rng.normal(0.0, pos_sigma)
                    c = c0 + np.array([jx, jy, jz])
                trial_reason[i, t] = self.trial(c, n)
        counts = np.stack([(trial_reason == f).sum(axis=1) for f in range(6)], axis=1)
        counts[:, NONE] = 0
        reason = np.where(counts.max(axis=1) > 0, counts.argmax(axis=1), NONE).astype(np.uint8)
        score = (trial_reason == NONE).mean(axis=1).astype(np.float32)
        return {"score": score, "reason": reason, "trial_reason": trial_reason}
