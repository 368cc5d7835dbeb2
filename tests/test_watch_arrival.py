"""Issue 27: when a run file is complete (towtank.live.arrival), as pure logic fed
observations, and the Linux read-lease probe on real files. No sleeping: times are given."""

from __future__ import annotations

import sys

import pytest

from towtank.live.arrival import ArrivalTracker, Observation, observe, writer_open

S = 1_000_000_000  # ns per s


def obs(size, t_mtime, writer, now):
    return Observation(size, int(t_mtime * S) if size is not None else 0, writer, now)


def test_a_closed_file_is_complete_after_the_quiet_time_only():
    tr = ArrivalTracker(settle_s=1.0, quiet_s=0.1)
    assert tr.update("a", obs(100, 10.00, True, 10.00)) is None  # being written
    assert tr.update("a", obs(200, 10.05, True, 10.05)) is None
    assert tr.update("a", obs(300, 10.10, False, 10.15)) is None  # closed, only 0.05 s quiet
    assert not tr.is_complete("a") and tr.is_waiting("a")
    assert tr.update("a", obs(300, 10.10, False, 10.21)) == "complete"
    assert tr.is_complete("a")
    assert tr.update("a", obs(300, 10.10, False, 11.5)) is None  # said once per content


def test_a_file_held_open_counts_only_after_settle_s():
    tr = ArrivalTracker(settle_s=1.0, quiet_s=0.1)
    tr.update("a", obs(100, 10.0, True, 10.0))
    assert tr.update("a", obs(100, 10.0, True, 10.9)) is None  # open, unchanged 0.9 s
    assert tr.update("a", obs(100, 10.0, True, 11.0)) == "complete"


def test_without_a_lease_the_settle_time_decides():
    tr = ArrivalTracker(settle_s=2.0, quiet_s=0.1)
    tr.update("a", obs(100, 10.0, None, 10.0))
    assert tr.update("a", obs(150, 10.4, None, 10.5)) is None
    assert tr.update("a", obs(150, 10.4, None, 12.3)) is None  # 1.9 s since its last write
    assert tr.update("a", obs(150, 10.4, None, 12.41)) == "complete"


def test_an_old_file_found_at_start_is_complete_at_once():
    tr = ArrivalTracker(settle_s=1.0)
    assert tr.update("a", obs(100, 5.0, None, 100.0)) == "complete"


def test_a_mtime_from_a_skewed_clock_cannot_make_a_growing_file_look_old():
    tr = ArrivalTracker(settle_s=1.0)
    tr.update("a", obs(100, 99.9, None, 100.0))
    # a share whose clock is an hour behind: the change is still dated after the last look
    assert tr.update("a", obs(200, 100.0 - 3600, None, 100.2)) is None
    assert tr.update("a", obs(200, 100.0 - 3600, None, 101.1)) is None
    assert tr.update("a", obs(200, 100.0 - 3600, None, 101.25)) == "complete"


def test_a_file_that_changes_after_its_verdict_is_complete_again():
    tr = ArrivalTracker(settle_s=1.0, quiet_s=0.1)
    tr.update("a", obs(100, 1.0, False, 10.0))
    assert tr.is_complete("a")
    assert tr.update("a", obs(120, 20.0, True, 20.0)) is None
    assert tr.is_waiting("a")
    assert tr.update("a", obs(120, 20.0, False, 20.2)) == "complete"


def test_a_file_that_vanishes_before_completing_and_a_complete_one_removed():
    tr = ArrivalTracker(settle_s=1.0)
    tr.update("a", obs(100, 10.0, True, 10.0))
    assert tr.update("a", obs(None, 0, None, 10.3)) == "vanished"
    assert tr.update("a", obs(None, 0, None, 10.6)) is None  # said once
    tr.update("b", obs(100, 1.0, False, 10.0))
    assert tr.update("b", obs(None, 0, None, 11.0)) == "removed"
    assert not tr.is_complete("b") and not tr.is_waiting("b")


def test_a_file_that_never_stops_growing_is_reported_once():
    tr = ArrivalTracker(settle_s=1.0, never_stops_s=5.0)
    events = [tr.update("a", obs(100 + i, 10.0 + 0.5 * i, True, 10.0 + 0.5 * i))
              for i in range(30)]
    assert events.count("never_stops") == 1
    assert events.index("never_stops") == 10  # 5 s after it appeared
    assert "complete" not in events


linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux leases")


@linux
def test_the_lease_tells_a_file_open_for_writing(tmp_path):
    from towtank.live.arrival import ignore_lease_breaks

    ignore_lease_breaks()
    path = tmp_path / "run_001.csv"
    with open(path, "wb") as fh:
        fh.write(b"t,speed\n")
        fh.flush()
        assert writer_open(path) is True
        assert observe(path, 0.0).writer_open is True
    assert writer_open(path) is False
    with open(path, "rb"):  # a reader does not count
        assert writer_open(path) is False
    assert writer_open(tmp_path / "absent.csv") is None
    assert observe(tmp_path / "absent.csv", 0.0).size is None
    assert observe(tmp_path, 0.0).size is None  # a folder is not a run file


def test_state_json_has_no_nan_and_follows_the_umask(tmp_path):
    import json
    import math
    import os

    import numpy as np

    from towtank.live.state import write_state

    path = write_state(tmp_path / ".live", {"version": np.int64(3), "value": math.nan,
                                            "rows": [{"ci": np.float64(np.inf), "s": "α"}]})
    text = path.read_text(encoding="utf-8")
    assert json.loads(text) == {"version": 3, "value": None, "rows": [{"ci": None, "s": "α"}]}
    assert "NaN" not in text and "Infinity" not in text
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
    assert [p.name for p in path.parent.iterdir()] == ["state.json"]  # no temporary left
