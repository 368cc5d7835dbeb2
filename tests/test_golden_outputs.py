"""Golden comparison: the shipped sample days' outputs stay the same while refactoring.

Both sample days (``protocols/sut2_hull.toml``, the SUT-2 hull day, and
``protocols/naca0015_fin.toml``, the NACA 0015 fin day, whose run files ship in
``sample_runs/``) are processed with their report (the session's ``sample_report``, shared
with the front-door test). Every CSV output, model.json, provenance.json, the cell values of
report.xlsx and the day's warnings are compared, as text, with the copies recorded in
``tests/golden/<day>/``; the pixels of every PDF page and PNG figure are hashed and compared
with ``tests/golden/sample_days.json``. Only what legitimately varies is normalised: the
checkout's absolute path, towtank's, Python's and the libraries' versions.

The text must be the same character for character outside its numbers, and every number the
same within a relative 1e-9 (and 1e-15 absolute, for values that cancel to zero). Exact bytes
would tie the comparison to one processor: the linear algebra (OpenBLAS) picks its kernels by
the processor, and their rounding differs in the last bits. Measured on the sample hull day with
OpenBLAS's Prescott kernels against its Haswell ones on one machine: 267 numbers differed, the
largest by 1.1e-12 relative (coefficients.csv), and every pixel was the same; on the fin day,
213 numbers, the largest by 2.0e-13 relative (fins.csv). A refactor that
changes a result changes it by far more than 1e-9.

The pixels depend on the drawing and rendering libraries (matplotlib, FreeType through it,
PDFium): they are compared when those are the versions the golden set was recorded with (stored
beside it), and a changed version is said in a warning rather than failing the refactor's check.

To record a new golden set after an intended change of the outputs::

    TOWTANK_WRITE_GOLDEN=1 python -m pytest -q tests/test_golden_outputs.py
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import warnings
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from towtank.report.workbook import write_workbook

ROOT = Path(__file__).resolve().parents[1]
GOLDEN_DIR = ROOT / "tests" / "golden"
GOLDEN = GOLDEN_DIR / "sample_days.json"  # the pixels' hashes and the renderer's versions
DAYS = ("sut2_hull", "naca0015_fin")
VARYING = ("version", "python", "libraries")  # provenance.json keys that legitimately vary
PIXELS = "pixels"  # the digest entries that depend on the renderer's versions
RTOL = 1e-9  # relative tolerance of every number (the module's docstring says why)
ATOL = 1e-15  # absolute tolerance, for numbers that cancel to zero

# A number standing on its own: not a piece of a word, a file name or a hex digest.
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?![\w.])")


def _normalise(text: str) -> str:
    return text.replace(str(ROOT), "<root>")


def _workbook_cells(path: Path) -> str:
    from openpyxl import load_workbook

    wb = load_workbook(path, read_only=True)
    lines = []
    for ws in wb.worksheets:
        lines.append(f"## {ws.title}")
        for row in ws.iter_rows(values_only=True):
            lines.append(repr(row))
    wb.close()
    return _normalise("\n".join(lines)) + "\n"


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


def day_texts(day: Any, out: Path, book: Path) -> dict[str, str]:
    """Every normalised text output of one sample day (``day``, processed with its report into
    ``out``), by the name of its golden copy; the workbook is written again into ``book``."""
    texts: dict[str, str] = {}
    for path in sorted(out.iterdir()):
        if path.suffix == ".csv" or path.name == "model.json":
            texts[path.name] = _normalise(path.read_text(encoding="utf-8"))
    prov: dict[str, Any] = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    for key in VARYING:
        prov.pop(key, None)
    texts["provenance.json"] = _normalise(json.dumps(prov, sort_keys=True, indent=1)) + "\n"
    texts["report.xlsx.cells.txt"] = _workbook_cells(write_workbook(day, book))
    texts["warnings.txt"] = _normalise("\n".join(str(n) for n in day.warnings)) + "\n"
    return texts


def day_pixels(out: Path) -> dict[str, str]:
    """sha256 of the pixels of the day's report.pdf and of every figure, by name."""
    digest = {f"report.pdf ({PIXELS})": _pdf_pixels(out / "report.pdf")}
    for png in sorted((out / "figures").glob("*.png")):
        digest[f"figures/{png.name} ({PIXELS})"] = _png_pixels(png)
    return digest


def _close(want: str, got: str) -> bool:
    a, b = float(want), float(got)
    return math.isclose(a, b, rel_tol=RTOL, abs_tol=ATOL)


def text_difference(want: str, got: str) -> str | None:
    """Where ``got`` differs from ``want``: None when the two are the same character for
    character outside their numbers and every number is the same within RTOL (relative) or
    ATOL (absolute); else one sentence naming the first line that differs."""
    want_lines, got_lines = want.splitlines(), got.splitlines()
    if len(want_lines) != len(got_lines):
        return f"{len(got_lines)} lines where {len(want_lines)} were recorded"
    for i, (w, g) in enumerate(zip(want_lines, got_lines, strict=True), start=1):
        if w == g:
            continue
        w_nums, g_nums = NUMBER.findall(w), NUMBER.findall(g)
        if (NUMBER.sub("#", w) != NUMBER.sub("#", g) or len(w_nums) != len(g_nums)
                or not all(_close(x, y) for x, y in zip(w_nums, g_nums, strict=True))):
            return f"line {i}: recorded {w[:200]!r}, now {g[:200]!r}"
    return None


@pytest.mark.parametrize("name", DAYS)
def test_sample_day_outputs_match_golden(name: str, tmp_path: Path, sample_report) -> None:
    written = sample_report(name)  # towtank.process_day(protocol, out=..., report=True)
    texts = day_texts(written.day, written.out, tmp_path)
    pixels = day_pixels(written.out)
    folder = GOLDEN_DIR / name
    if os.environ.get("TOWTANK_WRITE_GOLDEN"):
        stored = json.loads(GOLDEN.read_text()) if GOLDEN.is_file() else {}
        stored[name] = pixels
        stored["renderer"] = renderer()
        GOLDEN.write_text(json.dumps(stored, indent=2, sort_keys=True) + "\n")
        folder.mkdir(exist_ok=True)
        for old in folder.iterdir():
            old.unlink()
        for file, text in texts.items():
            (folder / file).write_text(text, encoding="utf-8")
    recorded = {p.name: p.read_text(encoding="utf-8") for p in sorted(folder.iterdir())}
    problems = [f"{file}: not written now" for file in sorted(set(recorded) - set(texts))]
    problems += [f"{file}: not recorded" for file in sorted(set(texts) - set(recorded))]
    for file in sorted(set(texts) & set(recorded)):
        where = text_difference(recorded[file], texts[file])
        if where:
            problems.append(f"{file}: {where}")
    stored = json.loads(GOLDEN.read_text())
    if stored.get("renderer") != renderer():
        warnings.warn(f"pixels not compared: recorded with {stored.get('renderer')}, drawn "
                      f"with {renderer()}", stacklevel=1)
    else:
        want = stored[name]
        problems += [f"{k}: differs" for k in sorted(set(want) | set(pixels))
                     if want.get(k) != pixels.get(k)]
    assert not problems, f"{name}: outputs differ from tests/golden: " + "; ".join(problems)


# ------------------------------------------------------------------ the comparison itself
def test_text_difference_tolerates_the_last_bits_only() -> None:
    row = "3,run_003.csv.gz,sting,0.0,ok,,0.3000090389957688,7.062584458194057,557d07f0,2024-05-21"
    assert text_difference(row, row) is None
    # the largest difference measured between two OpenBLAS kernels (1.1e-12 relative)
    assert text_difference(row, row.replace("7.062584458194057", "7.062584458201624")) is None
    # a result changed in its eighth significant digit (1.4e-8); a word, a file name, a digest,
    # a date, a field changed
    for changed in ("7.062584458194057", "7.062584558194057"), ("sting", "strut"), \
            ("run_003", "run_004"), ("557d07f0", "557d07f1"), ("2024-05-21", "2024-05-22"), \
            ("0.0,ok", "0.0,ok,"):
        assert text_difference(row, row.replace(*changed)) is not None, changed
    assert text_difference(row, row + "\n" + row) is not None
    # numbers that cancel to zero: a difference below ATOL is the last bits of a zero
    assert text_difference("x=1e-17", "x=-3.2e-16") is None
    assert text_difference("x=1e-17", "x=2e-11") is not None


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), min_size=1,
                max_size=8), st.integers(-4, 4))
def test_text_difference_accepts_a_few_ulps(values: list[float], ulps: int) -> None:
    want = ",".join(repr(v) for v in values)
    moved = [v if not math.isfinite(v + math.ulp(v) * ulps) else v + math.ulp(v) * ulps
             for v in values]
    assert text_difference(want, ",".join(repr(v) for v in moved)) is None


@given(st.lists(st.floats(min_value=1e-3, max_value=1e6), min_size=1, max_size=8),
       st.integers(0, 7), st.floats(min_value=1e-8, max_value=1e3))
def test_text_difference_finds_a_changed_result(values: list[float], which: int,
                                                change: float) -> None:
    which %= len(values)
    want = ",".join(repr(v) for v in values)
    changed = list(values)
    changed[which] = values[which] * (1 + change)
    assert text_difference(want, ",".join(repr(v) for v in changed)) is not None
