"""Entry point: ``python -m benchmarks [--quick] [--only SUITE ...] [--gate] [--out PAGE]``.

Times every capability of mgn beside its peer (one suite per capability, see README.md) and
rewrites one page, ``benchmarks/PERFORMANCE.md`` (machine, command, date, the table of current
numbers, mgn / peer ratios, the gate, the machine's limits), and its plot
``benchmarks/performance.png``. Every timing is also written to ``results.json`` beside the page
(not part of the repository). ``--gate`` exits 1 when an mgn / peer ratio is below its floor
(``benchmarks/limits.py``, ``FLOORS``); ``--from-results FILE`` rewrites the page and the plot
from a stored results.json without measuring.
"""

from __future__ import annotations

import argparse
import datetime
import json
import re
import shlex
import sys
import time
from pathlib import Path
from typing import Any

from . import (
    bench_cluster,
    bench_collision,
    bench_drop,
    bench_eval_grasps,
    bench_format,
    bench_layout,
    bench_learn,
    bench_lens,
    bench_object_labels,
    bench_path,
    bench_pick,
    bench_pipeline,
    bench_pj,
    bench_raycast,
    bench_render,
    bench_scene_grasps,
    bench_scene_labels,
    bench_seal,
    bench_sensor,
    bench_shake,
    bench_view_labels,
)
from .common import (
    Row,
    import_mgn,
    load_average,
    machine_description,
    machine_markdown,
    markdown_table,
    thread_counts,
)
from .limits import (
    gate,
    gate_failures,
    gate_markdown,
    limits_markdown,
    measure_limits,
    plot_ratios,
    shares,
    shares_markdown,
)

HERE = Path(__file__).resolve().parent
#: One suite per capability, in the order of the page.
SUITES = {
    "raycast": bench_raycast,
    "collision": bench_collision,
    "seal": bench_seal,
    "pj": bench_pj,
    "object_labels": bench_object_labels,
    "shake": bench_shake,
    "drop": bench_drop,
    "render": bench_render,
    "sensor": bench_sensor,
    "path": bench_path,
    "layout": bench_layout,
    "lens": bench_lens,
    "view_labels": bench_view_labels,
    "scene_grasps": bench_scene_grasps,
    "scene_labels": bench_scene_labels,
    "pick": bench_pick,
    "eval_grasps": bench_eval_grasps,
    "learn": bench_learn,
    "format": bench_format,
    "pipeline": bench_pipeline,
    "cluster": bench_cluster,
}
PAGE = HERE / "PERFORMANCE.md"
PLOT_NAME = "performance.png"

NOTES = [
    "embreex bundles Embree 4; mgn links Debian's Embree 3.13: the ray-casting rows compare two "
    "Embree versions as well as two wrappers.",
    "Peer time includes the Python work around the library call (trimesh's hit-point "
    "computation, python-fcl's loop): it is what a user of the peer pays.",
]


def write_atomic(path: Path, text: str) -> None:
    """Writes ``text`` to a temporary file beside ``path``, then renames it over ``path``."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def previous_runs(json_path: Path) -> list[dict[str, str]]:
    """Command, date, mode and load averages of the run that wrote ``json_path`` and of the runs
    whose rows it kept in turn (newest first): where an ``--only`` run's kept rows come from."""
    try:
        doc = json.loads(json_path.read_text())
        machine = doc.get("machine", {})
        run = {
            "command": str(doc["command"]),
            "date_utc": str(doc["date_utc"]),
            "mode": str(doc["mode"]),
            "load_average_at_start": str(machine.get("load_average_at_start", "?")),
            "load_average_at_end": str(machine.get("load_average_at_end", "?")),
        }
    except (OSError, ValueError, KeyError, AttributeError):
        return []
    older = doc.get("kept_from", []) if doc.get("kept_rows") else []
    return [run] + [r for r in older if isinstance(r, dict)]


def merge_previous_rows(json_path: Path, rows: list[Row], only: set[str]) -> tuple[list[Row], int]:
    """The rows of an ``--only`` run merged into the previous run's table: rows of the suites not
    run now are kept in their places; a previous row is replaced if its suite was run now or (rows
    written before suites were recorded) its case was measured now. Returns (rows, kept)."""
    if not json_path.exists():
        return rows, 0
    try:
        previous = json.loads(json_path.read_text())["rows"]
    except (OSError, ValueError, KeyError) as err:
        log(f"benchmarks: previous rows in {json_path} not kept ({err})")
        return rows, 0
    cases = {r.case for r in rows}
    merged: list[Row] = []
    inserted = False
    kept = 0
    for d in previous:
        if d.get("suite") in only or d.get("case") in cases:
            if not inserted:
                merged += rows
                inserted = True
            continue
        merged.append(Row.from_json(d))
        kept += 1
    if not inserted:
        merged += rows
    return merged, kept


def rows_out_of_sync(out: Path) -> str | None:
    """Why an ``--only`` run into ``out`` would lose rows, or None. The table of ``out`` is
    rebuilt from ``results.json`` beside it, so every row the table shows must be in that file;
    a results.json written by an older ``--only`` run, or none (a fresh clone has the page but
    not the file), can hold fewer rows than the table."""
    json_path = out.with_name("results.json")
    if not out.exists():
        return None
    text = out.read_text()
    section = re.search(r"^## Results$(.*?)^## ", text, flags=re.MULTILINE | re.DOTALL)
    if section is None:
        return None
    shown = sum(1 for line in section.group(1).splitlines() if line.startswith("| ")) - 1
    try:
        stored = len(json.loads(json_path.read_text())["rows"]) if json_path.exists() else 0
    except (OSError, ValueError, KeyError):
        stored = 0
    if shown > stored:
        return (
            f"{out} shows {shown} benchmark rows but {json_path} holds {stored}: an --only run "
            f"would drop {shown - stored} row(s) from the table. Run the full `python -m "
            f"benchmarks` once to bring results.json in line, or pass --out to another file."
        )
    return None


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def render_page(doc: dict[str, Any], rows: list[Row], checks: list[dict[str, Any]]) -> str:
    """The whole of PERFORMANCE.md from a results document (what results.json holds)."""
    threads = doc["mgn_threads"]
    table = markdown_table(rows, threads)
    notes = [f"- {r.case}: {'; '.join(r.notes)}" for r in rows if r.notes]
    kept = doc.get("kept_rows", 0)
    runs = [
        f"`{r['command']}` on {r['date_utc']}, {r['mode']} mode, load average "
        f"{r['load_average_at_start']} at start and {r['load_average_at_end']} at end"
        for r in doc.get("kept_from") or []
    ]
    origin = f", measured by {'; and by '.join(reversed(runs))}" if runs else ""
    kept_note = (
        f" The table keeps {kept} row(s) of other suites from the previous run's results.json"
        f"{origin}."
        if kept
        else ""
    )
    failures = gate_failures(checks)
    verdict = (
        f"**{len(failures)} ratio(s) below their floor.**"
        if failures
        else "Every measured ratio is at or above its floor."
    )
    return "\n".join(
        [
            "# mgn performance",
            "",
            (
                f"Generated by `{doc['command']}` on {doc['date_utc']} ({doc['mode']} mode, "
                f"{doc['repeats']} timed repetitions per call after one warm-up, "
                f"{doc['elapsed_seconds']:.0f} s).{kept_note} The command rewrites this page; "
                "do not edit it. Method: [README.md](README.md)."
            ),
            *([f"\n{doc['provenance']}"] if doc.get("provenance") else []),
            "",
            "## Machine",
            "",
            machine_markdown(doc["machine"]),
            "",
            "## Results",
            "",
            (
                "Rates are the median over the repetitions, with the interquartile range in "
                "brackets. Ratios above 1 mean mgn is faster. Agreement compares the warm-up "
                "results of both sides on every item."
            ),
            "",
            table,
            "",
            "## Gate",
            "",
            (
                "`python -m benchmarks --gate` fails when an mgn / peer ratio is below its floor "
                "(`limits.py`, `FLOORS`). " + verdict
            ),
            "",
            gate_markdown(checks),
            "",
            "## Machine limits",
            "",
            "What the stages are bound by, measured in the same run with all usable cores "
            "(`limits.py`), and the share of it each bound stage reaches.",
            "",
            limits_markdown(doc.get("limits", {})),
            "",
            shares_markdown(doc.get("limit_shares", [])),
            "",
            "## Speed ratios",
            "",
            f"![mgn / peer speed ratios]({PLOT_NAME})",
            "",
            "## Notes",
            "",
            *notes,
            *[f"- {n}" for n in NOTES],
            *([f"\nmgn side: {doc['mgn_status']}"] if doc.get("mgn_status", "ok") != "ok" else []),
            "",
        ]
    )


def write_outputs(out: Path, doc: dict[str, Any], rows: list[Row]) -> list[str]:
    """Writes results.json, the page and its plot (each atomically); returns the gate's
    failures."""
    checks = gate(rows)
    doc["gate"] = checks
    out.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(out.with_name("results.json"), json.dumps(doc, indent=2) + "\n")
    write_atomic(out, render_page(doc, rows, checks))
    plot = out.with_name(PLOT_NAME)
    tmp = plot.with_name(plot.stem + ".tmp.png")
    if plot_ratios(rows, tmp):
        tmp.replace(plot)
    else:
        log("benchmarks: no mgn/peer ratio to plot")
    return gate_failures(checks)


def from_results(json_path: Path, out: Path, check_gate: bool) -> int:
    """Rewrites the page and the plot from a stored results.json (no measuring)."""
    try:
        doc = json.loads(json_path.read_text())
        rows = [Row.from_json(d) for d in doc["rows"]]
    except (OSError, ValueError, KeyError) as err:
        log(f"benchmarks: cannot read {json_path}: {err}")
        return 2
    if json_path.resolve() != out.with_name("results.json").resolve():
        log(f"benchmarks: results.json beside {out} is rewritten from {json_path}")
    failures = write_outputs(out, doc, rows)
    log(f"benchmarks: wrote {out} from {json_path}")
    for f in failures:
        log(f"benchmarks: gate: {f}")
    return 1 if check_gate and failures else 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument(
        "--quick",
        action="store_true",
        help="fewer rays, poses, objects and scenes, 3 repetitions (a few minutes)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=PAGE,
        help="the page; results.json and performance.png go beside it (default: %(default)s)",
    )
    parser.add_argument("--only", choices=sorted(SUITES), action="append", help="run only these")
    parser.add_argument("--repeats", type=int, help="timed repetitions per call (7, quick: 3)")
    parser.add_argument(
        "--gate", action="store_true", help="exit 1 when an mgn / peer ratio is below its floor"
    )
    parser.add_argument(
        "--from-results",
        type=Path,
        metavar="JSON",
        help="rewrite the page and the plot from this results.json; measure nothing",
    )
    args = parser.parse_args(argv)
    if args.from_results:
        return from_results(args.from_results, args.out, args.gate)
    repeats = args.repeats or (3 if args.quick else 7)
    if repeats < 1:
        parser.error("--repeats must be at least 1")

    if args.only:
        problem = rows_out_of_sync(args.out)
        if problem:
            parser.error(problem)

    mgn, mgn_status = import_mgn()
    if mgn is None:
        log(f"benchmarks: {mgn_status}; measuring the peers only")
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    machine = machine_description()
    threads = thread_counts()
    started = time.perf_counter()
    rows = []
    for name in args.only or list(SUITES):
        log(f"benchmarks: {name} ({'quick' if args.quick else 'full'}, {repeats} repetitions)")
        measured = SUITES[name].run(
            quick=args.quick, repeats=repeats, mgn=mgn, mgn_status=mgn_status, log=log
        )
        for r in measured:
            r.suite = name
        rows += measured
    new_rows = list(rows)
    kept = 0
    kept_from = None
    if args.only:
        previous_json = args.out.with_name("results.json")
        rows, kept = merge_previous_rows(previous_json, rows, set(args.only))
        kept_from = previous_runs(previous_json) if kept else None
    log("benchmarks: machine limits")
    limits = measure_limits(mgn, quick=args.quick, repeats=repeats, log=log)
    elapsed = time.perf_counter() - started
    machine["load_average_at_end"] = load_average()
    command = "python -m benchmarks" + "".join(f" {shlex.quote(a)}" for a in argv)
    doc = {
        "command": command,
        "date_utc": date,
        "mode": "quick" if args.quick else "full",
        "repeats": repeats,
        "elapsed_seconds": elapsed,
        "kept_rows": kept,
        **({"kept_from": kept_from} if kept_from else {}),
        "mgn_status": mgn_status or "ok",
        "machine": machine,
        "mgn_threads": threads,
        "rows": [r.to_json() for r in rows],
        "limits": limits,
        "limit_shares": shares(rows, limits),
    }
    print(markdown_table(rows, threads))
    failures = write_outputs(args.out, doc, rows)
    log(f"benchmarks: wrote {args.out}, results.json and {PLOT_NAME} in {elapsed:.0f} s")
    status = 0
    disagree = [r for r in new_rows if r.agreement_ok is False]
    if disagree:
        log(f"benchmarks: {len(disagree)} row(s) where mgn and the peer disagree")
        status = 1
    for f in failures:
        log(f"benchmarks: gate: {f}")
    if args.gate and failures:
        log(f"benchmarks: gate failed: {len(failures)} ratio(s) below their floor")
        status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
