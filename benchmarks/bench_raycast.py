"""Ray casting: mgn.RayScene against trimesh's Embree intersector (embreex).

Both sides get the same triangles in the same world frame and the same float32 ray arrays. mgn is
timed with 1 thread and with every usable core; the peer as it comes (trimesh's
`RayMeshIntersector` over embreex). The Python-side work each library does around the trace
(trimesh unitises directions and computes hit points with a plane intersection in NumPy; mgn
fills its result arrays in C++) is part of what is measured: it is what a user pays. Each row
times the mgn call that answers the same question as the peer's: `intersect` (distance, point,
normal, ids) against `intersects_location`, `intersect_ids` (ids only, the same ids as
`intersect`'s) against `intersects_first`, `occluded` against `intersects_any`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from .common import (
    PEER_NOT_INSTALLED,
    Row,
    fraction,
    measure_alternating,
    percent,
    thread_counts,
)

DIST_TOL = 1e-4  # metres: hit distances of both sides must agree within this
HIT_AGREEMENT_MIN = 0.999

# ----------------------------------------------------------------------------------------------
# Data sets (metres)


def as_float32_mesh(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh with vertices rounded to float32, mgn's vertex type, so that both sides start
    from bit-identical geometry."""
    vertices = np.asarray(mesh.vertices, np.float32).astype(np.float64)
    return trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=False)


def random_rotation(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n,3,3) rotations, uniform over SO(3) (normalised Gaussian quaternions)."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


class RayDataSet:
    """Meshes with their world poses: `parts[k] = (mesh in its own frame, X_WO)`."""

    def __init__(self, name: str, parts: list[tuple[trimesh.Trimesh, np.ndarray]]):
        self.name = name
        self.parts = parts
        world = [m.copy().apply_transform(X) for m, X in parts]
        # The peer traces one mesh: every instance baked into world coordinates.
        self.world_mesh = trimesh.util.concatenate(world)
        counts = np.array([len(m.faces) for m, _ in parts])
        self.face_offsets = np.concatenate([[0], np.cumsum(counts)])
        self.num_triangles = int(counts.sum())
        self.bounds = self.world_mesh.bounds

    def instance_of_face(self, global_face: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Peer's face index in the concatenated mesh -> (instance index, face in instance)."""
        inst = np.searchsorted(self.face_offsets, global_face, side="right") - 1
        return inst, global_face - self.face_offsets[inst]


def icosphere_data() -> RayDataSet:
    sphere = as_float32_mesh(trimesh.creation.icosphere(subdivisions=6, radius=0.1))  # 81,920 tri
    return RayDataSet(f"icosphere ({len(sphere.faces):,} tri)", [(sphere, np.eye(4))])


def scene_data(rng: np.random.Generator) -> RayDataSet:
    """A tote floor and eight objects (five shapes, some repeated) at random poses above it."""
    ellipsoid = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    ellipsoid.apply_scale([0.08, 0.05, 0.04])
    shapes = {
        "ellipsoid": ellipsoid,
        "torus": trimesh.creation.torus(0.06, 0.02, major_sections=128, minor_sections=64),
        "cylinder": trimesh.creation.cylinder(radius=0.04, height=0.12, sections=512),
        "capsule": trimesh.creation.capsule(height=0.1, radius=0.03, count=[96, 96]),
        "box": trimesh.creation.box(extents=(0.1, 0.07, 0.05)),
    }
    layout = [
        "ellipsoid",
        "ellipsoid",
        "torus",
        "torus",
        "cylinder",
        "capsule",
        "capsule",
        "box",
    ]
    shapes = {k: as_float32_mesh(v) for k, v in shapes.items()}
    floor = as_float32_mesh(trimesh.creation.box(extents=(0.5, 0.4, 0.01)))
    parts = [(floor, _pose(np.eye(3), [0.0, 0.0, -0.005]))]
    rotations = random_rotation(rng, len(layout))
    for name, R in zip(layout, rotations, strict=True):
        p = rng.uniform([-0.17, -0.12, 0.04], [0.17, 0.12, 0.14])
        parts.append((shapes[name], _pose(R, p)))
    data = RayDataSet("", parts)
    data.name = f"scene: floor + 8 objects ({data.num_triangles:,} tri)"
    return data


def _pose(R: np.ndarray, p) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = p
    return X


def random_rays(
    rng: np.random.Generator, bounds: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Origins uniform on a sphere of radius = bbox diagonal (twice the bounding sphere) around
    the bbox centre; directions towards points uniform in the bbox; unit length."""
    lo, hi = bounds
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    u = rng.normal(size=(n, 3))
    origins = centre + radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    targets = rng.uniform(lo, hi, size=(n, 3))
    d = targets - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(d, np.float32)


def camera_rays(bounds: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """A pinhole camera (60° field of view) above the bbox centre looking straight down, framing
    the bbox's larger horizontal side; rays in row-major pixel order through the pixel centres,
    all from the camera centre."""
    lo, hi = bounds
    centre = (lo + hi) / 2
    half_side = 0.5 * float(np.max((hi - lo)[:2]))
    tan_half_fov = np.tan(np.radians(30.0))
    f = 0.5 * width / tan_half_fov
    eye = centre + [0.0, 0.0, 1.05 * half_side / tan_half_fov]
    v, u = np.mgrid[0:height, 0:width]
    # OpenCV camera (x right, y down, z forward) looking along world -z: world = (x, -y, -z).
    dx = (u.ravel() + 0.5 - width / 2) / f
    dy = (v.ravel() + 0.5 - height / 2) / f
    d = np.stack([dx, -dy, -np.ones_like(dx)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    origins = np.broadcast_to(eye, d.shape)
    return np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(d, np.float32)


# ----------------------------------------------------------------------------------------------
# The two sides


def load_peer() -> tuple[Any | None, str]:
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (embreex: {exc})"
    return RayMeshIntersector, ""


def build_mgn_scene(mgn: Any, data: RayDataSet) -> Any:
    # One mgn.Mesh per distinct shape, shared by its instances.
    by_id: dict[int, Any] = {}
    meshes, poses = [], []
    for mesh, X in data.parts:
        if id(mesh) not in by_id:
            by_id[id(mesh)] = mgn.Mesh(
                np.ascontiguousarray(mesh.vertices, np.float32),
                np.ascontiguousarray(mesh.faces, np.int32),
            )
        meshes.append(by_id[id(mesh)])
        poses.append(X)
    return mgn.RayScene(meshes, poses=np.stack(poses))


def peer_first_hits(data: RayDataSet, tri: np.ndarray) -> dict[str, np.ndarray]:
    hit = tri >= 0
    inst, face = data.instance_of_face(np.where(hit, tri, 0))
    return {
        "hit": hit,
        "instance": np.where(hit, inst, -1),
        "face": np.where(hit, face, -1),
    }


def peer_location_hits(
    data: RayDataSet, origins: np.ndarray, result: tuple, n: int
) -> dict[str, np.ndarray]:
    locations, index_ray, index_tri = result
    hit = np.zeros(n, bool)
    hit[index_ray] = True
    tri = np.full(n, -1, np.int64)
    tri[index_ray] = index_tri
    dist = np.full(n, np.inf)
    dist[index_ray] = np.linalg.norm(locations - origins[index_ray].astype(np.float64), axis=1)
    out = peer_first_hits(data, tri)
    out["hit"] = hit
    out["distance"] = dist
    return out


def mgn_hits(h: Any) -> dict[str, np.ndarray]:
    return {
        "hit": np.asarray(h.hit, bool),
        "instance": np.asarray(h.instance_ids),
        "face": np.asarray(h.face_ids),
        "distance": np.asarray(h.distance, np.float64),
    }


def agreement(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> tuple[str, bool]:
    """Hit/miss agreement (the pass criterion), hit distance agreement where both report a
    distance (also a criterion), and the share of common hits on the same triangle (information:
    a ray through a shared edge or vertex may legitimately report either triangle)."""
    hit_ok = fraction(a["hit"] == b["hit"])
    both = a["hit"] & b["hit"]
    parts = [f"hit/miss {percent(hit_ok)}"]
    ok = hit_ok >= HIT_AGREEMENT_MIN
    if "distance" in a and "distance" in b:
        dist_ok = fraction(np.abs(a["distance"][both] - b["distance"][both]) <= DIST_TOL)
        parts.append(f"distance ±{DIST_TOL:g} m {percent(dist_ok)}")
        ok = ok and dist_ok >= HIT_AGREEMENT_MIN
    if "face" in a and "face" in b:
        same = (a["face"][both] == b["face"][both]) & (a["instance"][both] == b["instance"][both])
        parts.append(f"same triangle {percent(fraction(same))}")
    parts.append(f"hit rate {percent(fraction(a['hit']))}")
    return "; ".join(parts), ok


def _same(a: Any, b: Any) -> bool:
    """Whether two mgn results (hit records, id tuples or boolean arrays) are bit-identical."""
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, tuple):
        return all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    ka, kb = mgn_hits(a), mgn_hits(b)
    return all(np.array_equal(ka[k], kb[k]) for k in ka)


def ray_calls(
    mgn_scene: Any | None,
    peer: Any | None,
    origins: np.ndarray,
    directions: np.ndarray,
    coherent: bool,
    threads: list[int],
) -> dict[str, Callable[[], object]]:
    """The timed calls of one ray set, by name."""
    cases: dict[str, Callable[[], object]] = {}
    if mgn_scene is not None:
        for t in threads:
            cases[f"mgn.intersect/{t}"] = lambda t=t: mgn_scene.intersect(
                origins, directions, coherent=coherent, num_threads=t
            )
            cases[f"mgn.intersect_ids/{t}"] = lambda t=t: mgn_scene.intersect_ids(
                origins, directions, coherent=coherent, num_threads=t
            )
            cases[f"mgn.occluded/{t}"] = lambda t=t: mgn_scene.occluded(
                origins, directions, coherent=coherent, num_threads=t
            )
    if peer is not None:
        cases["peer.location"] = lambda: peer.intersects_location(
            origins, directions, multiple_hits=False
        )
        cases["peer.first"] = lambda: peer.intersects_first(origins, directions)
        cases["peer.any"] = lambda: peer.intersects_any(origins, directions)
    return cases


# ----------------------------------------------------------------------------------------------


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    rng = np.random.default_rng(20240611)
    n_random = 200_000 if quick else 1_000_000
    side = 447 if quick else 1000  # 447² = 199,809 rays
    threads = thread_counts()
    Peer, peer_status = load_peer()
    rows: list[Row] = []

    for data in (icosphere_data(), scene_data(rng)):
        ray_sets = [
            (
                f"{n_random:,} random rays",
                *random_rays(rng, data.bounds, n_random),
                False,
            ),
            (f"{side}×{side} camera rays", *camera_rays(data.bounds, side, side), True),
        ]
        mgn_scene = build_mgn_scene(mgn, data) if mgn is not None else None
        peer = Peer(data.world_mesh) if Peer is not None else None

        for rays_name, origins, directions, coherent in ray_sets:
            n = len(origins)
            log(f"  ray casting: {data.name}, {rays_name}")
            cases = ray_calls(mgn_scene, peer, origins, directions, coherent, threads)
            # Warm-up; these results are the ones compared.
            results = {name: fn() for name, fn in cases.items()}
            timings = measure_alternating(cases, repeats) if cases else {}

            m_first = mgn_hits(results[f"mgn.intersect/{threads[-1]}"]) if mgn_scene else None
            same_across_threads = {
                call: all(
                    _same(results[f"mgn.{call}/1"], results[f"mgn.{call}/{t}"]) for t in threads
                )
                for call in ("intersect", "intersect_ids", "occluded")
                if mgn_scene is not None
            }
            specs = [
                (
                    "first hit with distance and point",
                    "intersect",
                    "location",
                    "intersects_location(multiple_hits=False)",
                ),
                ("first hit, triangle index", "intersect_ids", "first", "intersects_first"),
                ("any hit (hit/miss only)", "occluded", "any", "intersects_any"),
            ]
            for query, mgn_call, peer_key, peer_call in specs:
                row = Row(
                    group="ray casting",
                    case=f"{data.name}, {rays_name}, {query}",
                    n=n,
                    unit="rays/s",
                    peer_name=f"RayMeshIntersector.{peer_call}",
                    mgn_status=mgn_status,
                    peer_status=peer_status,
                    limit_work=("embree_coherent" if coherent else "embree_random", 1.0),
                )
                if mgn_scene is not None:
                    row.mgn = {t: timings[f"mgn.{mgn_call}/{t}"] for t in threads}
                    if len(threads) > 1:
                        same = same_across_threads[mgn_call]
                        row.notes.append(
                            f"mgn results with 1 and {threads[-1]} threads "
                            + ("identical" if same else "DIFFER")
                        )
                if peer is not None:
                    row.peer = timings[f"peer.{peer_key}"]
                    row.notes.append(f"peer used {row.peer.cores_used:.2f} cores")
                if peer_key == "any":
                    row.notes.append(
                        "trimesh answers intersects_any with a first-hit trace; "
                        "mgn.occluded uses Embree's any-hit query"
                    )
                if mgn_scene is not None and peer is not None:
                    if peer_key == "location":
                        p = peer_location_hits(data, origins, results["peer.location"], n)
                        row.agreement, row.agreement_ok = agreement(m_first, p)
                    elif peer_key == "first":
                        p = peer_first_hits(data, np.asarray(results["peer.first"]))
                        inst, face = results[f"mgn.intersect_ids/{threads[-1]}"]
                        m = {"hit": inst >= 0, "instance": inst, "face": face}
                        ids_same = all(
                            np.array_equal(a, b)
                            for a, b in zip(
                                (inst, face), (m_first["instance"], m_first["face"]), strict=True
                            )
                        )
                        row.notes.append(
                            "mgn.intersect_ids ids "
                            + ("identical to" if ids_same else "DIFFER from")
                            + " mgn.intersect's"
                        )
                        row.agreement, row.agreement_ok = agreement(m, p)
                    else:
                        m = {"hit": np.asarray(results[f"mgn.occluded/{threads[-1]}"], bool)}
                        p = {"hit": np.asarray(results["peer.any"], bool)}
                        row.agreement, row.agreement_ok = agreement(m, p)
                rows.append(row)
    return rows
