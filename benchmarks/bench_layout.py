"""Layout labels: mgn.view_labels.layout.compute_layout against the same rules written with NumPy
and SciPy.

Synthetic view: 20 random overlapping ellipses with a random z order at 1200×1200 (600×600 in
quick mode), rendered with a z-buffer; amodal masks, visible ids, depth and occlusion rates as the
per-view labels give them. The peer is what a user would write in NumPy: one ``bincount`` of the
visible ids under each amodal mask (the seen-over counts), shifted-image comparisons for the
shared boundaries and ``scipy.ndimage.label`` (8-connectivity) per object for completeness.
Agreement: identical relation matrix, edge sizes and region counts. Target: <= 40 ms per view
for mgn at 1200×1200.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .common import PEER_NOT_INSTALLED, Row, measure_alternating, thread_counts

N_OBJECTS = 20
MIN_PX = 10
FRACTION = 0.1


def synthetic_view(size: int, n: int, seed: int = 7) -> dict[str, np.ndarray]:
    """n ellipses of 5-20 % of the image size at random depths: label images of one view."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    amodal = np.zeros((n, size, size), bool)
    visible = np.zeros((size, size), np.int32)
    depth = np.zeros((size, size), np.float32)
    zbuf = np.full((size, size), np.inf, np.float32)
    z = rng.uniform(0.6, 0.9, n).astype(np.float32)
    for i in range(n):
        cy, cx = rng.uniform(0.2 * size, 0.8 * size, 2)
        ay, ax = rng.uniform(0.05 * size, 0.2 * size, 2)
        t = rng.uniform(0, np.pi)
        u = (xx - cx) * np.cos(t) + (yy - cy) * np.sin(t)
        v = -(xx - cx) * np.sin(t) + (yy - cy) * np.cos(t)
        amodal[i] = (u / ax) ** 2 + (v / ay) ** 2 <= 1.0
        closer = amodal[i] & (z[i] < zbuf)
        visible[closer] = i + 1
        zbuf[closer] = z[i]
        depth[closer] = z[i]
    occ = np.array([1.0 - (visible == i + 1).sum() / amodal[i].sum() for i in range(n)])
    return {"visible": visible, "amodal": amodal, "depth": depth, "occlusion": occ}


def load_peer() -> tuple[Any | None, str]:
    try:
        from scipy import ndimage  # optional on purpose
    except ImportError as exc:
        return None, f"{PEER_NOT_INSTALLED} (scipy: {exc})"
    return ndimage, ""


def peer_layout(ndimage: Any, view: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    visible, amodal = view["visible"], view["amodal"]
    n = amodal.shape[0]
    # S[a, b]: pixels of b's amodal mask where a is seen.
    S = np.stack([np.bincount(visible[amodal[b]], minlength=n + 1)[1:] for b in range(n)], 1)
    vis_px = np.bincount(visible.ravel(), minlength=n + 1)[1:]
    both = (vis_px[:, None] > 0) & (vis_px[None, :] > 0)
    occludes = both & (S >= MIN_PX) & (S >= FRACTION * (S + S.T))  # [a, b]: a occludes b
    np.fill_diagonal(occludes, False)
    parent = occludes.T  # [b, a]

    # The parent's own stretch of boundary (cpp/include/mgn/scene/layout.hpp): child pixels p
    # with a 4-neighbour q that shows the parent, lies inside the child's amodal mask and is in
    # front of p (depth(q) < depth(p)).
    def shifted(img: np.ndarray, fill: Any) -> list[np.ndarray]:
        pad = np.pad(img, 1, constant_values=fill)
        return [pad[:-2, 1:-1], pad[2:, 1:-1], pad[1:-1, :-2], pad[1:-1, 2:]]

    depth = view["depth"]
    vis_nb, depth_nb = shifted(visible, 0), shifted(depth, np.inf)
    edge = np.zeros((n, n), np.int64)
    for b, a in np.argwhere(parent):
        child = visible == b + 1
        touch = np.zeros_like(child)
        for nv, nd, na in zip(vis_nb, depth_nb, shifted(amodal[b], False), strict=True):
            touch |= (nv == a + 1) & na & (nd < depth)
        edge[b, a] = int(np.count_nonzero(child & touch))
    regions = np.zeros(n, np.int64)
    for i in np.flatnonzero(vis_px):
        labels, _count = ndimage.label(visible == i + 1, structure=np.ones((3, 3)))
        sizes = np.bincount(labels.ravel())[1:]
        regions[i] = np.count_nonzero(sizes >= max(10, 0.005 * vis_px[i]))
    return {"parent": parent, "edge": edge, "regions": regions}


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
) -> list[Row]:
    size = 600 if quick else 1200
    threads = thread_counts()
    log(f"  layout: {N_OBJECTS} ellipses, {size}x{size}")
    view = synthetic_view(size, N_OBJECTS)
    ndimage, peer_status = load_peer()
    row = Row(
        group="layout",
        case=f"{N_OBJECTS} overlapping ellipses, {size}×{size}, relations + layers + difficulty",
        n=1,
        unit="views/s",
        peer_name="NumPy bincount + shifted images + scipy.ndimage.label",
        mgn_status=mgn_status,
        peer_status=peer_status,
    )
    cases: dict[str, Callable[[], object]] = {}
    if mgn is not None:
        from mgn.view_labels.layout import compute_layout

        cats = np.arange(N_OBJECTS)
        bins = ["no_rel"] * N_OBJECTS
        for t in threads:
            cases[f"mgn/{t}"] = lambda t=t: compute_layout(
                view["visible"],
                view["amodal"],
                view["depth"],
                cats,
                bins,
                occlusion=view["occlusion"],
                num_threads=t,
            )
    if ndimage is not None:
        cases["peer"] = lambda: peer_layout(ndimage, view)
    results = {name: fn() for name, fn in cases.items()}
    timings = measure_alternating(cases, repeats) if cases else {}
    if mgn is not None:
        row.mgn = {t: timings[f"mgn/{t}"] for t in threads}
        for t in threads:
            row.notes.append(f"mgn {t} thread(s): {1000 * timings[f'mgn/{t}'].median:.1f} ms/view")
        a, b = results[f"mgn/{threads[0]}"], results[f"mgn/{threads[-1]}"]
        same = np.array_equal(a.relation, b.relation) and np.array_equal(a.order, b.order)
        row.notes.append(f"relations: {a.parent_ids.size}, difficulty {a.difficulty}")
        row.notes.append("mgn results with 1 and N threads " + ("identical" if same else "DIFFER"))
    if ndimage is not None:
        row.peer = timings["peer"]
        row.notes.append(f"peer: {1000 * timings['peer'].median:.1f} ms/view")
    if mgn is not None and ndimage is not None:
        m, p = results[f"mgn/{threads[-1]}"], results["peer"]
        edge = np.zeros((N_OBJECTS, N_OBJECTS), np.int64)
        edge[m.child_ids - 1, m.parent_ids - 1] = m.edge_size
        checks = {
            "relations": np.array_equal(m.relation == -1, p["parent"]),
            "edge sizes": np.array_equal(edge, p["edge"]),
            "regions": np.array_equal(m.num_regions, p["regions"]),
        }
        row.agreement = ", ".join(f"{k} {'equal' if v else 'DIFFER'}" for k, v in checks.items())
        row.agreement_ok = all(checks.values())
    return [row]


if __name__ == "__main__":
    import sys

    from .common import import_mgn, markdown_table

    mgn_mod, status = import_mgn()
    rows = run(quick=False, repeats=5, mgn=mgn_mod, mgn_status=status, log=print)
    print(markdown_table(rows, thread_counts()))
    for r in rows:
        print("\n".join(r.notes))
    sys.exit(0 if all(r.agreement_ok is not False for r in rows) else 1)
