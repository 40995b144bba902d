"""Learning baselines (mgn.learn): training step, prediction, and a whole training run (no peer).

- One training step of the default model (small U-Net, width 16, RGB, 256 x 256) on a batch of
  4 views, forward, loss, backward and Adam step: views/s, 1 and all threads.
- One prediction of a 1200 x 1200 photograph (the network at 256 px, the instance extraction,
  the maps brought back to 1200 x 1200): images/s, 1 and all threads.
- Not with --quick: the budget of the learning issue, a 12-scene, 16-view dataset (192 views,
  generated at 0.25 x 1200 px = 300 x 300 px; generation not timed) trained for 10 epochs at
  256 px on all threads: views/s, the whole run's seconds in the notes (target <= 600 s on 2
  cores).

``python -m benchmarks.bench_learn [THREADS]`` runs the whole-run case alone (on THREADS torch
threads, default all cores) and prints its seconds.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import Row, Timing, bench_tempdir, measure_alternating, thread_counts

BATCH = 4
SIZE = 256
#: The whole-run dataset: 12 scenes x 16 views of the default objects, labels kept small.
RUN_SCENES = 12
RUN_EPOCHS = 10
RUN_CONFIG = {
    "camera": {"views": list(range(16)), "resolution_scale": 0.25},
    "object_labels": {
        "suction_points": 300,
        "pj_points": 100,
        "physics_grasps": 3,
        "physics_grid": 2,
    },
}


def _torch() -> Any | None:
    try:
        import torch
    except ImportError:
        return None
    return torch


def whole_run(threads: int, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Generate the 12 x 16 dataset and train the default model 10 epochs on ``threads``."""
    from mgn.learn import ModelConfig, TrainConfig, train
    from mgn.pipeline import generate
    from mgn.pipeline.config import load_config

    root = bench_tempdir("mgn_bench_learn_")
    t0 = time.perf_counter()
    report = generate(
        root / "ds", RUN_SCENES, config=load_config(RUN_CONFIG), seed=0, progress=False
    )
    gen = time.perf_counter() - t0
    log(f"learn: generated {RUN_SCENES} scenes in {gen:.0f} s ({report.format_summary()})")
    c0, t0 = time.process_time(), time.perf_counter()
    res = train(
        root / "ds",
        root / "model",
        model_config=ModelConfig(image_size=SIZE),
        train_config=TrainConfig(epochs=RUN_EPOCHS),
        num_threads=threads,
        progress=False,
    )
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    log(f"learn: trained {res.num_views} views x {RUN_EPOCHS} epochs in {wall:.0f} s")
    return {
        "views": res.num_views,
        "wall": wall,
        "cpu": cpu,
        "generate_s": gen,
        "epoch_s": [h["seconds"] for h in res.history],
        "loss": res.history[-1]["loss"],
    }


def run(
    *, quick: bool, repeats: int, mgn: Any, mgn_status: str, log: Callable[[str], None]
) -> list[Row]:
    rows = [
        Row(
            "learning",
            f"train step: small U-Net w16, {BATCH} RGB views {SIZE}x{SIZE}",
            BATCH,
            "views/s",
            "—",
            peer_status="no peer",
        ),
        Row(
            "learning",
            "predict: one 1200x1200 photo (network at 256 px, instances)",
            1,
            "images/s",
            "—",
            peer_status="no peer",
        ),
    ]
    if not quick:
        rows.append(
            Row(
                "learning",
                f"train: {RUN_SCENES} scenes x 16 views, {RUN_EPOCHS} epochs at {SIZE} px",
                0,
                "views/s",
                "—",
                peer_status="no peer",
            )
        )
    torch = _torch()
    if mgn is None or torch is None:
        for r in rows:
            r.mgn_status = mgn_status if mgn is None else "torch not installed (mgn[learn])"
        return rows
    from mgn.learn import ModelConfig, Predictor
    from mgn.learn.checkpoint import MODEL_FORMAT, write_torch_file
    from mgn.learn.model import build_model
    from mgn.learn.training import compute_losses

    mc = ModelConfig(image_size=SIZE)
    torch.manual_seed(0)
    model = build_model(mc)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    rng = np.random.default_rng(0)
    x = torch.from_numpy(rng.uniform(0, 1, (BATCH, 3, SIZE, SIZE)).astype(np.float32))
    t = torch.from_numpy((rng.uniform(0, 1, (BATCH, 3, SIZE, SIZE)) > 0.5).astype(np.float32))
    w = torch.ones(BATCH, SIZE, SIZE)

    def step() -> None:
        loss = compute_losses(model(x), t, w, mc)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()

    def with_threads(n: int, fn: Callable[[], None]) -> Callable[[], None]:
        def call() -> None:
            torch.set_num_threads(n)
            fn()

        return call

    threads = thread_counts()
    cases = {n: with_threads(n, step) for n in threads}
    for c in cases.values():
        c()
    rows[0].mgn = measure_alternating(cases, repeats)
    log("learn: training step")
    path = bench_tempdir("mgn_bench_learn_model_") / "model.pt"
    write_torch_file(
        path,
        {
            "format": MODEL_FORMAT,
            "model_config": mc.to_dict(),
            "state_dict": model.state_dict(),
            "training": {},
        },
    )
    pred = Predictor(path, device="cpu")
    photo = rng.integers(0, 256, (1200, 1200, 3), dtype=np.uint8)
    cases = {n: with_threads(n, lambda: pred.predict(photo)) for n in threads}  # type: ignore[misc]
    for c in cases.values():
        c()
    rows[1].mgn = measure_alternating(cases, repeats)
    log("learn: prediction")
    torch.set_num_threads(max(threads))
    if not quick:
        r = whole_run(max(threads), log)
        rows[2].n = r["views"] * RUN_EPOCHS
        rows[2].mgn = {max(threads): Timing([r["wall"]], [r["cpu"]])}
        ok = r["wall"] <= 600
        rows[2].agreement = f"{r['wall']:.0f} s {'<=' if ok else '>'} 600 s"
        rows[2].agreement_ok = ok
        rows[2].notes.append(
            f"{r['views']} views; epochs {min(r['epoch_s']):.0f}-{max(r['epoch_s']):.0f} s; "
            f"final loss {r['loss']:.3f}; dataset generated in {r['generate_s']:.0f} s (not timed)"
        )
    return rows


if __name__ == "__main__":
    import sys

    result = whole_run(int(sys.argv[1]) if len(sys.argv) > 1 else os.cpu_count() or 1)
    print({k: (round(v, 2) if isinstance(v, float) else v) for k, v in result.items()})
