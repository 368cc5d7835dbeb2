"""Golden comparison: the shipped sample days' outputs stay byte-identical while refactoring.

Both sample days (``protocols/sut2_hull.toml``, the SUT-2 hull day, and
``protocols/naca0015_fin.toml``, the NACA 0015 fin day, whose run files ship in
``sample_runs/``) are processed with their report (the session's ``sample_report``, shared
with the front-door test) and every CSV output, model.json, provenance.json, the cell
values of report.xlsx, the day's warnings and the pixels of every PDF page and PNG figure are
hashed and compared with ``tests/golden/sample_days.json``. Only what legitimately varies is
normalised: the checkout's absolute path, towtank's, Python's and the libraries' versions. The
pixels depend on the drawing and rendering libraries too (matplotlib, FreeType through it, PDFium):
they are compared when those are the versions the golden set was recorded with (stored beside it),
and a changed version is said in a warning rather than failing the refactor's check.

To record a new golden set after an intended change of the outputs::

    TOWTANK_WRITE_GOLDEN=1 python -m pytest -q tests/test_golden_outputs.py
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from pathlib import Path
from typing import Any

import pytest

from towtank.report.workbook import write_workbook

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden" / "sample_days.json"
DAYS = ("sut2_hull", "naca0015_fin")
VARYING = ("version", "python", "libraries")  # provenance.json keys that legitimately vary
PIXELS = "pixels"  # the digest entries that depend on the renderer's versions


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


def renderer() -> str:
    """The versions the pixels depend on: matplotlib (it draws and embeds the fonts), PDFium."""
    from importlib.metadata import version

    import matplotlib

    return f"matplotlib {matplotlib.__version__}, pypdfium2 {version('pypdfium2')}"


def _pdf_pixels(path: Path) -> str:
    """sha256 of every page of a PDF rendered at 80 dpi (RGB), page after page."""
    import pypdfium2

    h = hashlib.sha256()
    pdf = pypdfium2.PdfDocument(path)
    try:
        for page in pdf:
            bitmap = page.render(scale=80 / 72)
            h.update(bitmap.to_pil().convert("RGB").tobytes())
            page.close()
    finally:
        pdf.close()
    return h.hexdigest()


def _png_pixels(path: Path) -> str:
    """sha256 of a PNG's decoded pixels (its metadata, e.g. matplotlib's version, left out)."""
    from PIL import Image

    with Image.open(path) as image:
        return hashlib.sha256(image.convert("RGBA").tobytes()).hexdigest()


def day_digest(day: Any, out: Path, book: Path) -> dict[str, str]:
    """sha256 of every normalised output of one sample day (``day``, processed with its report
    into ``out``), by file name; the workbook is written again into ``book`` from ``day``."""
    digest: dict[str, str] = {}
    for path in sorted(out.iterdir()):
        if path.suffix == ".csv" or path.name == "model.json":
            digest[path.name] = _sha(_normalise(path.read_text(encoding="utf-8")))
    prov: dict[str, Any] = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    for key in VARYING:
        prov.pop(key, None)
    digest["provenance.json"] = _sha(_normalise(json.dumps(prov, sort_keys=True)))
    digest["report.xlsx (cells)"] = _sha(_workbook_cells(write_workbook(day, book)))
    digest["warnings"] = _sha(_normalise("\n".join(str(n) for n in day.warnings)))
    digest[f"report.pdf ({PIXELS})"] = _pdf_pixels(out / "report.pdf")
    for png in sorted((out / "figures").glob("*.png")):
        digest[f"figures/{png.name} ({PIXELS})"] = _png_pixels(png)
    return digest


@pytest.mark.parametrize("name", DAYS)
def test_sample_day_outputs_match_golden(name: str, tmp_path: Path, sample_report) -> None:
    written = sample_report(name)  # towtank.process_day(protocol, out=..., report=True)
    got = day_digest(written.day, written.out, tmp_path)
    if os.environ.get("TOWTANK_WRITE_GOLDEN"):
        stored = json.loads(GOLDEN.read_text()) if GOLDEN.is_file() else {}
        stored[name] = got
        stored["renderer"] = renderer()
        GOLDEN.write_text(json.dumps(stored, indent=2, sort_keys=True) + "\n")
    stored = json.loads(GOLDEN.read_text())
    want = stored[name]
    if stored.get("renderer") != renderer():
        warnings.warn(f"pixels not compared: recorded with {stored.get('renderer')}, drawn "
                      f"with {renderer()}", stacklevel=1)
        want = {k: v for k, v in want.items() if PIXELS not in k}
        got = {k: v for k, v in got.items() if PIXELS not in k}
    changed = sorted(k for k in set(want) | set(got) if want.get(k) != got.get(k))
    assert not changed, f"{name}: outputs differ from tests/golden: {changed}"
