"""Path tracing: mgn ``path`` (with and without Open Image Denoise) against Blender Cycles (CPU,
``bpy`` wheel) and Mitsuba 3 (``mitsuba`` wheel, CPU variant) on one scene.

The scene (benchmarks/path_scene.py): 20 built-in objects dropped into the tote
(:func:`mgn.scene.drop_scene`, fixed seed), two rectangular area lights and a uniform environment,
view 0 of the MetaGraspNet rig. Each engine renders it at 1, 4, 16, 64 samples per pixel (quick:
1, 4, 16), and once at a high sample count: its own reference. Error = FLIP (``flip-evaluator``,
LDR, 67 px/degree) and PSNR of each image against the reference of the same engine, both after the
same tone mapping (linear radiance x the exposure that puts the reference's 99.5th luminance
percentile at 1, clip, sRGB). Denoised rows: mgn radiance + albedo + normal through ``pyoidn``
(the denoiser's time is part of the view's time); Cycles with its own OIDN denoiser (albedo and
normal passes), as BlenderProc uses it.

Each engine runs in its own subprocess (peak memory is then per engine: the child's maximum
resident set size); the peers get the scene as plain data (a pickled SceneDesc) and never import
mgn. Every engine first renders its instance ids (objects emitting their id, one sample at the
pixel centre); agreement with mgn's raster instance ids shows the export is aligned.

Renders take minutes each on a 2-core machine, so the engines run one after another (not
alternated as in common.py); the 1-minute load average is recorded beside every timing. The
suite's own table, error plot and timings go to a work folder outside the repository; its rows
(mgn against each peer at 16 spp) go into benchmarks/PERFORMANCE.md.

    python -m benchmarks --only path [--quick]
    python -m benchmarks.bench_path --figures   # the pictures of docs/rendering.md
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pickle
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import path_scene as ps
from .common import PEER_NOT_INSTALLED, Row, Timing

HERE = Path(__file__).resolve().parent
FULL = {"width": 240, "spps": (1, 4, 16, 64), "ref_spp": 512, "target_spp": (1, 4)}
QUICK = {"width": 120, "spps": (1, 4, 16), "ref_spp": 128, "target_spp": (4,)}
ENGINES = ("mgn", "cycles", "mitsuba")
THREADS = 2
#: OIDN qualities compared on mgn's traced images (each with and without ``clean_aux``).
DENOISE_STUDY = ("fast", "balanced", "high")


def load1() -> float:
    return float(os.getloadavg()[0])


# ----------------------------------------------------------------------------------------------
# Children: one engine each


def _engine_mgn(
    desc: ps.SceneDesc, scene_json: Path, tmp: Path, adaptive: float = 0.0
) -> dict[str, Callable]:
    import pyoidn

    CameraView, Intrinsics = ps.cameras().CameraView, ps.cameras().Intrinsics
    from mgn.render import path as mpath

    inp = ps.mgn_inputs(scene_json)
    lights, env = ps.mgn_lighting()
    scene = mpath.PathScene(
        inp["meshes"], inp["poses"], inp["instance_ids"], inp["materials"], lights, env
    )
    c = desc.camera
    view = CameraView(Intrinsics(c.width, c.height, c.fx, c.fy, c.cx, c.cy), c.X_WC)

    try:  # what `render.denoise` runs, with the default quality, guides and resolution
        from mgn.render.denoiser import denoise as photo_denoise
        from mgn.render.settings import RenderSettings

        defaults = RenderSettings()

        def mgn_denoise(radiance: np.ndarray, albedo: np.ndarray, normal: np.ndarray) -> Any:
            return photo_denoise(
                radiance,
                albedo,
                normal,
                defaults.denoise_quality,
                guides=defaults.denoise_guides,
                resolution=defaults.denoise_resolution,
            )

    except ImportError:

        def mgn_denoise(radiance: np.ndarray, albedo: np.ndarray, normal: np.ndarray) -> Any:
            return pyoidn.denoise(radiance, albedo=albedo, normal=normal, hdr=True)

    def trace(spp: int, seed: int) -> Any:
        opts = mpath.PathTraceOptions(
            spp=spp, max_bounces=desc.max_bounces, seed=seed, num_threads=THREADS
        )
        if hasattr(opts, "labels"):  # the image only, as the pipeline traces it (ids: ids())
            opts = dataclasses.replace(opts, labels=False)
        if hasattr(opts, "clamp_indirect"):  # unclamped, as the peers are set up
            opts = dataclasses.replace(opts, clamp_indirect=0.0)
        if adaptive > 0.0:  # extra samples where the first pass is noisy (adaptive sampling)
            opts = dataclasses.replace(opts, adaptive_samples=adaptive)
        return scene.render(view, opts)

    def render(spp: int, denoise: bool, seed: int) -> np.ndarray:
        out = trace(spp, seed)
        if not denoise:
            return out.radiance
        return np.asarray(mgn_denoise(out.radiance, out.albedo, out.normal), np.float32)

    def denoiser_study(spp: int, seed: int) -> list[tuple[str, bool, float, np.ndarray]]:
        """The OIDN settings on one traced image: (quality, clean_aux, CPU-s, image)."""
        out = trace(spp, seed)
        a = np.ascontiguousarray(np.clip(out.albedo, 0.0, 1.0), np.float32)
        n = np.ascontiguousarray(np.clip(out.normal, -1.0, 1.0), np.float32)
        rows = []
        for q in DENOISE_STUDY:
            for clean in (False, True):
                c0 = time.process_time()
                img = pyoidn.denoise(out.radiance, a, n, hdr=True, quality=q, clean_aux=clean)
                rows.append((q, clean, time.process_time() - c0, np.asarray(img, np.float32)))
        return rows

    def ids() -> np.ndarray:
        opts = mpath.PathTraceOptions(spp=1, max_bounces=0, num_threads=THREADS)
        return np.asarray(scene.render(view, opts).instance_ids, np.int32)

    return {
        "render": render,
        "ids": ids,
        "keep": scene,
        "denoiser_study": denoiser_study,
        "trace": trace,
    }


def _engine_cycles(desc: ps.SceneDesc, scene_json: Path, tmp: Path) -> dict[str, Callable]:
    import bpy

    ids_img = ps.cycles_ids(desc, tmp, THREADS)  # builds its own session; do it first
    scene = ps.cycles_scene(desc, tmp, THREADS)
    n = [0]

    def render(spp: int, denoise: bool, seed: int) -> np.ndarray:
        n[0] += 1
        return ps.cycles_render(scene, spp, tmp / f"c{n[0]}.exr", denoise=denoise, seed=seed)

    return {"render": render, "ids": lambda: ids_img, "version": bpy.app.version_string}


def _engine_mitsuba(desc: ps.SceneDesc, scene_json: Path, tmp: Path) -> dict[str, Callable]:
    variant = ps.mitsuba_variant()
    import mitsuba as mi

    ids_img = ps.mitsuba_ids(desc, tmp)
    scene = mi.load_dict(ps.mitsuba_dict(desc, tmp, 1))

    def render(spp: int, denoise: bool, seed: int) -> np.ndarray:
        if denoise:
            raise ValueError("Mitsuba 3 has no CPU denoiser")
        return ps.mitsuba_render(scene, spp, seed=seed)

    return {"render": render, "ids": lambda: ids_img, "version": f"{mi.__version__} {variant}"}


def child_main(argv: list[str]) -> int:
    """One engine in this process: prints JSON (timings, load, peak memory), saves the images to
    --out (npz)."""
    p = argparse.ArgumentParser()
    p.add_argument("--engine", choices=ENGINES, required=True)
    p.add_argument("--desc", required=True, help="pickled SceneDesc")
    p.add_argument("--scene", required=True, help="scene JSON (mgn side)")
    p.add_argument("--spps", required=True, help="comma-separated")
    p.add_argument("--ref-spp", type=int, required=True)
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--denoise", action="store_true", help="also the denoised variants")
    p.add_argument("--denoised-only", action="store_true", help="only the denoised variants")
    p.add_argument("--out", required=True)
    p.add_argument("--adaptive", type=float, default=0.0, help="mgn: adaptive_samples")
    a = p.parse_args(argv)
    with Path(a.desc).open("rb") as f:
        desc: ps.SceneDesc = pickle.load(f)
    spps = [int(s) for s in a.spps.split(",") if s]
    result: dict[str, Any] = {"configs": []}
    images: dict[str, np.ndarray] = {}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        t0 = time.perf_counter()
        if a.engine == "mgn":
            eng = _engine_mgn(desc, Path(a.scene), tmp, a.adaptive)
        else:
            eng = {"cycles": _engine_cycles, "mitsuba": _engine_mitsuba}[a.engine](
                desc, Path(a.scene), tmp
            )
        result["setup_s"] = time.perf_counter() - t0
        result["version"] = eng.get("version", "")
        images["ids"] = eng["ids"]()
        if not spps and a.ref_spp == 0:  # alignment check only
            spps = []
            np.savez(a.out, **images)
            print(json.dumps(result))
            return 0
        render = eng["render"]
        variants = (True,) if a.denoised_only else (False, True) if a.denoise else (False,)
        for denoise in variants:  # warm-up (JIT, BVH, denoiser weights)
            render(1, denoise, 99)
        for spp in spps:
            for denoise in variants:
                wall, cpu, loads = [], [], []
                for _ in range(a.repeats):
                    loads.append(load1())
                    c0, w0 = time.process_time(), time.perf_counter()
                    img = render(spp, denoise, 0)
                    wall.append(time.perf_counter() - w0)
                    cpu.append(time.process_time() - c0)
                key = f"{spp}{'d' if denoise else ''}"
                images[key] = np.asarray(img, np.float32)
                result["configs"].append(
                    {"spp": spp, "denoise": denoise, "wall": wall, "cpu": cpu, "load1": loads}
                )
                print(f"{a.engine} {key}: {np.median(wall):.2f} s", file=sys.stderr, flush=True)
        if "denoiser_study" in eng and a.ref_spp > 0:
            result["denoiser_study"] = []
            for spp in spps[:2]:
                for q, clean, cpu, img in eng["denoiser_study"](spp, 0):
                    key = f"dn{spp}_{q}_{int(clean)}"
                    images[key] = img
                    result["denoiser_study"].append(
                        {"spp": spp, "quality": q, "clean_aux": clean, "cpu": cpu, "key": key}
                    )
        if a.ref_spp > 0:
            load = load1()
            w0 = time.perf_counter()
            images["ref"] = np.asarray(render(a.ref_spp, False, 12345), np.float32)
            result["ref"] = {"spp": a.ref_spp, "wall": time.perf_counter() - w0, "load1": load}
    result["peak_kib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    np.savez(a.out, **images)
    print(json.dumps(result))
    return 0


def _python_for(engine: str) -> str:
    """The interpreter of a child: bpy needs NumPy < 2 and Python 3.11, so Cycles may live in
    another environment (MGN_BENCH_BPY_PYTHON)."""
    if engine == "cycles":
        return os.environ.get("MGN_BENCH_BPY_PYTHON", sys.executable)
    return sys.executable


def run_child(
    engine: str,
    desc_path: Path,
    scene_json: Path,
    spps: tuple[int, ...],
    ref_spp: int,
    repeats: int,
    out: Path,
    log: Callable[[str], None],
    denoised_only: bool = False,
    adaptive: float = 0.0,
) -> tuple[dict | None, str]:
    cmd = [_python_for(engine), "-m", "benchmarks.bench_path", "--engine", engine]
    cmd += ["--desc", str(desc_path), "--scene", str(scene_json), "--out", str(out)]
    cmd += ["--spps", ",".join(map(str, spps)), "--ref-spp", str(ref_spp)]
    cmd += ["--repeats", str(repeats)]
    if engine in ("mgn", "cycles"):
        cmd.append("--denoise")
    if denoised_only:
        cmd.append("--denoised-only")
    if adaptive > 0.0:
        cmd += ["--adaptive", str(adaptive)]
    proc = subprocess.Popen(
        cmd, cwd=HERE.parent, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    err_lines = []
    assert proc.stderr is not None
    for line in proc.stderr:
        err_lines.append(line)
        if line.startswith(engine):
            log("    " + line.rstrip())
    stdout = proc.stdout.read() if proc.stdout else ""
    if proc.wait() != 0:
        text = "".join(err_lines)
        last = (text.strip().splitlines() or ["?"])[-1]
        status = PEER_NOT_INSTALLED if "ModuleNotFoundError" in text else "failed"
        return None, f"{status} ({last[:200]})"
    return json.loads(stdout.strip().splitlines()[-1]), ""


# ----------------------------------------------------------------------------------------------
# Error metrics


def exposure_of(ref: np.ndarray) -> float:
    lum = ref @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    return 1.0 / max(float(np.percentile(lum, 99.5)), 1e-6)


def tonemap(x: np.ndarray, exposure: float) -> np.ndarray:
    return ps.linear_to_srgb(np.nan_to_num(x, nan=0.0, posinf=1.0) * exposure).astype(np.float32)


def flip_error(ref: np.ndarray, test: np.ndarray) -> float:
    import flip_evaluator as flip

    _, mean, _ = flip.evaluate(ref, test, "LDR", inputsRGB=True, applyMagma=False)
    return float(mean)


def psnr(ref: np.ndarray, test: np.ndarray) -> float:
    mse = float(np.mean((ref.astype(np.float64) - test) ** 2))
    return float("inf") if mse == 0 else 10.0 * np.log10(1.0 / mse)


# ----------------------------------------------------------------------------------------------
# The suite


def _label(engine: str, denoise: bool) -> str:
    name = {"mgn": "mgn path", "cycles": "Cycles", "mitsuba": "Mitsuba 3"}[engine]
    return name + (" + OIDN" if denoise else "")


def evaluate(
    results: dict[str, dict | None], frames: dict[str, dict[str, np.ndarray]], mgn_ids: np.ndarray
) -> dict[str, Any]:
    """Per engine and config: seconds/view, load, FLIP and PSNR against its own reference; id
    agreement with mgn's raster instance ids; FLIP between the engines' references."""
    table = []
    agreement = {}
    refs = {}
    for engine, res in results.items():
        if res is None:
            continue
        f = frames[engine]
        agreement[engine] = float(np.mean(f["ids"] == mgn_ids))
        if "ref" not in f:
            continue
        e = exposure_of(f["ref"])
        ref_t = tonemap(f["ref"], e)
        refs[engine] = (f["ref"], ref_t)
        for cfg in res["configs"]:
            key = f"{cfg['spp']}{'d' if cfg['denoise'] else ''}"
            test = tonemap(f[key], e)
            table.append(
                {
                    "engine": engine,
                    "label": _label(engine, cfg["denoise"]),
                    "spp": cfg["spp"],
                    "denoise": cfg["denoise"],
                    "seconds": float(np.median(cfg["wall"])),
                    "cpu_seconds": float(np.median(cfg["cpu"])),
                    "cores_used": float(np.median(np.asarray(cfg["cpu"]) / cfg["wall"])),
                    "load1": float(np.mean(cfg["load1"])),
                    "flip": flip_error(ref_t, test),
                    "psnr": psnr(ref_t, test),
                    "peak_mib": res["peak_kib"] / 1024,
                }
            )
    study = []
    res_mgn = results.get("mgn")
    if res_mgn is not None and "ref" in frames.get("mgn", {}):
        e = exposure_of(frames["mgn"]["ref"])
        ref_t = tonemap(frames["mgn"]["ref"], e)
        raw_cpu = {
            c["spp"]: float(np.median(c["cpu"])) for c in res_mgn["configs"] if not c["denoise"]
        }
        for d in res_mgn.get("denoiser_study", []):
            test = tonemap(frames["mgn"][d["key"]], e)
            study.append(
                {
                    **d,
                    "trace_cpu": raw_cpu.get(d["spp"], float("nan")),
                    "flip": flip_error(ref_t, test),
                    "psnr": psnr(ref_t, test),
                }
            )
    # Faithfulness of the exports: the engines' references against each other, each with the
    # mgn reference's exposure (same radiometry expected).
    cross = {}
    if "mgn" in refs:
        e = exposure_of(refs["mgn"][0])
        base = tonemap(refs["mgn"][0], e)
        for engine, (ref, _) in refs.items():
            if engine != "mgn":
                other = tonemap(ref, e)
                cross[engine] = {
                    "flip": flip_error(base, other),
                    "mean_radiance_ratio": float(ref.mean() / max(refs["mgn"][0].mean(), 1e-9)),
                }
    return {"table": table, "id_agreement": agreement, "cross": cross, "denoiser_study": study}


def plot(ev: dict[str, Any], path: Path, title: str) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    labels = sorted({r["label"] for r in ev["table"]})
    for label in labels:
        rows = sorted((r for r in ev["table"] if r["label"] == label), key=lambda r: r["spp"])
        t = [r["cpu_seconds"] for r in rows]
        style = "-" if "OIDN" in label else "--"
        for ax, key in zip(axes, ("flip", "psnr"), strict=True):
            ax.plot(t, [r[key] for r in rows], style, marker="o", label=label)
            for r in rows:
                ax.annotate(str(r["spp"]), (r["cpu_seconds"], r[key]), fontsize=7)
    for ax, name in zip(
        axes, ("FLIP (lower is better)", "PSNR dB (higher is better)"), strict=True
    ):
        ax.set_xscale("log")
        ax.set_xlabel("CPU seconds per view (2 threads; ~2x the wall time on 2 idle cores)")
        ax.set_ylabel(name)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_yscale("log")
    axes[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def markdown(ev: dict[str, Any], meta: dict[str, Any]) -> str:
    lines = [
        "## Path tracing (`python -m benchmarks --only path`)",
        "",
        meta["intro"],
        "",
        "| engine | spp | s/view | CPU-s/view | load (1 min) | cores used | FLIP | PSNR dB "
        "| peak RSS MiB |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(ev["table"], key=lambda r: (r["label"], r["spp"])):
        lines.append(
            f"| {r['label']} | {r['spp']} | {r['seconds']:.2f} | {r['cpu_seconds']:.2f} | "
            f"{r['load1']:.1f} | {r['cores_used']:.2f} | {r['flip']:.4f} | {r['psnr']:.1f} | "
            f"{r['peak_mib']:.0f} |"
        )
    lines += ["", *meta["notes"], ""]
    if ev.get("denoiser_study"):
        lines += [
            "Denoiser settings (mgn's traced image of the table, seed 0, through `pyoidn` with "
            "each OIDN quality, with and without `clean_aux`; CPU-s of the denoiser alone and "
            "with the trace; error against mgn's reference):",
            "",
            "| spp | quality | clean_aux | denoise CPU-s | trace + denoise CPU-s | FLIP "
            "| PSNR dB |",
            "|---|---|---|---|---|---|---|",
        ]
        for d in ev["denoiser_study"]:
            lines.append(
                f"| {d['spp']} | {d['quality']} | {d['clean_aux']} | {d['cpu']:.2f} | "
                f"{d['cpu'] + d['trace_cpu']:.2f} | {d['flip']:.4f} | {d['psnr']:.1f} |"
            )
        lines.append("")
    return "\n".join(lines)


def run(
    *,
    quick: bool,
    repeats: int,
    mgn: Any | None,
    mgn_status: str,
    log: Callable[[str], None],
    out_dir: Path | None = None,
) -> list[Row]:
    cfg = QUICK if quick else FULL
    width, spps, ref_spp = cfg["width"], cfg["spps"], cfg["ref_spp"]
    reps = min(repeats, 2)
    # The suite's own table, plot and timings go to a work folder outside the repository; the
    # rows it returns go into benchmarks/PERFORMANCE.md.
    out_dir = out_dir or Path(tempfile.gettempdir()) / "mgn_benchmarks" / "path"
    out_dir.mkdir(parents=True, exist_ok=True)
    if mgn is None:
        log(f"  path: {mgn_status}; nothing to compare")
        return []
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        scene_json = tmp / "scene.json"
        t0 = time.perf_counter()
        ps.drop(scene_json)
        log(f"  path: scene dropped in {time.perf_counter() - t0:.0f} s; {width}x{width} px")
        desc = ps.describe(scene_json, width)
        desc_path = tmp / "desc.pkl"
        desc_path.write_bytes(pickle.dumps(desc))
        mgn_ids = raster_ids(desc, scene_json)
        results: dict[str, dict | None] = {}
        statuses: dict[str, str] = {}
        frames: dict[str, dict[str, np.ndarray]] = {}
        for engine in ENGINES:
            log(f"  path: {engine}")
            out = tmp / f"{engine}.npz"
            results[engine], statuses[engine] = run_child(
                engine, desc_path, scene_json, spps, ref_spp, reps, out, log
            )
            if results[engine] is not None:
                with np.load(out) as z:
                    frames[engine] = {k: z[k] for k in z.files}
            else:
                log(f"    {engine}: {statuses[engine]}")
        # The principal point: a camera with (cx, cy) moved by (+23, -31) px at this size.
        shifted = ps.describe(scene_json, width, cx_shift=23.0, cy_shift=-31.0)
        shifted_path = tmp / "desc_shifted.pkl"
        shifted_path.write_bytes(pickle.dumps(shifted))
        shifted_ids = raster_ids(shifted, scene_json)
        shift_agreement = {}
        for engine in ("cycles", "mitsuba"):
            out = tmp / f"{engine}_shifted.npz"
            res, _ = run_child(engine, shifted_path, scene_json, (), 0, 1, out, log)
            if res is not None:
                with np.load(out) as z:
                    shift_agreement[engine] = float(np.mean(z["ids"] == shifted_ids))
        # The target at full size: mgn denoised at 1200 x 1200, and Cycles' cost per sample there.
        target = None
        if not quick and results["mgn"] is not None:
            target = full_size_target(scene_json, tmp, cfg["target_spp"], log)
    ev = evaluate(results, frames, mgn_ids)
    ev["statuses"] = statuses
    ev["results"] = results
    ev["target"] = target
    ev["shifted_id_agreement"] = shift_agreement
    ev["config"] = {"width": width, "spps": list(spps), "ref_spp": ref_spp, "repeats": reps}
    meta = describe_results(ev, width, ref_spp)
    (out_dir / "path_results.json").write_text(json.dumps(ev, indent=1, default=float) + "\n")
    (out_dir / "path_results.md").write_text(markdown(ev, meta))
    plot(ev, out_dir / "path.png", meta["title"])
    log(f"  path: wrote {out_dir / 'path_results.md'}, path_results.json, path.png")
    return rows_for_runner(ev, width)


def raster_render(desc: ps.SceneDesc, scene_json: Path):  # mgn RenderOutput
    """mgn's raster render (RGB, depth, instance ids) of the benchmark view."""
    from mgn.render import Instance, Renderer

    CameraView, Intrinsics = ps.cameras().CameraView, ps.cameras().Intrinsics

    c = desc.camera
    inp = ps.mgn_inputs(scene_json)
    r = Renderer(c.width, c.height)
    r.set_instances(
        [
            Instance(r.add_mesh(m), X, i)
            for m, X, i in zip(inp["meshes"], inp["poses"], inp["instance_ids"], strict=True)
        ]
    )
    K = Intrinsics(c.width, c.height, c.fx, c.fy, c.cx, c.cy)
    return r.render(CameraView(K, c.X_WC), randomize=False)


def raster_ids(desc: ps.SceneDesc, scene_json: Path) -> np.ndarray:
    """mgn's raster instance ids of the view (the labels' id image)."""
    return np.asarray(raster_render(desc, scene_json).instance_ids, np.int32)


def full_size_target(
    scene_json: Path, tmp: Path, spps: tuple[int, ...], log: Callable[[str], None]
) -> dict[str, Any]:
    """mgn denoised at 1200 x 1200 (the target's size) and Cycles at 1 spp there (its cost per
    sample per view at full size), each timed once after a warm-up."""
    desc = ps.describe(scene_json, 1200)
    desc_path = tmp / "desc1200.pkl"
    desc_path.write_bytes(pickle.dumps(desc))
    out: dict[str, Any] = {}
    for engine, s in (("mgn", spps), ("cycles", (1,))):
        log(f"  path: {engine} at 1200x1200")
        res, status = run_child(
            engine, desc_path, scene_json, s, 0, 1, tmp / f"{engine}1200.npz", log
        )
        out[engine] = res if res is not None else status
    return out


def describe_results(ev: dict[str, Any], width: int, ref_spp: int) -> dict[str, Any]:
    res = ev["results"]
    notes = []
    for engine, status in ev["statuses"].items():
        if status:
            notes.append(f"- {engine}: {status}")
    for engine, agree in ev["id_agreement"].items():
        notes.append(
            f"- alignment: {engine}'s instance ids equal mgn's raster instance ids on "
            f"{100 * agree:.3f} % of pixels"
        )
    for engine, agree in ev.get("shifted_id_agreement", {}).items():
        notes.append(
            f"- principal point: with (cx, cy) moved by (+23, -31) px, {engine}'s ids equal mgn's "
            f"on {100 * agree:.3f} % of pixels"
        )
    for engine, c in ev["cross"].items():
        notes.append(
            f"- export faithfulness: {engine}'s reference vs mgn's reference, FLIP "
            f"{c['flip']:.4f}, mean radiance ratio {c['mean_radiance_ratio']:.3f}"
        )
    for engine, r in res.items():
        if r is not None and "ref" in r:
            full = r["ref"]["wall"] * (1200 * 1200) / (width * width) * 4096 / ref_spp
            notes.append(
                f"- {engine} reference: {ref_spp} spp at {width}x{width} took "
                f"{r['ref']['wall']:.0f} s (load {r['ref']['load1']:.1f}); a 4096-spp 1200x1200 "
                f"reference would take about {full / 3600:.1f} h at that rate; setup "
                f"{r['setup_s']:.1f} s; version {r.get('version') or 'this checkout'}"
            )
    notes += target_notes(ev)
    intro = (
        f"{width}x{width} px (the MetaGraspNet camera scaled by {width / 1200:g}), view 0, "
        f"max 6 bounces, 2 threads; error against each engine's own {ref_spp}-spp reference "
        "(a 4096-spp 1200x1200 reference per engine does not fit on this shared machine: see "
        "the notes for the measured cost). Engines ran one after another; the load column is the "
        "1-minute load average when the timing started (2 cores: anything above 2 means other "
        "processes shared them)."
    )
    return {
        "intro": intro,
        "notes": notes,
        "title": f"{width}x{width}, error vs own {ref_spp}-spp reference",
    }


def flip_at(rows: list[dict[str, Any]], seconds: float) -> tuple[float, str]:
    """FLIP of one engine configuration at a given time per view, interpolated log-log between
    the measured sample counts; ("", "beyond ...") when outside the measured range."""
    rows = sorted(rows, key=lambda r: r["cpu_seconds"])
    t = np.log([r["cpu_seconds"] for r in rows])
    f = np.log([r["flip"] for r in rows])
    x = float(np.log(seconds))
    if x < t[0]:
        return float("nan"), f"below its fastest point ({rows[0]['cpu_seconds']:.2f} CPU-s)"
    if x > t[-1]:
        return float(rows[-1]["flip"]), (
            f"beyond its slowest point ({rows[-1]['cpu_seconds']:.2f} CPU-s, {rows[-1]['spp']} "
            "spp); its "
            "FLIP there is given, an upper bound of what it would reach in that time"
        )
    return float(np.exp(np.interp(x, t, f))), "interpolated"


def _flip_cell(rows: list[dict[str, Any]], seconds: float) -> str:
    if len(rows) < 2:
        return "—"
    val, how = flip_at(rows, seconds)
    if np.isnan(val):
        return "n/a (slower)"
    return f"≤ {val:.4f}" if how.startswith("beyond") else f"{val:.4f}"


def target_notes(ev: dict[str, Any]) -> list[str]:
    """The target (a denoised view at a FLIP no worse than a peer reaches with 10x the time),
    checked at the study's size: each denoised mgn point against the
    FLIP each peer configuration reaches in the same time and in 10x that time (log-log
    interpolation between its measured sample counts; "≤ x" = beyond its slowest point, where x
    is its FLIP at that point, an upper bound; "n/a" = even its 1 spp is slower); then the
    measured times at 1200 x 1200."""
    table = ev["table"]
    mgn_d = sorted(
        (r for r in table if r["engine"] == "mgn" and r["denoise"]), key=lambda r: r["spp"]
    )
    peers: dict[str, list[dict[str, Any]]] = {}
    for r in table:
        if r["engine"] != "mgn":
            peers.setdefault(r["label"], []).append(r)
    labels = sorted(peers)
    lines = []
    if mgn_d and labels:
        lines += [
            "",
            "Target check (FLIP, lower is better): each denoised mgn point against what each "
            "peer reaches with the same CPU time (1×) and with 10× that CPU time (CPU seconds, "
            "not wall time, because the shared machine gave each process a varying share of its "
            "cores), interpolated between its "
            "measured sample counts (≤ x: beyond its slowest point, x is an upper bound; n/a: "
            "its 1 spp is already slower).",
            "",
            "| mgn + OIDN | CPU-s/view | FLIP | "
            + " | ".join(f"{lab} 1× | {lab} 10×" for lab in labels)
            + " |",
            "|---|---|---|" + "---|---|" * len(labels),
        ]
        for m in mgn_d:
            cells = []
            for lab in labels:
                cells += [
                    _flip_cell(peers[lab], m["cpu_seconds"]),
                    _flip_cell(peers[lab], 10 * m["cpu_seconds"]),
                ]
            lines.append(
                f"| {m['spp']} spp | {m['cpu_seconds']:.2f} | {m['flip']:.4f} | "
                + " | ".join(cells)
                + " |"
            )
        lines.append("")
    tgt = ev.get("target") or {}
    r = tgt.get("mgn")
    if isinstance(r, dict):
        for c in r["configs"]:
            if c["denoise"]:
                raw = [
                    f"{np.median(d['wall']):.2f} s"
                    for d in r["configs"]
                    if d["spp"] == c["spp"] and not d["denoise"]
                ]
                lines.append(
                    f"- 1200x1200: mgn {c['spp']} spp + OIDN took {np.median(c['wall']):.2f} s "
                    f"per view (load {np.mean(c['load1']):.1f}, {np.median(c['cpu']):.1f} CPU-s; "
                    f"target <= 3 s on 2 idle cores); without OIDN {', '.join(raw)}"
                )
    elif r:
        lines.append(f"- 1200x1200 mgn: {r}")
    r = tgt.get("cycles")
    if isinstance(r, dict):
        for c in r["configs"]:
            lines.append(
                f"- 1200x1200: Cycles {c['spp']} spp{' + OIDN' if c['denoise'] else ''} took "
                f"{np.median(c['wall']):.2f} s per view (load {np.mean(c['load1']):.1f}, "
                f"{np.median(c['cpu']):.1f} CPU-s)"
            )
    elif r:
        lines.append(f"- 1200x1200 Cycles: {r}")
    return lines


def rows_for_runner(ev: dict[str, Any], width: int) -> list[Row]:
    """Rows for the common results table: mgn against each peer at the same spp (16)."""
    rows = []
    by = {(r["engine"], r["spp"], r["denoise"]): r for r in ev["table"]}
    res = ev["results"]

    def timing(engine: str, spp: int, denoise: bool) -> Timing | None:
        r = res.get(engine)
        if r is None:
            return None
        for c in r["configs"]:
            if c["spp"] == spp and c["denoise"] == denoise:
                return Timing(c["wall"], c["cpu"])
        return None

    for peer, denoise in (("cycles", True), ("mitsuba", False)):
        spp = 16
        m, p = timing("mgn", spp, denoise), timing(peer, spp, denoise)
        row = Row(
            group="path tracing",
            case=f"{width}×{width}, {spp} spp{' + OIDN' if denoise else ''}",
            n=1,
            unit="views/s",
            peer_name=_label(peer, denoise),
            mgn_status=ev["statuses"].get("mgn", ""),
            peer_status=ev["statuses"].get(peer, ""),
        )
        if m is not None:
            row.mgn = {THREADS: m}
        row.peer = p
        a, b = by.get(("mgn", spp, denoise)), by.get((peer, spp, denoise))
        if a and b:
            row.agreement = f"FLIP vs own ref: mgn {a['flip']:.3f}, peer {b['flip']:.3f}"
        rows.append(row)
    return rows


# ----------------------------------------------------------------------------------------------
# The pictures of docs/rendering.md (--figures)


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


GLASS_NAMES = ("wine_glass", "bottle_clear", "can_soda", "box_tea", "tennis_ball", "pear", "mug")


def save_png(rgb: np.ndarray, path: Path, max_kib: int = 400) -> None:
    """Writes an sRGB uint8 image as PNG; quantised to a palette if the plain PNG is too big."""
    from PIL import Image

    img = Image.fromarray(np.asarray(rgb, np.uint8))
    img.save(path, optimize=True)
    if path.stat().st_size > max_kib * 1024:
        img.quantize(
            colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.FLOYDSTEINBERG
        ).save(path, optimize=True)
    _log(f"  wrote {path} ({path.stat().st_size // 1024} KiB)")


def raster_rgb(desc: ps.SceneDesc, scene_json: Path) -> np.ndarray:
    return np.asarray(raster_render(desc, scene_json).rgb, np.uint8)


def glass_camera(scene_json: Path, width: int) -> ps.Camera:
    """An oblique camera above the tote aimed between the glass objects."""

    from mgn.io.scene_json import read_scene_json

    scene = read_scene_json(scene_json)
    glass = [
        np.asarray(i.X_WO, np.float64)[:3, 3]
        for i in scene.instances
        if i.name in ("wine_glass", "bottle_clear")
    ]
    target = np.mean(glass, axis=0) if glass else np.zeros(3)
    eye = target + np.array([0.0, -0.14, 0.42])
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, np.array([0.0, 0.0, 1.0]))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = x, y, z, eye
    f = 1.5 * width
    return ps.Camera(width, width, f, f, width / 2, width / 2, X)


def render_set(
    name: str,
    desc: ps.SceneDesc,
    scene_json: Path,
    tmp: Path,
    mgn_spp: int,
    high_spp: int,
    cycles_spp: int,
    exposure: float,
    out: Path,
    closeup: tuple[str, ...] = (),
) -> dict[str, float]:
    from mgn.render import path as mpath

    desc_path = tmp / f"{name}.pkl"
    desc_path.write_bytes(pickle.dumps(desc))
    times: dict[str, float] = {}
    save_png(raster_rgb(desc, scene_json), out / f"{name}_raster.png")
    film = mpath.FilmOptions(exposure=exposure)
    res, status = run_child(
        "mgn", desc_path, scene_json, (mgn_spp, high_spp), 0, 1, tmp / f"{name}_mgn.npz", _log
    )
    if res is None:
        raise RuntimeError(f"mgn path failed: {status}")
    with np.load(tmp / f"{name}_mgn.npz") as z:
        demo, high, ids = z[f"{mgn_spp}d"], z[f"{high_spp}"], z["ids"]
    save_png(mpath.develop(demo, film), out / f"{name}_path.png")
    save_png(mpath.develop(high, film), out / f"{name}_path_high.png")
    for c in res["configs"]:
        if c["spp"] == mgn_spp and c["denoise"]:
            times["mgn"] = c["wall"][0]
        if c["spp"] == high_spp and not c["denoise"]:
            times["mgn_high"] = c["wall"][0]
    res, status = run_child(
        "cycles", desc_path, scene_json, (), cycles_spp, 1, tmp / f"{name}_cycles.npz", _log
    )
    if res is None:
        raise RuntimeError(f"Cycles failed: {status}")
    with np.load(tmp / f"{name}_cycles.npz") as z:
        cycles = z["ref"]
    save_png(mpath.develop(cycles, film), out / f"{name}_cycles.png")
    times["cycles"] = res["ref"]["wall"]
    _log(
        f"  {name}: mgn {mgn_spp} spp + OIDN {times['mgn']:.1f} s, {high_spp} spp "
        f"{times['mgn_high']:.1f} s, Cycles {cycles_spp} spp {times['cycles']:.1f} s"
    )
    if closeup:
        # The glass objects' bounding box (+ a margin), each image enlarged 2x, side by side.
        sel = [it.instance_id for it in desc.items if it.name in closeup]
        ys, xs = np.nonzero(np.isin(ids, sel))
        if len(ys):
            m = 6
            y0, y1 = max(0, ys.min() - m), min(ids.shape[0], ys.max() + 1 + m)
            x0, x1 = max(0, xs.min() - m), min(ids.shape[1], xs.max() + 1 + m)
            tiles = [
                mpath.develop(np.ascontiguousarray(i[y0:y1, x0:x1]), film)
                for i in (demo, high, cycles)
            ]
            gap = np.full((y1 - y0, 4, 3), 255, np.uint8)
            strip = np.concatenate([tiles[0], gap, tiles[1], gap, tiles[2]], 1)
            save_png(np.repeat(np.repeat(strip, 2, 0), 2, 1), out / f"{name}_closeup.png")
    return times


def figures_main(argv: list[str] | None = None) -> int:
    """``python -m benchmarks.bench_path --figures``: regenerates the pictures of
    docs/rendering.md: one scene rendered by mgn's raster engine, by mgn's path tracer at the
    demo's settings (1 spp + OIDN ``fast``, as scripts/demo.yaml) and at a high sample count (not
    denoised), and by Blender Cycles; the same for a glass scene, plus a close-up of its glass
    objects. The path-traced and Cycles images go through the same film
    (``mgn.render.path.develop``), so they differ only by the renderer. Each engine runs in its
    own process, as in the benchmark. PNGs are colour-quantised to stay small (< 400 KB)."""
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.bench_path --figures", description=figures_main.__doc__
    )
    p.add_argument("--width", type=int, default=480)
    p.add_argument("--mgn-spp", type=int, default=1, help="denoised (the demo's setting)")
    p.add_argument("--high-spp", type=int, default=256, help="mgn without denoising")
    p.add_argument("--cycles-spp", type=int, default=256)
    p.add_argument("--exposure", type=float, default=0.5, help="EV for both path-traced images")
    p.add_argument("--out", type=Path, default=HERE.parent / "docs" / "images")
    a = p.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        scene_json = tmp / "scene.json"
        t0 = time.perf_counter()
        ps.drop(scene_json)
        _log(f"scene dropped in {time.perf_counter() - t0:.0f} s")
        desc = ps.describe(scene_json, a.width)
        assert np.mean(raster_ids(desc, scene_json) > 0) > 0.1, "the camera sees no objects"
        render_set(
            "render_bin",
            desc,
            scene_json,
            tmp,
            a.mgn_spp,
            a.high_spp,
            a.cycles_spp,
            a.exposure,
            a.out,
        )
        glass_json = tmp / "glass.json"
        ps.drop(glass_json, GLASS_NAMES, seed=3)
        glass = ps.describe(glass_json, a.width)
        glass = dataclasses.replace(glass, camera=glass_camera(glass_json, a.width))
        render_set(
            "render_glass",
            glass,
            glass_json,
            tmp,
            a.mgn_spp,
            a.high_spp,
            a.cycles_spp,
            a.exposure,
            a.out,
            closeup=("wine_glass", "bottle_clear"),
        )
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--figures"]:
        sys.exit(figures_main(sys.argv[2:]))
    sys.exit(child_main(sys.argv[1:]))
