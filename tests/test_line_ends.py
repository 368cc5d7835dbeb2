"""Text tables are split into lines only where a file's lines end (CR, LF, CR LF): a form
feed, vertical tab, record separator, NEL or Unicode line separator that a spreadsheet or a
logger leaves inside a cell stays in its cell (:func:`towtank.runtime.safefile.text_lines`).
The run sheet's case is in tests/test_runsheet.py."""

from __future__ import annotations

import numpy as np
import pytest

from towtank.ingest.readers import read_lvm_columns
from towtank.reference.sets import read_reference_csv
from towtank.runtime.safefile import text_lines

#: Characters ``str.splitlines`` splits at that are no line end of a text file.
NOT_LINE_ENDS = ["\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029"]


@pytest.mark.parametrize("text, lines", [
    ("", []), ("a", ["a"]), ("a\n", ["a"]), ("a\r\nb\rc\nd", ["a", "b", "c", "d"]),
    ("a\n\nb\n", ["a", "", "b"]), ("a\x0cb\u2028c\n", ["a\x0cb\u2028c"]),
])
def test_text_lines_splits_at_cr_lf_only(text, lines):
    assert text_lines(text) == lines


@pytest.mark.parametrize("char", NOT_LINE_ENDS)
def test_a_reference_csv_keeps_a_cell_with_a_separator_character(tmp_path, char):
    path = tmp_path / "ref.csv"
    path.write_text(f"symbol,prime,source\nX_uu,-0.0101,Table 4{char}p. 12\nY_v,-0.05,\n",
                    encoding="utf-8")
    assert read_reference_csv(path) == {"X_uu": -0.0101, "Y_v": -0.05}


@pytest.mark.parametrize("char", NOT_LINE_ENDS)
def test_an_lvm_comment_with_a_separator_character_keeps_every_row(char):
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Separator\tTab",
            "Decimal_Separator\t.", f"Description\tbalance 2{char}cal. 5",
            "***End_of_Header***", "", "Channels\t1\t", "Samples\t4", "X0\t0", "Delta_X\t0.01",
            "***End_of_Header***\t", "X_Value\tdrag\tComment"]
    rows = [f"{0.01 * i:.2f}\t{1.5 + i}\t" + (f"tow{char}1" if i == 2 else "") for i in range(4)]
    cols, _ = read_lvm_columns(("\r\n".join(head + rows) + "\r\n").encode(), "run.lvm")
    assert np.allclose(cols["drag"], [1.5, 2.5, 3.5, 4.5])
