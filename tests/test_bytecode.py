"""The test run's and the benchmark's new processes keep their bytecode where the environment
switches writing it off (towtank.testing.bytecode): the run's beside the sources, as Python's
default has it, the benchmark's under a folder of its own."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from towtank.testing.bytecode import (
    NO_BYTECODE,
    PREFIX,
    bytecode_env,
    pycache_folders,
    remove_new_pycache,
)


def test_the_environment_is_changed_only_where_writing_is_off(tmp_path):
    base = {"PATH": "/usr/bin"}
    assert bytecode_env(base, tmp_path) == base
    assert bytecode_env(base | {NO_BYTECODE: ""}, tmp_path) == base | {NO_BYTECODE: ""}
    assert bytecode_env(base | {NO_BYTECODE: "1"}, tmp_path) == base | {PREFIX: str(tmp_path)}
    # a folder the environment names already is kept
    named = base | {NO_BYTECODE: "1", PREFIX: "/elsewhere"}
    assert bytecode_env(named, tmp_path) == base | {PREFIX: "/elsewhere"}
    assert named[NO_BYTECODE] == "1"  # the caller's mapping is left as it was


_CHILD = """
import subprocess, sys
from pathlib import Path
from towtank.testing.bytecode import write_bytecode_again
src = Path(sys.argv[1])
assert sys.dont_write_bytecode
assert write_bytecode_again()
assert not write_bytecode_again()  # on already: nothing to do
sys.path.insert(0, str(src))
import probe_module  # compiled here: its bytecode beside it
subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv[1]); "
                "import probe_grandchild", str(src)], check=True)
"""


def test_a_process_and_its_children_write_bytecode_beside_the_sources(tmp_path):
    """Switched on again as Python's default has it: in __pycache__ beside each source, where
    an installed library's bytecode is read from too."""
    src = tmp_path / "src"
    src.mkdir()
    for name in ("probe_module", "probe_grandchild"):
        (src / f"{name}.py").write_text("VALUE = 1\n")
    env = {"PATH": "/usr/bin", NO_BYTECODE: "1",
           "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    subprocess.run([sys.executable, "-c", _CHILD, str(src)], env=env, check=True, timeout=120)
    written = sorted(p.name.split(".")[0] for p in (src / "__pycache__").glob("probe_*.pyc"))
    assert written == ["probe_grandchild", "probe_module"]


def test_only_the_bytecode_folders_a_run_made_are_removed(tmp_path):
    """A __pycache__ that was there before the run stays; those the run made go, the sources
    beside them stay."""
    src = tmp_path / "src"
    (src / "old" / "__pycache__").mkdir(parents=True)
    (src / "old" / "__pycache__" / "a.cpython-311.pyc").write_bytes(b"old")
    before = pycache_folders([src])
    assert before == {src / "old" / "__pycache__"}
    for folder in (src, src / "new"):
        (folder / "__pycache__").mkdir(parents=True)
        (folder / "__pycache__" / "m.cpython-311.pyc").write_bytes(b"new")
        (folder / "m.py").write_text("VALUE = 1\n")
    remove_new_pycache([src], before)
    assert pycache_folders([src]) == before
    assert (src / "old" / "__pycache__" / "a.cpython-311.pyc").read_bytes() == b"old"
    assert (src / "m.py").exists() and (src / "new" / "m.py").exists()
