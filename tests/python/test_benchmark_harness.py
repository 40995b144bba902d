"""The benchmark harness keeps the generated table whole: an ``--only`` run rebuilds the table from
results.json, so it must refuse when that file holds fewer rows than the table shows."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks.__main__ import rows_out_of_sync


def _write(folder: Path, table_rows: int, json_rows: int) -> Path:
    lines = ["# mgn benchmark results", "", "## Results", "", "| benchmark | N |", "|---|---|"]
    lines += [f"| case {i} | 1 |" for i in range(table_rows)]
    lines += ["", "## Machine limits", "", "| limit | value |", "|---|---|", "| cores | 2 |"]
    out = folder / "RESULTS.md"
    out.write_text("\n".join(lines) + "\n")
    (folder / "results.json").write_text(
        json.dumps({"rows": [{"case": f"case {i}"} for i in range(json_rows)]})
    )
    return out


def test_an_only_run_is_refused_when_results_json_lacks_rows_of_the_table(tmp_path: Path) -> None:
    out = _write(tmp_path, table_rows=3, json_rows=1)
    problem = rows_out_of_sync(out)
    assert problem is not None
    assert "shows 3 benchmark rows" in problem and "holds 1" in problem


def test_an_only_run_is_allowed_when_results_json_holds_every_row(tmp_path: Path) -> None:
    assert rows_out_of_sync(_write(tmp_path, table_rows=3, json_rows=3)) is None
    assert rows_out_of_sync(tmp_path / "missing.md") is None
