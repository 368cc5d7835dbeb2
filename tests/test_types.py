"""The static checks: mypy, configured by pyproject.toml's ``[tool.mypy]``, finds no error in
towtank/ (issue 24), and ruff (``[tool.ruff]``) finds nothing in towtank/ and tests/. Both are
in the ``test`` extra, so the README's test command, and CI, run these checks."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "pyproject.toml"

BAD_MODULE = (
    "def first(x: int | None) -> int:\n"
    "    return x + 1\n"
    "\n"
    "\n"
    "def untyped():\n"
    "    return 1 + 'a'\n"
)


def _mypy(targets: list[str]) -> tuple[int, str]:
    """mypy's exit status and its report (stdout and stderr) for ``targets``, with the
    project's configuration and no cache written (one run checks them all). mypy runs in a
    process of its own: in this one it would leave ≈ 1.5 million objects of its own behind,
    which every later garbage collection of the test process would go through."""
    import mypy  # noqa: F401 - a test dependency: missing, the suite fails rather than skips

    done = subprocess.run([sys.executable, "-m", "mypy", "--config-file", str(CONFIG),
                           "--cache-dir", os.devnull, "--show-error-codes", *targets],
                          capture_output=True, text=True, timeout=600, check=False)
    return done.returncode, done.stdout + done.stderr


@pytest.fixture(scope="session")
def report(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, str]:
    """One mypy run over towtank/ and a module with two known errors (checking towtank/ is
    the whole cost; the second module adds nothing to it)."""
    bad = tmp_path_factory.mktemp("mypy_bad") / "bad_module.py"
    bad.write_text(BAD_MODULE, encoding="utf-8")
    return _mypy([str(ROOT / "towtank"), str(bad)])


@pytest.mark.heavy
def test_towtank_has_no_type_error(report: tuple[int, str]) -> None:
    """Every error mypy reports is in the known-bad module: none in towtank/."""
    status, text = report
    errors = [line for line in text.splitlines() if re.search(r":\d+: error:", line)]
    in_towtank = [line for line in errors if "bad_module.py:" not in line]
    assert status in (0, 1) and not in_towtank, f"mypy found type errors in towtank:\n{text}"
    summary = re.search(r"Found (\d+) errors? in (\d+) files? \(checked (\d+) source files\)",
                        text)
    assert summary is not None, text
    assert summary.group(2) == "1", f"errors in more files than the known-bad one:\n{text}"
    assert int(summary.group(3)) > 100, f"towtank's modules were not all checked:\n{text}"


@pytest.mark.heavy
def test_the_configuration_catches_errors(report: tuple[int, str]) -> None:
    """The check can fail: under the project's configuration mypy reports an unchecked None
    and, in a function without annotations (check_untyped_defs), a str added to an int."""
    status, text = report
    assert status == 1, text
    assert "bad_module.py:2: error" in text and "[operator]" in text, text
    assert "bad_module.py:6: error" in text, text


def _ruff(targets: list[str]) -> tuple[int, str]:
    """ruff's exit status and report for ``targets``, with the project's ``[tool.ruff]``
    configuration and no cache written."""
    import ruff  # noqa: F401 - a test dependency: missing, the suite fails rather than skips

    done = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--config",
                           str(CONFIG), *targets], capture_output=True, text=True, timeout=120,
                          check=False)
    return done.returncode, done.stdout + done.stderr


def test_the_code_and_its_tests_are_ruff_clean() -> None:
    """``ruff check`` (pyproject.toml's rules) finds nothing in towtank/ and tests/."""
    status, text = _ruff([str(ROOT / "towtank"), str(ROOT / "tests")])
    assert status == 0, f"ruff found problems:\n{text}"


def test_ruff_finds_a_planted_problem(tmp_path: Path) -> None:
    """The check above can fail: an unused import and an undefined name are reported."""
    bad = tmp_path / "bad_module.py"
    bad.write_text("import os\n\n\ndef f():\n    return undefined_name\n", encoding="utf-8")
    status, text = _ruff([str(bad)])
    assert status == 1 and "F401" in text and "F821" in text, text
