"""Every command and option of `towtank --help` is in the README's Commands and in
docs/formats.md, and every file a command writes is named in its --help and in
docs/formats.md: the help and the documents are the same program's."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from towtank.commands.cli import _parser
from towtank.commands.identify import IDENTIFY_OUTPUTS
from towtank.commands.predict import DESIGN_OUTPUTS, PREDICT_OUTPUTS
from towtank.commands.simulate import SIMULATE_OUTPUTS
from towtank.commands.steady import STEADY_OUTPUTS
from towtank.ingest.protocol import OUTPUT_NAMES

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text(encoding="utf-8")
FORMATS = (REPO / "docs" / "formats.md").read_text(encoding="utf-8")


def _section(text: str, heading: str) -> str:
    start = text.index(heading)
    end = text.find("\n## ", start + len(heading))
    return text[start:end if end > 0 else None]


COMMANDS_README = _section(README, "## Commands")
COMMANDS_FORMATS = _section(FORMATS, "## 4. Command line")


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _options(parser: argparse.ArgumentParser) -> list[str]:
    return [opt for a in parser._actions if a.help != argparse.SUPPRESS
            for opt in a.option_strings if opt.startswith("--") and opt != "--help"]


CASES = [(cmd, opt) for cmd, p in _subparsers().items() for opt in [None, *_options(p)]]


@pytest.mark.parametrize(("command", "option"), CASES,
                         ids=[f"{c}{' ' + o if o else ''}" for c, o in CASES])
def test_every_command_and_option_is_documented(command, option):
    for name, text in (("README's Commands", COMMANDS_README),
                       ("docs/formats.md §4", COMMANDS_FORMATS)):
        assert f"towtank {command}" in text, f"towtank {command} is not in {name}"
        if option is not None:
            line = next((ln for ln in text.splitlines() if f"towtank {command}" in ln), "")
            block = text[text.index(line):]
            block = block[: block.find("\ntowtank ", 1) if "\ntowtank " in block[1:] else None]
            assert option in block, f"{command} {option} is not in {name}"


WRITES = {"process": OUTPUT_NAMES, "predict": PREDICT_OUTPUTS | set(DESIGN_OUTPUTS.values()),
          "simulate": SIMULATE_OUTPUTS, "steady": STEADY_OUTPUTS,
          "identify": IDENTIFY_OUTPUTS}


@pytest.mark.parametrize("command", sorted(WRITES))
def test_every_output_file_is_in_the_help_and_the_formats(command):
    parser = _subparsers()[command]
    text = " ".join(parser.format_help().split())
    for name in sorted(WRITES[command]):
        shown = name + "/" if name in ("figures", "export") else name
        assert shown in text, f"{shown} is not in 'towtank {command} --help'"
        assert shown in FORMATS, f"{shown} is not in docs/formats.md"
