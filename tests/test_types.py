"""The package type-checks: mypy, configured by pyproject.toml's ``[tool.mypy]``, finds no
error in towtank/ (issue 24). mypy is in the ``test`` extra, so CI runs this check."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "pyproject.toml"


def _mypy(targets: list[str], cache: Path) -> tuple[int, str]:
    """mypy's exit status and its report (stdout and stderr) for ``targets``, with the
    project's configuration."""
    from mypy import api  # a test dependency: missing, the suite fails rather than skips
    stdout, stderr, status = api.run(["--config-file", str(CONFIG), "--cache-dir", str(cache),
                                      "--show-error-codes", *targets])
    return status, stdout + stderr


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One mypy cache for this module's runs, outside the repository."""
    return tmp_path_factory.mktemp("mypy_cache")


def test_towtank_has_no_type_error(cache: Path) -> None:
    status, report = _mypy([str(ROOT / "towtank")], cache)
    assert status == 0, f"mypy found type errors in towtank:\n{report}"
    assert "Success: no issues found" in report, report


def test_the_configuration_catches_errors(cache: Path, tmp_path: Path) -> None:
    """The check can fail: under the project's configuration mypy reports an unchecked None
    and, in a function without annotations (check_untyped_defs), a str added to an int."""
    bad = tmp_path / "bad_module.py"
    bad.write_text(
        "def first(x: int | None) -> int:\n"
        "    return x + 1\n"
        "\n"
        "\n"
        "def untyped():\n"
        "    return 1 + 'a'\n",
        encoding="utf-8",
    )
    status, report = _mypy([str(bad)], cache)
    assert status == 1, report
    assert "bad_module.py:2: error" in report and "[operator]" in report, report
    assert "bad_module.py:6: error" in report, report
