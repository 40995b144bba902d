"""Product text says what a thing is, its unit, range and default; the history of how it got there
lives in CHANGELOG.md and docs/decisions/ only. These tests read README.md, docs/ (without
docs/decisions/), the public C++ headers and the Python package line by line."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: Work rounds, issue numbers and "this machine" are history, not product text.
HISTORY = re.compile(r"session [0-9]|issue [0-9]|this machine", re.IGNORECASE)

#: Files and folders (ending in "/") allowed to name history; none.
HISTORY_ALLOWED: tuple[str, ...] = ()


def _allowed(rel: str) -> bool:
    return any(rel == a or (a.endswith("/") and rel.startswith(a)) for a in HISTORY_ALLOWED)


#: Files that must not be cited any more: the study log and the study outputs removed from
#: benchmarks/ (kept in the repository's history).
REMOVED = re.compile(
    r"benchmarks/(RESULTS\.md|path_results\.|path_crop_results\.|ratios\.png|path\.png)"
)

SUFFIXES = {".md", ".py", ".pyi", ".hpp", ".h", ".txt"}


def _product_files() -> list[Path]:
    files = [ROOT / "README.md"]
    for folder in ("docs", "cpp/include", "python"):
        for p in sorted((ROOT / folder).rglob("*")):
            if not p.is_file() or p.suffix not in SUFFIXES:
                continue
            if (ROOT / "docs" / "decisions") in p.parents:
                continue
            files.append(p)
    return files


def _offending_lines(pattern: re.Pattern[str]) -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for p in _product_files():
        rel = p.relative_to(ROOT).as_posix()
        for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            if pattern.search(line):
                found.setdefault(rel, []).append(f"{rel}:{n}: {line.strip()}")
    return found


def test_product_text_names_no_work_round_issue_or_machine() -> None:
    found = _offending_lines(HISTORY)
    bad = [line for rel, lines in found.items() if not _allowed(rel) for line in lines]
    assert not bad, (
        "history in product text (move it to CHANGELOG.md or a docs/decisions/ record):\n"
        + "\n".join(bad)
    )


def test_product_text_cites_no_removed_study_file() -> None:
    found = _offending_lines(REMOVED)
    bad = [line for rel, lines in found.items() if not _allowed(rel) for line in lines]
    assert not bad, "citations of files removed from benchmarks/:\n" + "\n".join(bad)


def test_the_allow_list_names_existing_paths() -> None:
    missing = [a for a in HISTORY_ALLOWED if not (ROOT / a).exists()]
    assert not missing, f"HISTORY_ALLOWED names paths that do not exist: {missing}"


def test_every_cited_decision_record_exists_and_is_indexed() -> None:
    folder = ROOT / "docs" / "decisions"
    records = {p.name for p in folder.glob("[0-9][0-9][0-9][0-9]-*.md")}
    assert records, "docs/decisions/ holds no record"
    index = (folder / "README.md").read_text(encoding="utf-8")
    unindexed = sorted(r for r in records if f"({r})" not in index)
    assert not unindexed, f"records missing from docs/decisions/README.md: {unindexed}"
    sources = _product_files() + sorted((ROOT / "third_party_notes").glob("*.md"))
    sources += [ROOT / "CHANGELOG.md", ROOT / "cpp" / "CMakeLists.txt"]
    sources += sorted((ROOT / "cpp" / "src").rglob("*.hpp")) + sorted(folder.glob("*.md"))
    cited = re.compile(r"decisions/([0-9]{4}-[a-z0-9-]+\.md)")
    missing = []
    for p in sources:
        for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            for m in cited.finditer(line):
                if m.group(1) not in records:
                    missing.append(f"{p.relative_to(ROOT)}:{n}: {m.group(1)}")
    assert not missing, "citations of decision records that do not exist:\n" + "\n".join(missing)
