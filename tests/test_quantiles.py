"""The one home of the coverage factors (towtank.stats.quantiles) and of the speed grouping."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from towtank.stats.grouping import speed_groups
from towtank.stats.quantiles import interval, normal_quantile, t95, t_quantile

PACKAGE = Path(__file__).resolve().parents[1] / "towtank"


def test_quantiles_follow_alpha():
    assert normal_quantile() == pytest.approx(1.959963984540054, rel=1e-15)
    assert normal_quantile(0.10) == pytest.approx(stats.norm.ppf(0.95), rel=1e-15)
    assert t_quantile(4, 0.10) == pytest.approx(2.131846786, rel=1e-9)
    assert t95(4) == pytest.approx(2.776445105, rel=1e-9)
    assert t_quantile(math.inf) == normal_quantile()
    assert t_quantile(0) == math.inf and t_quantile(math.nan) == math.inf
    assert t_quantile(10, 0.10) < t95(10)  # a narrower interval at a lower level
    lo, hi = interval(1.0, 0.1, 4, 0.10)
    assert (lo, hi) == pytest.approx((1.0 - 0.2131846786, 1.0 + 0.2131846786), rel=1e-9)
    assert interval(2.0, 0.0, 0) == (2.0, 2.0)  # an exact fit: no width, not nan
    with pytest.raises(ValueError, match="alpha"):
        normal_quantile(1.5)


def test_no_hard_wired_95_percent_quantile_in_the_package():
    """0.975 and 1.96 are not written anywhere but the quantiles' home (a Monte-Carlo
    percentile of ``towtank simulate`` aside, and the test tooling)."""
    found = []
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel.startswith("testing/") or rel == "stats/quantiles.py":
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#")[0]
            if re.search(r"\b(0\.975|1\.96\d*)\b", code) and "table.quantile" not in code:
                found.append(f"{rel}:{n}")
    assert not found


def test_one_speed_grouping():
    groups = speed_groups([2.0, 0.8, 1.99, 1.2, np.nan, 2.03, 0.81])
    np.testing.assert_array_equal(groups, [2, 0, 2, 1, -1, 2, 0])
    from towtank.analysis import similarity

    assert similarity.speed_groups is speed_groups
