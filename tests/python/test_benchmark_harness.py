"""The benchmark harness: the generated page keeps its table whole (an ``--only`` run rebuilds the
table from results.json, so it must refuse when that file holds fewer rows than the page shows),
and the regression gate fails exactly when an mgn / peer ratio is below its floor."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks.__main__ import main, previous_runs, render_page, rows_out_of_sync
from benchmarks.common import Row, Timing
from benchmarks.limits import FLOORS, Floor, gate, gate_failures


def _write(folder: Path, table_rows: int, json_rows: int) -> Path:
    lines = ["# mgn performance", "", "## Results", "", "| benchmark | N |", "|---|---|"]
    lines += [f"| case {i} | 1 |" for i in range(table_rows)]
    lines += ["", "## Gate", "", "| row | verdict |", "|---|---|", "| case 0 | pass |"]
    out = folder / "PERFORMANCE.md"
    out.write_text("\n".join(lines) + "\n")
    (folder / "results.json").write_text(
        json.dumps({"rows": [{"case": f"case {i}"} for i in range(json_rows)]})
    )
    return out


def test_an_only_run_is_refused_when_results_json_lacks_rows_of_the_table(tmp_path: Path) -> None:
    out = _write(tmp_path, table_rows=3, json_rows=1)
    problem = rows_out_of_sync(out)
    assert problem is not None
    assert "shows 3 benchmark rows" in problem
    assert "holds 1" in problem


def test_an_only_run_is_allowed_when_results_json_holds_every_row(tmp_path: Path) -> None:
    assert rows_out_of_sync(_write(tmp_path, table_rows=3, json_rows=3)) is None
    assert rows_out_of_sync(tmp_path / "missing.md") is None


def _row(group: str, case: str, mgn_seconds: dict[int, float], peer_seconds: float | None) -> Row:
    """A row of n = 100 items: mgn took mgn_seconds[threads] per call, the peer peer_seconds."""
    row = Row(group=group, case=case, n=100, unit="items/s", peer_name="peer.call")
    row.mgn = {t: Timing(wall=[s, s, s], cpu=[s, s, s]) for t, s in mgn_seconds.items()}
    if peer_seconds is not None:
        row.peer = Timing(wall=[peer_seconds] * 3, cpu=[peer_seconds] * 3)
    return row


def test_the_gate_compares_the_stated_ratio_with_its_floor() -> None:
    floors = (
        Floor("ray casting", r"^icosphere.*random rays", 1.0),  # per core
        Floor("rendering", r"RGB", 6.0, None),  # the most threads measured
        Floor("lens", r"^resample", 0.5),
        Floor("collision", r"collide", 0.6),  # its suite not run
    )
    rows = [
        # mgn 1 thread 0.5 s, 2 threads 0.2 s, peer 0.8 s: ratio 1.6 (1T), 4.0 (2T).
        _row("ray casting", "icosphere, 1,000 random rays, first hit", {1: 0.5, 2: 0.2}, 0.8),
        # 2 threads only: 0.1 s against 0.5 s = 5.0 < 6.
        _row("rendering", "20 objects, RGB + depth", {2: 0.1}, 0.5),
        # No peer timing: not measured.
        _row("lens", "resample RGB", {1: 0.1}, None),
        _row("layout", "no floor names this row", {1: 1.0}, 0.01),
    ]
    checks = gate(rows, floors)
    by_row = {c["row"].split(":")[0]: c for c in checks}
    assert by_row["ray casting"]["threads"] == 1
    assert abs(by_row["ray casting"]["ratio"] - 1.6) < 1e-9
    assert by_row["ray casting"]["verdict"] == "pass"
    assert by_row["rendering"]["threads"] == 2
    assert abs(by_row["rendering"]["ratio"] - 5.0) < 1e-9
    assert by_row["rendering"]["verdict"] == "FAIL"
    assert by_row["lens"]["verdict"] == "not measured"
    assert by_row["collision"]["verdict"] == "not measured"
    assert "layout" not in by_row
    failures = gate_failures(checks)
    assert len(failures) == 1
    assert "rendering" in failures[0]
    assert "5.00x" in failures[0]


def test_every_floor_is_positive_and_names_a_suite_group() -> None:
    groups = {
        "ray casting",
        "collision",
        "suction seal",
        "parallel-jaw",
        "physics",
        "scene drop",
        "rendering",
        "path tracing",
        "layout",
        "lens",
        "view labels",
        "dataset files",
    }
    for f in FLOORS:
        assert f.floor > 0, f
        assert f.group in groups, f
        assert f.threads in (1, None), f


def test_the_page_is_rewritten_from_stored_results_and_the_gate_fails(tmp_path: Path) -> None:
    rows = [
        _row("collision", "torus vs ellipsoid, collide (boolean)", {1: 1.0, 2: 0.5}, 0.5),
        _row("lens", "undistortion map, 100×100", {1: 0.1}, 0.2),
    ]
    doc = {
        "command": "python -m benchmarks --only collision --only lens",
        "date_utc": "2026-12-06 12:00 UTC",
        "mode": "full",
        "repeats": 3,
        "elapsed_seconds": 1.0,
        "mgn_status": "ok",
        "machine": {
            "cpu_model": "test CPU",
            "logical_cpus": 2,
            "physical_cores": 2,
            "usable_cpus": 2,
            "ram_gib": 1.0,
            "os": "test OS",
            "kernel": "0",
            "python": "3",
            "mgn_revision": "abc1234",
            "load_average_at_start": "0 0 0",
            "versions": {},
        },
        "mgn_threads": [1, 2],
        "rows": [r.to_json() for r in rows],
        "limits": {},
        "limit_shares": [],
    }
    stored = tmp_path / "stored.json"
    stored.write_text(json.dumps(doc))
    out = tmp_path / "page" / "PERFORMANCE.md"
    # The collide row's per-core ratio is 0.5, below its floor of 0.6: the gate fails.
    assert main(["--from-results", str(stored), "--out", str(out), "--gate"]) == 1
    page = out.read_text()
    assert "Generated by `python -m benchmarks --only collision --only lens` on 2026-12-06" in page
    assert "test CPU" in page
    assert "abc1234" in page
    failed = "| collision: torus vs ellipsoid, collide (boolean) | 1 | 0.50× | 0.60× | **FAIL** |"
    assert failed in page
    assert "| lens: undistortion map, 100×100 | 1 | 2.00× | 0.40× | pass |" in page
    assert (out.parent / "performance.png").stat().st_size > 0
    assert json.loads((out.parent / "results.json").read_text())["rows"] == doc["rows"]
    assert rows_out_of_sync(out) is None  # results.json beside the page holds every row
    # Without --gate the page is written and the run succeeds.
    assert main(["--from-results", str(stored), "--out", str(out)]) == 0


def test_an_only_run_names_the_runs_whose_rows_it_keeps(tmp_path: Path) -> None:
    rows = [_row("lens", "undistortion map, 100×100", {1: 0.1}, 0.2)]
    machine = {"load_average_at_start": "0.1 0.2 0.3", "load_average_at_end": "1.0 1.1 1.2"}
    older = {
        "command": "python -m benchmarks",
        "date_utc": "2026-12-06 10:00 UTC",
        "mode": "full",
        "machine": machine,
        "kept_rows": 0,
        "rows": [],
    }
    (tmp_path / "results.json").write_text(json.dumps(older))
    assert previous_runs(tmp_path / "results.json") == [
        {
            "command": "python -m benchmarks",
            "date_utc": "2026-12-06 10:00 UTC",
            "mode": "full",
            "load_average_at_start": "0.1 0.2 0.3",
            "load_average_at_end": "1.0 1.1 1.2",
        }
    ]
    # A run that itself kept rows passes on where they came from, newest first.
    newer = dict(
        older,
        command="python -m benchmarks --only lens",
        kept_rows=3,
        kept_from=previous_runs(tmp_path / "results.json"),
    )
    (tmp_path / "results.json").write_text(json.dumps(newer))
    runs = previous_runs(tmp_path / "results.json")
    assert [r["command"] for r in runs] == [
        "python -m benchmarks --only lens",
        "python -m benchmarks",
    ]
    assert previous_runs(tmp_path / "missing.json") == []
    doc = dict(
        newer,
        repeats=3,
        elapsed_seconds=1.0,
        mgn_status="ok",
        mgn_threads=[1],
        rows=[r.to_json() for r in rows],
        limits={},
        limit_shares=[],
        kept_from=runs,
        machine=dict(
            machine,
            cpu_model="c",
            logical_cpus=2,
            physical_cores=2,
            usable_cpus=2,
            ram_gib=1.0,
            os="o",
            kernel="k",
            python="3",
            mgn_revision="r",
            versions={},
        ),
    )
    page = render_page(doc, rows, gate(rows))
    assert "keeps 3 row(s) of other suites" in page
    assert (
        "measured by `python -m benchmarks` on 2026-12-06 10:00 UTC, full mode, load average "
        "0.1 0.2 0.3 at start and 1.0 1.1 1.2 at end; and by `python -m benchmarks --only lens`"
    ) in page
