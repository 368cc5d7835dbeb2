"""Boolean-mask helpers shared by the checks on reading and the phase detection (vectorised)."""

from __future__ import annotations

import numpy as np


def runs_of_true(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start indices and lengths of the stretches of True in a boolean array."""
    if mask.size == 0:
        return np.array([], dtype=int), np.array([], dtype=int)
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    return starts, np.flatnonzero(d == -1) - starts


def close_gaps(mask: np.ndarray, max_gap: int) -> np.ndarray:
    """Fill stretches of False no longer than ``max_gap`` that lie between two True samples."""
    if max_gap <= 0 or not mask.any():
        return mask
    starts, lengths = runs_of_true(~mask)
    ends = starts + lengths
    fill = (lengths <= max_gap) & (starts > 0) & (ends < mask.size)
    if not fill.any():
        return mask
    delta = np.zeros(mask.size + 1, dtype=np.int64)
    delta[starts[fill]] += 1  # gap starts are distinct, and so are gap ends
    delta[ends[fill]] -= 1
    return mask | (np.cumsum(delta[:-1]) > 0)


def longest_run(mask: np.ndarray) -> tuple[int, int] | None:
    """[i0, i1) of the longest stretch of True (the first of equals)."""
    starts, lengths = runs_of_true(mask)
    if starts.size == 0:
        return None
    k = int(np.argmax(lengths))
    return int(starts[k]), int(starts[k] + lengths[k])
