"""Text from the inputs written safely: never run as a formula, never invalid XML.

A campaign name, a remark, a reason or a channel name is the lab's text. Written as it is, a
cell beginning with ``=`` becomes a live formula in a spreadsheet (``=HYPERLINK(...)`` a link,
``=2*3`` a 6), and a control character makes an .xlsx that is not valid XML. Following the
usual CSV-injection guidance (OWASP), text that a spreadsheet would run (beginning with ``=``,
``+``, ``-``, ``@``, a tab or a carriage return, and not a number) is written with a leading
apostrophe in the CSV files; in the workbook it is stored as a text cell. Characters XML 1.0
cannot hold (C0 controls other than tab, line feed and carriage return; U+FFFE, U+FFFF;
unpaired surrogates) are replaced by U+FFFD.
"""

from __future__ import annotations

import re

__all__ = ["clean_text", "csv_text", "FORMULA_START"]

#: First characters that make a spreadsheet read a cell as a formula.
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")

_ILLEGAL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\ufffe\uffff\ud800-\udfff]")


def clean_text(text: str) -> str:
    """``text`` with the characters XML 1.0 (and a terminal) cannot hold replaced by U+FFFD."""
    return _ILLEGAL.sub("\ufffd", text)


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def csv_text(text: str) -> str:
    """A text cell for a CSV file: cleaned, and neutralised with a leading ``'`` when a
    spreadsheet would run it as a formula (a number such as ``-0.5`` is left alone)."""
    text = clean_text(text)
    if text.startswith(FORMULA_START) and not _is_number(text.strip()):
        return "'" + text
    return text
