"""Grouping of runs by tested speed: the one home of the speed grouping of every stage."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def speed_groups(speed: npt.ArrayLike, rel_tol: float = 0.02) -> np.ndarray:
    """Group points by tested speed: repeats at one carriage speed share a group.

    Sorted speeds are chained into one group while each lies within ``rel_tol`` of the previous
    one (single linkage: a gap larger than ``rel_tol`` times the smaller speed's size starts a
    group).

    Parameters
    ----------
    speed : array_like
        Speed of each point [m/s]; a NaN is in no group.
    rel_tol : float, default 0.02
        Relative gap that separates two tested speeds [-].

    Returns
    -------
    numpy.ndarray
        Integer group of each point, 0 for the slowest speed, numbered upwards; −1 for NaN.
    """
    u = np.atleast_1d(np.asarray(speed, dtype=float)).ravel()
    groups = np.full(u.size, -1, dtype=int)
    idx = np.flatnonzero(np.isfinite(u))
    if idx.size == 0:
        return groups
    order = idx[np.argsort(u[idx], kind="stable")]
    s = u[order]
    gaps = np.diff(s) > rel_tol * np.abs(s[:-1])
    groups[order] = np.concatenate(([0], np.cumsum(gaps)))
    return groups
