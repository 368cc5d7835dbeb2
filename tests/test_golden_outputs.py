"""Golden comparison: the shipped sample days' outputs stay byte-identical while refactoring.

Both sample days (``protocols/sut2_hull.toml``, the SUT-2 hull day, and
``protocols/naca0015_fin.toml``, the NACA 0015 fin day, whose run files ship in
``sample_runs/``) are processed and every CSV output, model.json, provenance.json, the cell
values of report.xlsx and the day's warnings are hashed and compared with
``tests/golden/sample_days.json``. Only what legitimately varies is normalised: the checkout's
absolute path, towtank's, Python's and the libraries' versions.

To record a new golden set after an intended change of the outputs::

    TOWTANK_WRITE_GOLDEN=1 python -m pytest -q tests/test_golden_outputs.py
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import pytest

import towtank
from towtank.report.workbook import write_workbook

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden" / "sample_days.json"
DAYS = ("sut2_hull", "naca0015_fin")
VARYING = ("version", "python", "libraries")  # provenance.json keys that legitimately vary


def _normalise(text: str) -> str:
    return text.replace(str(ROOT), "<root>")


def _sha(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _workbook_cells(path: Path) -> str:
    from openpyxl import load_workbook

    wb = load_workbook(path, read_only=True)
    lines = []
    for ws in wb.worksheets:
        lines.append(f"## {ws.title}")
        for row in ws.iter_rows(values_only=True):
            lines.append(repr(row))
    wb.close()
    return _normalise("\n".join(lines))


def day_digest(name: str, out: Path) -> dict[str, str]:
    """sha256 of every normalised output of one sample day, by file name."""
    day = towtank.process_day(ROOT / "protocols" / f"{name}.toml", out=out, jobs=2,
                              report=False, cache=False)
    digest: dict[str, str] = {}
    for path in sorted(out.iterdir()):
        if path.suffix == ".csv" or path.name == "model.json":
            digest[path.name] = _sha(_normalise(path.read_text(encoding="utf-8")))
    prov: dict[str, Any] = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    for key in VARYING:
        prov.pop(key, None)
    digest["provenance.json"] = _sha(_normalise(json.dumps(prov, sort_keys=True)))
    book = out / "book"
    book.mkdir()
    digest["report.xlsx (cells)"] = _sha(_workbook_cells(write_workbook(day, book)))
    digest["warnings"] = _sha(_normalise("\n".join(str(n) for n in day.warnings)))
    return digest


@pytest.mark.parametrize("name", DAYS)
def test_sample_day_outputs_match_golden(name: str, tmp_path: Path) -> None:
    got = day_digest(name, tmp_path / name)
    if os.environ.get("TOWTANK_WRITE_GOLDEN"):
        stored = json.loads(GOLDEN.read_text()) if GOLDEN.is_file() else {}
        stored[name] = got
        GOLDEN.write_text(json.dumps(stored, indent=2, sort_keys=True) + "\n")
    want = json.loads(GOLDEN.read_text())[name]
    changed = sorted(k for k in set(want) | set(got) if want.get(k) != got.get(k))
    assert not changed, f"{name}: outputs differ from tests/golden: {changed}"
