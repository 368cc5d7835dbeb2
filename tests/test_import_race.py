"""No module is imported by the main thread while the background import thread imports.

Two threads importing one package at once can see it half-initialised (exit 3 with "module
'scipy' has no attribute '_lib'" about one day in 500, when the reduction in this process
imports scipy.signal while the thread that preloads the fitting libraries imports scipy.stats).
The import thread runs only while worker processes do the reducing and this process waits, and
is joined before anything else runs here. The test records every import (a finder in front of
sys.meta_path) in a fresh interpreter, where nothing is imported yet, and checks that the main
thread imports nothing while the thread is alive: with in-process reduction (jobs=1, where a
preloading thread would race on every day) and with worker processes.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from towtank.testing import synthetic as syn

SCRIPT = textwrap.dedent("""
    import json
    import sys
    import threading


    class Recorder:
        def __init__(self):
            self.events = []

        def find_spec(self, name, path=None, target=None):
            alive = any(t.name == "towtank-imports" for t in threading.enumerate())
            self.events.append((threading.current_thread().name, name, alive))
            return None


    if __name__ == "__main__":
        recorder = Recorder()
        events = recorder.events
        sys.meta_path.insert(0, recorder)
        import towtank
        day = towtank.process_day(sys.argv[1], jobs=int(sys.argv[2]), report=False,
                                  cache=False)
        clash = [n for who, n, alive in events if who == "MainThread" and alive]
        loader = sorted({n for who, n, _ in events if who == "towtank-imports"})
        print(json.dumps({"clash": clash, "loader": loader, "ok": len(day.reductions)}))
""")


@pytest.fixture(scope="session")
def protocol(tmp_path_factory):
    root = tmp_path_factory.mktemp("race")
    syn.make_hull_day(root, seed=3, fs=200.0, sheet_format="csv")
    return syn.write_protocol(root / "protocol.toml",
                              **syn.hull_protocol_sections(".", "out", sheet_format="csv"))


@pytest.mark.heavy
@pytest.mark.parametrize("jobs", [1, 2])
def test_main_thread_never_imports_while_the_loader_does(protocol, tmp_path, jobs):
    script = tmp_path / "run_day.py"
    script.write_text(SCRIPT)
    out = subprocess.run([sys.executable, str(script), str(protocol), str(jobs)],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout.strip().splitlines()[-1])
    assert res["ok"] >= 40
    assert res["clash"] == [], res["clash"][:20]
    if jobs > 1:  # the loader did its work while the workers reduced
        assert "statsmodels" in res["loader"], res["loader"][:20]
