"""towtank.stats.robust: order statistics, block samples and the robust scale behind the checks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from towtank.stats import robust

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@settings(max_examples=100, deadline=None)
@given(x=arrays(np.float64, st.integers(1, 300), elements=finite),
       qs=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=4))
def test_quantiles_are_the_ranked_values(x, qs):
    got = robust.quantiles(x, tuple(qs))
    ranked = np.sort(x)
    want = [ranked[min(x.size - 1, int(q * x.size))] for q in qs]
    assert list(got) == want


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 30_000), size=st.sampled_from([64, 512, 2048]))
def test_blocks_are_contiguous_stretches_spread_over_the_signal(n, size):
    x = np.arange(n, dtype=float)
    b = robust.blocks(x, size=size)
    if n <= size:
        assert np.array_equal(b, x)
        return
    assert b.size == size
    parts = b.reshape(8, size // 8)
    assert np.all(np.diff(parts, axis=1) == 1)  # each block contiguous
    assert parts[0, 0] == 0 and parts[-1, -1] == n - 1  # first and last samples included
    assert np.all(np.diff(parts[:, 0]) > 0)  # in order


def test_spread_sample_keeps_a_short_plateau():
    x = np.zeros(100_000)
    x[50_000:50_600] = 1.0  # 0.6 % of the samples
    assert robust.quantile(robust.spread_sample(x), 0.995) == 1.0


@pytest.mark.parametrize("centred", [False, True])
def test_robust_scale_of_normal_noise_with_outliers(centred):
    rng = np.random.default_rng(3)
    r = rng.normal(0.0, 0.2, 4096)
    r[::97] = 50.0  # 1 % wild values do not move it
    s = robust.robust_scale(r, 1e-9, centred=centred)
    assert s == pytest.approx(0.2, rel=0.06)


def test_robust_scale_survives_quantised_values_and_keeps_its_floor():
    r = np.zeros(1000)
    r[::3] = 0.01  # a third one step off: the MAD is 0, the 90th percentile is not
    assert robust.robust_scale(r, 1e-6) == pytest.approx(0.01 / robust.Q90_ABS_TO_SD)
    assert robust.robust_scale(np.zeros(100), 1e-6) == 1e-6
    assert robust.robust_scale(np.array([]), 0.5) == 0.5
