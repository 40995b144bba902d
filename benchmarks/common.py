"""Timing, machine description and reporting shared by the benchmarks.

Every measurement runs the mgn calls and the peer calls of one case in the same loop, alternating
their order from one repetition to the next (A B C, then C B A, ...), so that a slow drift of the
machine (thermal throttling, another process) hurts every side alike. Each side gets a warm-up
call that is not timed; its result is the one the agreement checks look at.
"""

from __future__ import annotations

import atexit
import dataclasses
import gc
import importlib.metadata
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

# ----------------------------------------------------------------------------------------------
# Optional imports: a missing side is reported, never faked.

MGN_NOT_BUILT = "mgn not built"
PEER_NOT_INSTALLED = "peer not installed"


def import_mgn() -> tuple[Any | None, str]:
    """Returns (module, "") or (None, reason) when the compiled mgn module is not importable."""
    try:
        import mgn  # optional on purpose

        for name in ("Mesh", "RayScene", "CollisionModel", "collide", "distance"):
            getattr(mgn, name)
    except (ImportError, AttributeError) as exc:
        return None, f"{MGN_NOT_BUILT} ({type(exc).__name__}: {exc})"
    return mgn, ""


def thread_counts() -> list[int]:
    """mgn is measured with 1 thread and with every core the process may use (2 here)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    return sorted({1, max(1, cores)})


def bench_tempdir(prefix: str) -> Path:
    """A new temporary folder that is removed when the process exits (a benchmark leaves
    nothing behind in the temporary directory, even when it fails half-way)."""
    path = Path(tempfile.mkdtemp(prefix=prefix))
    atexit.register(shutil.rmtree, path, True)
    return path


# ----------------------------------------------------------------------------------------------
# Timing


@dataclasses.dataclass
class Timing:
    """Wall-clock and process CPU seconds of the timed repetitions of one callable."""

    wall: list[float]
    cpu: list[float]

    @property
    def median(self) -> float:
        return float(np.median(self.wall))

    @property
    def q1(self) -> float:
        return float(np.percentile(self.wall, 25))

    @property
    def q3(self) -> float:
        return float(np.percentile(self.wall, 75))

    @property
    def cores_used(self) -> float:
        """Median CPU time over wall time: about 1.0 for a single-threaded call."""
        return float(np.median(np.asarray(self.cpu) / np.asarray(self.wall)))

    def rate(self, n: int) -> float:
        """Items per second at the median time."""
        return n / self.median

    def rate_iqr(self, n: int) -> tuple[float, float]:
        """Items per second at the upper and lower quartile of the time (low, high)."""
        return n / self.q3, n / self.q1

    def to_json(self, n: int) -> dict[str, Any]:
        lo, hi = self.rate_iqr(n)
        return {
            "wall_seconds": self.wall,
            "cpu_seconds": self.cpu,
            "median_seconds": self.median,
            "rate_per_s": self.rate(n),
            "rate_iqr_per_s": [lo, hi],
            "rate_min_max_per_s": [n / max(self.wall), n / min(self.wall)],
            "cores_used": self.cores_used,
        }


def measure_alternating(cases: dict[str, Callable[[], object]], repeats: int) -> dict[str, Timing]:
    """Times every callable `repeats` times, alternating the order of the callables each round.

    The callables must already have been called once (warm-up) by the caller. Garbage collection
    is run before and disabled during each timed call, as timeit does.
    """
    names = list(cases)
    wall: dict[str, list[float]] = {k: [] for k in names}
    cpu: dict[str, list[float]] = {k: [] for k in names}
    for rep in range(repeats):
        order = names if rep % 2 == 0 else names[::-1]
        for name in order:
            gc.collect()
            gc.disable()
            try:
                c0 = time.process_time()
                t0 = time.perf_counter()
                cases[name]()
                t1 = time.perf_counter()
                c1 = time.process_time()
            finally:
                gc.enable()
            wall[name].append(t1 - t0)
            cpu[name].append(c1 - c0)
    return {k: Timing(wall[k], cpu[k]) for k in names}


# ----------------------------------------------------------------------------------------------
# Result rows


@dataclasses.dataclass
class Row:
    """One line of the results table: one query on one data set, mgn against one peer call."""

    group: str  # "ray casting" or "collision"
    case: str  # the data set and query, in words
    n: int  # items per timed call (rays, pose pairs)
    unit: str  # "rays/s", "checks/s"
    peer_name: str  # the peer call as a user writes it
    mgn: dict[int, Timing] = dataclasses.field(default_factory=dict)  # by thread count
    mgn_status: str = ""  # "" when measured, else the reason
    peer: Timing | None = None
    peer_status: str = ""
    agreement: str = "—"  # in words, e.g. "hit/miss 99.998 %"
    agreement_ok: bool | None = None  # None when it could not be checked
    notes: list[str] = dataclasses.field(default_factory=list)
    # The machine limit the row is bound by and one item's work in its unit, e.g.
    # ("embree_coherent", 1.0) for rays; see benchmarks/limits.py.
    limit_work: tuple[str, float] | None = None
    suite: str = ""  # the `python -m benchmarks --only` name that measured the row

    def ratio(self, threads: int) -> float | None:
        if self.peer is None or threads not in self.mgn:
            return None
        return self.mgn[threads].rate(self.n) / self.peer.rate(self.n)

    def to_json(self) -> dict[str, Any]:
        return {
            "group": self.group,
            "case": self.case,
            "n": self.n,
            "unit": self.unit,
            "peer_call": self.peer_name,
            "mgn": {str(k): v.to_json(self.n) for k, v in self.mgn.items()},
            "mgn_status": self.mgn_status or "ok",
            "peer": self.peer.to_json(self.n) if self.peer else None,
            "peer_status": self.peer_status or "ok",
            "ratio_mgn_over_peer": {str(k): self.ratio(k) for k in self.mgn},
            "agreement": self.agreement,
            "agreement_ok": self.agreement_ok,
            "notes": self.notes,
            "limit_work": list(self.limit_work) if self.limit_work else None,
            "suite": self.suite,
        }

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Row:
        """The row as :meth:`to_json` wrote it (timings, agreement and notes; for the table of a
        later ``--only`` run that keeps the rows of the suites it did not measure)."""

        def timing(t: dict[str, Any]) -> Timing:
            return Timing(list(t["wall_seconds"]), list(t["cpu_seconds"]))

        lw = d.get("limit_work")
        return cls(
            group=d["group"],
            case=d["case"],
            n=int(d["n"]),
            unit=d["unit"],
            peer_name=d["peer_call"],
            mgn={int(k): timing(v) for k, v in d["mgn"].items()},
            mgn_status="" if d["mgn_status"] == "ok" else d["mgn_status"],
            peer=timing(d["peer"]) if d.get("peer") else None,
            peer_status="" if d["peer_status"] == "ok" else d["peer_status"],
            agreement=d["agreement"],
            agreement_ok=d["agreement_ok"],
            notes=list(d["notes"]),
            limit_work=(str(lw[0]), float(lw[1])) if lw else None,
            suite=d.get("suite", ""),
        )


def fraction(mask: np.ndarray) -> float:
    return float(np.mean(mask)) if mask.size else 1.0


def percent(x: float) -> str:
    return f"{100.0 * x:.3f} %"


# ----------------------------------------------------------------------------------------------
# Formatting


def fmt_rate(x: float) -> str:
    for scale, suffix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if x >= scale:
            return f"{x / scale:.3g} {suffix}"
    return f"{x:.3g}"


def fmt_timing(t: Timing | None, n: int, status: str) -> str:
    if t is None:
        return status.split(" (", maxsplit=1)[0] if status else "—"
    lo, hi = t.rate_iqr(n)
    return f"{fmt_rate(t.rate(n))} [{fmt_rate(lo)}–{fmt_rate(hi)}]"


def markdown_table(rows: list[Row], threads: list[int]) -> str:
    tmax = max(threads)
    head = ["benchmark", "N", "unit"]
    head += [f"mgn {t} thread{'s' if t > 1 else ''}" for t in threads]
    head += ["peer call", "peer"]
    head += ["mgn 1T / peer"] + ([f"mgn {tmax}T / peer"] if tmax > 1 else [])
    head += ["agreement"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [f"{r.group}: {r.case}", f"{r.n:,}", r.unit]
        cells += [fmt_timing(r.mgn.get(t), r.n, r.mgn_status) for t in threads]
        cells += [f"`{r.peer_name}`", fmt_timing(r.peer, r.n, r.peer_status)]
        for t in [1] + ([tmax] if tmax > 1 else []):
            ratio = r.ratio(t)
            cells.append("—" if ratio is None else f"{ratio:.2f}×")
        flag = "" if r.agreement_ok in (None, True) else " **MISMATCH**"
        cells.append(r.agreement + flag)
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------------
# Machine description


def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def _dist_version(name: str) -> str:
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def _dpkg_version(name: str) -> str:
    try:
        out = subprocess.run(
            ["dpkg-query", "-W", "-f=${Version}", name],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() or "not installed"


def _git_revision() -> str:
    root = Path(__file__).resolve().parent.parent
    try:
        rev = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain"],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    if not rev:
        return "no commit yet"
    return rev + (" (with uncommitted changes)" if dirty else "")


def load_average() -> str:
    """1, 5 and 15 minute load averages: other work on the machine skews every number."""
    fields = _read("/proc/loadavg").split()
    return " ".join(fields[:3]) if len(fields) >= 3 else "unknown"


def machine_description() -> dict[str, Any]:
    cpuinfo = _read("/proc/cpuinfo")
    model = "unknown"
    cores: set[tuple[str, str]] = set()
    phys = core = ""
    for line in cpuinfo.splitlines():
        key, _, value = line.partition(":")
        key, value = key.strip(), value.strip()
        if key == "model name" and model == "unknown":
            model = value
        elif key == "physical id":
            phys = value
        elif key == "core id":
            core = value
            cores.add((phys, core))
    mem_kib = 0
    for line in _read("/proc/meminfo").splitlines():
        if line.startswith("MemTotal:"):
            mem_kib = int(line.split()[1])
    os_name = platform.platform()
    for line in _read("/etc/os-release").splitlines():
        if line.startswith("PRETTY_NAME="):
            os_name = line.split("=", 1)[1].strip('"')
    mgn, _ = import_mgn()
    return {
        "cpu_model": model,
        "logical_cpus": os.cpu_count(),
        "physical_cores": len(cores) or None,
        "usable_cpus": thread_counts()[-1],
        "ram_gib": round(mem_kib / 2**20, 1),
        "os": os_name,
        "kernel": platform.release(),
        "python": sys.version.split()[0],
        "mgn_revision": _git_revision(),
        "load_average_at_start": load_average(),
        "versions": {
            "mgn": getattr(mgn, "__version__", "not built") if mgn else "not built",
            "numpy": _dist_version("numpy"),
            "trimesh": _dist_version("trimesh"),
            "embreex": _dist_version("embreex"),
            "python-fcl": _dist_version("python-fcl"),
            "libembree3 (mgn's Embree, Debian)": _dpkg_version("libembree3-3"),
            "libfcl (mgn's FCL, Debian)": _dpkg_version("libfcl0.7"),
        },
    }


def machine_markdown(m: dict[str, Any]) -> str:
    lines = [
        (
            f"- CPU: {m['cpu_model']} — {m['logical_cpus']} logical CPUs, "
            f"{m['physical_cores'] or '?'} physical cores, "
            f"{m['usable_cpus']} usable by this process"
        ),
        f"- RAM: {m['ram_gib']} GiB; OS: {m['os']} (kernel {m['kernel']}); Python {m['python']}",
        f"- mgn source revision: {m['mgn_revision']}",
        (
            f"- load average (1/5/15 min) at start: {m['load_average_at_start']}, at end: "
            f"{m.get('load_average_at_end', 'unknown')} (anything near or above "
            f"{m['usable_cpus']} means other work shared the CPUs)"
        ),
        "- versions: " + ", ".join(f"{k} {v}" for k, v in m["versions"].items()),
    ]
    return "\n".join(lines)
