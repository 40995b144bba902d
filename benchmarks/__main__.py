"""Entry point: `python -m benchmarks [--quick] [--out benchmarks/RESULTS.md]`."""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

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
from .limits import limits_markdown, measure_limits, plot_ratios, shares, shares_markdown

HERE = Path(__file__).resolve().parent
SUITES = {
    "raycast": bench_raycast,
    "collision": bench_collision,
    "seal": bench_seal,
    "pj": bench_pj,
    "object_labels": bench_object_labels,
    "shake": bench_shake,
    "drop": bench_drop,
    "render": bench_render,
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


#: The generated part of RESULTS.md lies between these lines; the sections after it are written
#: by hand (studies measured outside this harness) and survive a rerun.
GENERATED_BEGIN = "<!-- generated:begin -->"
GENERATED_END = "<!-- generated:end -->"


def write_keeping_hand_written(out: Path, report: str) -> None:
    """Writes ``report`` (the generated part) into ``out``, keeping what ``out`` has before and
    after its generated part. A file from before these markers: everything from its first
    ``<!-- name:begin -->`` line on is kept. Written to a temporary file, then renamed."""
    head, tail = "", "\n"
    if out.exists():
        old = out.read_text()
        if GENERATED_BEGIN in old and GENERATED_END in old:
            head = old[: old.index(GENERATED_BEGIN)]
            tail = old[old.index(GENERATED_END) + len(GENERATED_END) :]
        else:
            m = re.search(r"^<!-- [\w-]+:begin -->$", old, flags=re.M)
            if m:
                tail = "\n\n" + old[m.start() :]
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(head + report + tail)
    tmp.replace(out)


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
    a results.json written by an older ``--only`` run can hold fewer rows than the table."""
    json_path = out.with_name("results.json")
    if not out.exists():
        return None
    text = out.read_text()
    section = re.search(r"^## Results$(.*?)^## ", text, flags=re.M | re.S)
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument(
        "--quick",
        action="store_true",
        help="2e5 rays, 2,000 poses, 3 repetitions (< 2 min)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=HERE / "RESULTS.md",
        help="Markdown report; results.json is written next to it (default: %(default)s)",
    )
    parser.add_argument("--only", choices=sorted(SUITES), action="append", help="run only these")
    parser.add_argument("--repeats", type=int, help="timed repetitions per call (7, quick: 3)")
    args = parser.parse_args(argv)
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
    json_path = args.out.with_name("results.json")
    new_rows = list(rows)
    kept = 0
    if args.only:
        rows, kept = merge_previous_rows(json_path, rows, set(args.only))
    log("benchmarks: machine limits")
    limits = measure_limits(mgn, quick=args.quick, repeats=repeats, log=log)
    stage_shares = shares(rows, limits)
    elapsed = time.perf_counter() - started
    machine["load_average_at_end"] = load_average()

    table = markdown_table(rows, threads)
    notes = [f"- {r.case}: {'; '.join(r.notes)}" for r in rows if r.notes]
    mode = "quick" if args.quick else "full"
    only = "".join(f" --only {n}" for n in args.only or [])
    kept_note = (
        f" The table keeps {kept} row(s) of other suites from the previous run's results.json."
        if kept
        else ""
    )
    report = "\n".join(
        [
            GENERATED_BEGIN,
            "# mgn benchmark results",
            "",
            (
                f"Generated by `python -m benchmarks{' --quick' if args.quick else ''}{only}` "
                f"({mode} mode, {repeats} timed repetitions per call after one warm-up, "
                f"{elapsed:.0f} s).{kept_note} See README.md for the method."
            ),
            "",
            "## Machine",
            "",
            machine_markdown(machine),
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
            "## Machine limits",
            "",
            "What the stages are bound by, measured in the same run with all usable cores "
            "(benchmarks/limits.py), and the share of it each bound stage reaches.",
            "",
            limits_markdown(limits),
            "",
            shares_markdown(stage_shares),
            "",
            "## Speed ratios",
            "",
            "![mgn / peer speed ratios](ratios.png)",
            "",
            "## Notes",
            "",
            *notes,
            "- embreex bundles Embree 4; mgn links Debian's Embree 3.13: the ray-casting rows "
            "compare two Embree versions as well as two wrappers.",
            "- Peer time includes the Python work around the library call (trimesh's hit-point "
            "computation, python-fcl's loop): it is what a user of the peer pays.",
            "",
            *([f"mgn side: {mgn_status}", ""] if mgn is None else []),
            GENERATED_END,
        ]
    )
    print(table)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_keeping_hand_written(args.out, report)
    json_path.write_text(
        json.dumps(
            {
                "mode": mode,
                "repeats": repeats,
                "elapsed_seconds": elapsed,
                "mgn_status": mgn_status or "ok",
                "machine": machine,
                "mgn_threads": threads,
                "rows": [r.to_json() for r in rows],
                "limits": limits,
                "limit_shares": stage_shares,
            },
            indent=2,
        )
        + "\n"
    )
    plot_path = args.out.with_name("ratios.png")
    if not plot_ratios(rows, plot_path):
        log("benchmarks: no mgn/peer ratio to plot")
    log(f"benchmarks: wrote {args.out}, {json_path} and {plot_path} in {elapsed:.0f} s")
    failed = [r for r in new_rows if r.agreement_ok is False]
    if failed:
        log(f"benchmarks: {len(failed)} row(s) where mgn and the peer disagree")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
