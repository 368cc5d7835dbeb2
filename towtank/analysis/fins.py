"""Fin (control surface) analysis: finite-span expectation, per-run table, curves, derivatives.

The measured fin coefficients (C_L = L/(q S), C_D = D/(q S), q = rho U^2 / 2, S = chord x span,
Re = U c / nu on the chord) are set beside the two-dimensional NACA 0015 section data of Sheldahl &
Klimas (1981) (:mod:`towtank.reference.sandia`) at each run's Reynolds number, and beside the
finite-span
expectation from Prandtl's lifting-line theory, which lowers the lift slope and adds induced drag
(docs/method.md, "Fins"; report section 5-4, Figs. 14-16).

Conventions: angles of attack ``alpha_deg`` in degrees, lift slopes per radian, induced angle in
radians. The fin's reference area is its planform chord x span, as in runs.csv.

References
----------
.. [1] Anderson, J. D., Fundamentals of Aerodynamics, McGraw-Hill, section 5.3 (Prandtl's
   classical lifting-line theory): eqs. for the induced angle alpha_i = C_L / (pi e AR), induced
   drag C_D,i = C_L^2 / (pi e AR) and lift slope a = a0 / (1 + a0 / (pi e AR)).
.. [2] Prestero, T. (2001), Verification of a six-degree of freedom simulation model for the
   REMUS autonomous underwater vehicle, MSc thesis, MIT / WHOI, section "Control fin forces and
   moments".
.. [3] Sheldahl, R. E. and Klimas, P. C. (1981), SAND80-2114, Sandia National Laboratories.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt
import pandas as pd

from towtank.reference import sandia
from towtank.stats import grouping

__all__ = [
    "FIN_COLUMNS",
    "FIN_TABLE_COLUMNS",
    "CURVE_COLUMNS",
    "control_derivatives",
    "control_lift_slope",
    "effective_aspect_ratio",
    "fin_curves",
    "fin_table",
    "lift_slope_estimates",
    "finite_span_coefficients",
    "finite_span_slope",
    "force_vs_speed",
    "induced_drag",
    "lift_slope_warnings",
    "linear_slope",
    "low_reynolds_warnings",
    "section_stall_angle",
    "attached_flow",
    "speed_groups",
]

#: The fins.csv columns of docs/formats.md section 5, in order.
FIN_COLUMNS: tuple[str, ...] = (
    "run", "angle_deg", "speed_mean", "re", "cl", "cd", "cl_sandia", "cd_sandia",
)
#: Columns of :func:`fin_table`: the fins.csv columns first, then the extensions.
FIN_TABLE_COLUMNS: tuple[str, ...] = FIN_COLUMNS + (
    "cl_3d", "cd_3d", "speed_group", "drag_mean", "lift_mean",
)
#: Columns of :func:`fin_curves`.
CURVE_COLUMNS: tuple[str, ...] = (
    "speed_group", "re_mean", "n_runs", "lift_slope", "lift_slope_ci_low", "lift_slope_ci_high",
    "lift_slope_sandia_2d", "lift_slope_3d", "stall_angle_deg", "cl_max", "stall_reached",
    "cd_min", "cd_min_angle_deg", "slope_angles_deg",
)
_RUN_COLUMNS = ("run", "angle_deg", "speed_mean", "re", "cl", "cd", "drag_mean", "lift_mean")

#: A 2-D section: (alpha_deg [deg], reynolds [-]) -> (cl [-], cd [-]), vectorised.
Section = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def _require(frame: pd.DataFrame, columns: tuple[str, ...], what: str) -> None:
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise ValueError(f"{what} lacks the column(s) {', '.join(missing)}.")


# --------------------------------------------------------------------------------------------
# Lifting line
# --------------------------------------------------------------------------------------------


def effective_aspect_ratio(
    span_m: npt.ArrayLike,
    chord_m: npt.ArrayLike,
    mounting: Literal["free", "wall"] = "free",
) -> np.ndarray:
    """Effective aspect ratio of a rectangular fin for the lifting-line correction.

    ``"free"``: the fin is tested alone with both tips free and its whole span counted as the
    wing, so AR = b / c (geometric aspect ratio of a rectangular planform). ``"wall"``: the fin's
    root sits on a wall, hull or end plate that acts as a plane of symmetry; its mirror image
    doubles the wing, so AR_eff = 2 b / c (method of images; Anderson [1]_ section 5.3 for the
    lifting line on the doubled wing).

    Parameters
    ----------
    span_m : array_like
        Fin span, root to tip [m].
    chord_m : array_like
        Fin chord [m].
    mounting : {"free", "wall"}, default "free"
        How the fin was mounted in the test.

    Returns
    -------
    numpy.ndarray
        Effective aspect ratio [-].
    """
    if mounting not in ("free", "wall"):
        raise ValueError(f"mounting must be 'free' or 'wall', not {mounting!r}.")
    span = np.asarray(span_m, dtype=float)
    chord = np.asarray(chord_m, dtype=float)
    if np.any(span <= 0) or np.any(chord <= 0):
        raise ValueError("Fin span and chord must be positive.")
    ar = span / chord
    return 2.0 * ar if mounting == "wall" else ar


def finite_span_slope(
    a0_per_rad: npt.ArrayLike, aspect_ratio: npt.ArrayLike, e: npt.ArrayLike = 1.0
) -> np.ndarray:
    """Lift-curve slope of a finite wing from its section slope (Prandtl lifting line).

    a = a0 / (1 + a0 / (pi e AR)), Anderson [1]_ section 5.3 (elliptic loading for e = 1).

    Parameters
    ----------
    a0_per_rad : array_like
        Two-dimensional section lift slope dC_l/dalpha [1/rad].
    aspect_ratio : array_like
        Effective aspect ratio [-], see :func:`effective_aspect_ratio`.
    e : array_like, default 1.0
        Span efficiency factor [-] (1 for elliptic loading).

    Returns
    -------
    numpy.ndarray
        Finite-span lift slope dC_L/dalpha [1/rad].
    """
    a0 = np.asarray(a0_per_rad, dtype=float)
    return a0 / (1.0 + a0 / (np.pi * np.asarray(e, dtype=float) * np.asarray(aspect_ratio, float)))


def induced_drag(
    cl: npt.ArrayLike, aspect_ratio: npt.ArrayLike, e: npt.ArrayLike = 1.0
) -> np.ndarray:
    """Induced drag coefficient C_D,i = C_L^2 / (pi e AR), Anderson [1]_ section 5.3.

    Parameters
    ----------
    cl : array_like
        Lift coefficient of the wing [-].
    aspect_ratio : array_like
        Effective aspect ratio [-].
    e : array_like, default 1.0
        Span efficiency factor [-].

    Returns
    -------
    numpy.ndarray
        Induced drag coefficient [-], never negative for AR > 0, e > 0.
    """
    cl = np.asarray(cl, dtype=float)
    return cl * cl / (np.pi * np.asarray(e, dtype=float) * np.asarray(aspect_ratio, dtype=float))


def _wrap_deg(alpha_deg: np.ndarray) -> np.ndarray:
    """Angles beyond +-180 deg folded back into [-180, 180) (the 2-D data are 360-deg periodic)."""
    return np.where(np.abs(alpha_deg) > 180.0, (alpha_deg + 180.0) % 360.0 - 180.0, alpha_deg)


def _induced_angle(
    alpha_deg: np.ndarray,
    reynolds: np.ndarray,
    k: np.ndarray,
    section: Section,
    tol: float,
    max_iter: int,
) -> np.ndarray:
    """Solve h(x) = x - k C_L,2D(alpha - x) = 0 for the induced angle x [rad], element-wise.

    Started from x = 0 with the damped fixed-point step x <- x - lam h(x), lam = 1 / (1 + 2 pi k)
    (a Newton step with the thin-aerofoil slope 2 pi); later steps use the secant slope of h
    through the last two iterates when it is positive (the stable, attached-flow side), the
    damped step otherwise. Safeguards: whenever a step fails to halve |h|, the next step bisects
    the sign-change bracket or, while no bracket is known yet, steps twice as far downhill until
    h changes sign (h(x) ~ x for large |x| because C_L,2D is bounded, so a bracket always
    exists). Converged when |h| <= tol * min(1, max(|h(0)|, 1e-6)) or the bracket is that
    narrow; the relative part keeps the precision for very small lift.
    """
    n = alpha_deg.size
    x = np.zeros(n)
    out = np.full(n, np.nan)

    def h(xs: np.ndarray, idx: np.ndarray) -> np.ndarray:
        cl, _ = section(_wrap_deg(alpha_deg[idx] - np.rad2deg(xs)), reynolds[idx])
        return xs - k[idx] * np.asarray(cl, dtype=float)

    hx = h(x, np.arange(n))
    active = np.isfinite(hx) & np.isfinite(k)
    lam = 1.0 / (1.0 + 2.0 * np.pi * k)
    target = tol * np.clip(np.abs(hx), 1e-6, 1.0)
    lo = np.where(hx < 0, 0.0, np.nan)  # h(lo) < 0
    hi = np.where(hx > 0, 0.0, np.nan)  # h(hi) > 0
    # past the section's stall h has several roots: start inside the bracket of the attached
    # branch (the root of largest |alpha_i|, i.e. smallest |alpha_eff|) where a scan finds one
    found, b_lo, b_hi = _attached_bracket(alpha_deg, reynolds, k, section)
    found &= active & ~(np.abs(hx) <= target)
    if found.any():
        up = np.deg2rad(alpha_deg) > 0  # h < 0 at the bracket end nearer alpha_i = 0
        lo = np.where(found, np.where(up, b_lo, b_hi), lo)
        hi = np.where(found, np.where(up, b_hi, b_lo), hi)
        x = np.where(found, b_lo, x)  # the end nearer alpha_i = 0: a bisection moves it
        hx = np.where(found, h(x, np.arange(n)), hx)
    x_prev = np.full(n, np.nan)
    h_prev = np.full(n, np.nan)
    expand = np.abs(lam * hx)
    slow = np.zeros(n, dtype=bool)
    done = active & (np.abs(hx) <= target)
    out[done] = x[done]
    live = active & ~done

    for _ in range(max_iter):
        idx = np.flatnonzero(live)
        if idx.size == 0:
            break
        xi, h_i, lo_i, hi_i = x[idx], hx[idx], lo[idx], hi[idx]
        with np.errstate(divide="ignore", invalid="ignore"):
            secant = (h_i - h_prev[idx]) / (xi - x_prev[idx])
        use_secant = np.isfinite(secant) & (secant > 0)
        cand = np.where(
            use_secant, xi - h_i / np.where(use_secant, secant, 1.0), xi - lam[idx] * h_i
        )
        bracketed = np.isfinite(lo_i) & np.isfinite(hi_i)
        inside = (cand >= np.fmin(lo_i, hi_i)) & (cand <= np.fmax(lo_i, hi_i))
        bisect = bracketed & (slow[idx] | ~inside)
        cand = np.where(bisect, 0.5 * (lo_i + hi_i), cand)
        widen = ~bracketed & slow[idx]
        expand[idx] = np.where(widen, 2.0 * np.maximum(expand[idx], 1e-12), expand[idx])
        cand = np.where(widen, xi - np.sign(h_i) * expand[idx], cand)

        hc = h(cand, idx)
        slow[idx] = ~(np.abs(hc) <= 0.5 * np.abs(h_i))
        lo[idx] = np.where(hc < 0, cand, lo_i)
        hi[idx] = np.where(hc > 0, cand, hi_i)
        x_prev[idx], h_prev[idx] = xi, h_i
        x[idx], hx[idx] = cand, hc
        width = np.abs(hi[idx] - lo[idx])
        finished = (
            (np.abs(hc) <= target[idx])
            | (width <= target[idx])
            | (cand == xi)
            | ~np.isfinite(hc)
        )
        out[idx[finished]] = np.where(np.isfinite(hc[finished]), cand[finished], np.nan)
        live[idx[finished]] = False

    if live.any():
        warnings.warn(
            f"The lifting-line induced angle did not converge to {tol:g} rad in {max_iter} "
            f"iterations at {int(live.sum())} point(s); the last iterate is used.",
            RuntimeWarning,
            stacklevel=3,
        )
        out[live] = x[live]
    return out


def _attached_bracket(
    alpha_deg: np.ndarray,
    reynolds: np.ndarray,
    k: np.ndarray,
    section: Section,
    n_scan: int = 64,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(found, lo, hi): a bracket [lo, hi] [rad] of the root of h of largest |alpha_i|.

    h(x) = x - k C_L,2D(alpha - x) is scanned at ``n_scan`` points from x = 0 to x = alpha
    (|alpha| <= 90 deg), where sign(alpha) h goes from <= 0 (x = 0) to |alpha| > 0 (zero
    effective angle): the last sign change is the attached-flow root, the one the lifting line
    is meant for (a smaller |x| is a stalled solution of the same equation).
    """
    a = np.deg2rad(alpha_deg)
    m = a.size
    ok = np.isfinite(a) & np.isfinite(k) & (np.abs(alpha_deg) <= 90.0) & (a != 0.0)
    found = np.zeros(m, dtype=bool)
    lo = np.full(m, np.nan)
    hi = np.full(m, np.nan)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return found, lo, hi
    frac = np.linspace(0.0, 1.0, n_scan)
    xs = a[idx, None] * frac[None, :]
    eff = _wrap_deg(alpha_deg[idx, None] - np.rad2deg(xs))
    cl, _ = section(eff.ravel(), np.repeat(reynolds[idx], n_scan))
    g = np.sign(a[idx])[:, None] * (xs - k[idx, None] * np.asarray(cl, float).reshape(-1, n_scan))
    cross = (g[:, :-1] <= 0) & (g[:, 1:] > 0)
    has = cross.any(axis=1)
    last = (n_scan - 2) - np.argmax(cross[:, ::-1], axis=1)
    rows = np.arange(idx.size)
    found[idx] = has
    lo[idx] = np.where(has, xs[rows, last], np.nan)
    hi[idx] = np.where(has, xs[rows, last + 1], np.nan)
    return found, lo, hi


def finite_span_coefficients(
    alpha_deg: npt.ArrayLike,
    reynolds: npt.ArrayLike,
    aspect_ratio: npt.ArrayLike,
    e: npt.ArrayLike = 1.0,
    *,
    section: Section = sandia.section_coefficients,
    tol: float = 1e-10,
    max_iter: int = 200,
) -> tuple[np.ndarray, np.ndarray]:
    """Finite-span lift and drag expected from 2-D section data (Prandtl lifting line).

    With the induced angle alpha_i = C_L / (pi e AR) [rad] (Anderson [1]_ section 5.3),

        C_L = C_l,2D(alpha - alpha_i, Re),
        C_D = C_d,2D(alpha - alpha_i, Re) + C_L^2 / (pi e AR),

    where alpha_i is found self-consistently, element-wise, to ``tol`` [rad]. In the linear range
    (C_l,2D = a0 alpha) this is C_L = a0 / (1 + a0 / (pi e AR)) alpha, the closed form of
    :func:`finite_span_slope`.

    Solver: a damped fixed-point iteration alpha_i <- alpha_i - lam h(alpha_i) on
    h(alpha_i) = alpha_i - C_l,2D(alpha - alpha_i) / (pi e AR), with lam = 1 / (1 + 2 pi /
    (pi e AR)) (one exact step for a linear section of slope 2 pi), started from alpha_i = 0,
    accelerated by the secant slope of h where that is positive (exact in two steps on any
    linear stretch of the 2-D curve) and safeguarded by bisection of a sign-change bracket
    whenever a step fails to halve |h|; vectorised over the inputs. Past stall the 2-D curve
    falls and h can have several roots (the lifting-line hysteresis): a scan of h from
    alpha_i = 0 to alpha_i = alpha brackets the root of largest |alpha_i| (smallest effective
    angle), the attached-flow branch, and the iteration starts inside that bracket; where the
    attached branch no longer exists the root found is a stalled one. Lifting-line theory is
    not meant for separated flow: post-stall values are indicative only.

    Parameters
    ----------
    alpha_deg : array_like
        Geometric angle of attack [deg], -180 ... 180.
    reynolds : array_like
        Reynolds number on the chord [-].
    aspect_ratio : array_like
        Effective aspect ratio [-], see :func:`effective_aspect_ratio`.
    e : array_like, default 1.0
        Span efficiency factor [-].
    section : callable, default :func:`towtank.reference.sandia.section_coefficients`
        2-D section data, ``section(alpha_deg, reynolds) -> (cl, cd)``, vectorised. Effective
        angles beyond +-180 deg are wrapped into [-180, 180) before the call.
    tol : float, default 1e-10
        Convergence tolerance on the induced angle [rad]; scaled down by the first residual
        |k C_l,2D(alpha)| when that is below 1 rad (not below 1e-6 x tol).
    max_iter : int, default 200
        Iteration limit; a RuntimeWarning is issued where it is reached.

    Returns
    -------
    cl3d : numpy.ndarray
        Finite-span lift coefficient [-], shape of the broadcast inputs.
    cd3d : numpy.ndarray
        Finite-span drag coefficient, profile plus induced [-].
    """
    alpha, re, ar, ee = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (alpha_deg, reynolds, aspect_ratio, e))
    )
    shape = alpha.shape
    if np.any(ar <= 0) or np.any(ee <= 0):
        raise ValueError("Aspect ratio and span efficiency must be positive.")
    alpha, re, ar, ee = (np.ravel(v).copy() for v in (alpha, re, ar, ee))
    k = 1.0 / (np.pi * ee * ar)

    # The first call may warn (e.g. Re clamped to the Sandia range); the iterations repeat it.
    section(alpha, re)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sandia.SandiaRangeWarning)
        alpha_i = _induced_angle(alpha, re, k, section, tol, max_iter)
        alpha_eff = np.where(np.isfinite(alpha_i), _wrap_deg(alpha - np.rad2deg(alpha_i)), np.nan)
        cl, cd = section(alpha_eff, re)
    cl = np.asarray(cl, dtype=float)
    cd3d = np.asarray(cd, dtype=float) + induced_drag(cl, ar, ee)
    return cl.reshape(shape), cd3d.reshape(shape)


def section_stall_angle(reynolds: npt.ArrayLike) -> np.ndarray:
    """Stall angle of the 2-D NACA 0015 section: the first local maximum of C_L(alpha >= 0).

    The Sandia table (Sheldahl & Klimas [3]_) interpolated linearly in alpha at the given Re
    (:func:`towtank.reference.sandia.section_coefficients`, its Re clamp included) is piecewise
    linear
    between the tabulated angles, so its first local maximum lies on one of them: the last
    tabulated angle before C_L first falls.

    Parameters
    ----------
    reynolds : array_like
        Reynolds number on the chord [-].

    Returns
    -------
    numpy.ndarray
        Section stall angle [deg], shape of ``reynolds``; NaN where Re is NaN or not positive.
    """
    re = np.asarray(reynolds, dtype=float)
    out = np.full(re.shape, np.nan)
    ok = np.isfinite(re) & (re > 0)
    if not ok.any():
        return out
    knots = np.unique(sandia.table()["alpha_deg"].to_numpy(dtype=float))
    unique_re, inverse = np.unique(re[ok], return_inverse=True)
    cl, _ = sandia.section_coefficients(knots[None, :], unique_re[:, None])
    falls = np.diff(cl, axis=1) < 0
    first = np.argmax(falls, axis=1)
    stall = np.where(falls.any(axis=1), knots[first], np.nan)
    out[ok] = stall[inverse]
    return out


# --------------------------------------------------------------------------------------------
# Per-run table and curves
# --------------------------------------------------------------------------------------------


def attached_flow(alpha_deg: npt.ArrayLike, cl_3d: npt.ArrayLike, reynolds: npt.ArrayLike,
                  aspect_ratio: float, e: float = 1.0) -> np.ndarray:
    """Where lifting-line theory holds: the effective angle is at or below the section's stall.

    |α − α_i| ≤ α_stall(Re), α_i = C_L,3D/(π·e·AR) [rad] (Anderson [1]_ section 5.3) and
    α_stall the 2-D section's stall angle (:func:`section_stall_angle`). Past it the
    self-consistent solution jumps between branches, so no finite-span value is given there.
    The one home of the attached-flow mask (the fin table and the report's curves).

    Parameters
    ----------
    alpha_deg : array_like
        Geometric angle of attack [deg].
    cl_3d : array_like
        Finite-span lift coefficient at that angle [-] (:func:`finite_span_coefficients`).
    reynolds : array_like
        Reynolds number on the chord [-].
    aspect_ratio : float
        Effective aspect ratio [-].
    e : float, default 1
        Oswald span efficiency [-].

    Returns
    -------
    numpy.ndarray
        True where the flow is attached (False where Re or C_L is NaN).
    """
    alpha = np.asarray(alpha_deg, dtype=float)
    effective = alpha - np.rad2deg(np.asarray(cl_3d, dtype=float) / (np.pi * e * aspect_ratio))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sandia.SandiaRangeWarning)  # said by the table
        stall = section_stall_angle(np.broadcast_to(np.asarray(reynolds, dtype=float),
                                                    alpha.shape))
    return np.asarray(np.abs(effective) <= stall)


def speed_groups(speed_mean: npt.ArrayLike, rel_tol: float = 0.05) -> np.ndarray:
    """Group runs by nominal carriage speed, labelled by the group's mean speed.

    The groups are :func:`towtank.stats.grouping.speed_groups` (single linkage on the sorted
    speeds); a group's label is its mean speed rounded to 0.01 m/s.

    Parameters
    ----------
    speed_mean : array_like
        Steady-phase mean carriage speed of each run [m/s].
    rel_tol : float, default 0.05
        Relative gap that separates two groups [-].

    Returns
    -------
    numpy.ndarray
        The group label of each run [m/s], NaN where the speed is NaN.
    """
    speed = np.asarray(speed_mean, dtype=float).ravel()
    labels = np.full(speed.shape, np.nan)
    groups = grouping.speed_groups(speed, rel_tol)
    for g in np.unique(groups[groups >= 0]):
        members = groups == g
        labels[members] = round(float(np.mean(speed[members])), 2)
    return labels


def fin_table(runs: pd.DataFrame, aspect_ratio: float, e: float = 1.0) -> pd.DataFrame:
    """One row per fin run: measured coefficients beside the Sandia 2-D and 3-D expectations.

    cl_sandia, cd_sandia are :func:`towtank.reference.sandia.section_coefficients` at the run's
    angle and
    chord Reynolds number (Sheldahl & Klimas [3]_); cl_3d, cd_3d the lifting-line expectation of
    :func:`finite_span_coefficients` for the fin's effective aspect ratio where the flow is
    attached, i.e. where the effective angle |alpha - alpha_i| (alpha_i = C_L,3D / (pi e AR),
    Anderson [1]_ section 5.3) is at or below the section's stall angle at the run's Re
    (:func:`section_stall_angle`), and NaN otherwise: past stall lifting-line theory does not
    hold and its self-consistent solution jumps between branches.

    Parameters
    ----------
    runs : pandas.DataFrame
        Fin runs with at least ``run``, ``angle_deg`` [deg], ``speed_mean`` [m/s], ``re`` [-]
        (on the chord), ``cl`` [-], ``cd`` [-] (on chord x span), ``drag_mean`` [N],
        ``lift_mean`` [N].
    aspect_ratio : float
        Effective aspect ratio of the fin [-], see :func:`effective_aspect_ratio`.
    e : float, default 1.0
        Span efficiency factor [-].

    Returns
    -------
    pandas.DataFrame
        Columns :data:`FIN_TABLE_COLUMNS`: the fins.csv columns of docs/formats.md section 5 (run,
        angle_deg, speed_mean, re, cl, cd, cl_sandia, cd_sandia), then cl_3d, cd_3d (NaN past
        the section's stall), speed_group [m/s] (see :func:`speed_groups`), drag_mean [N],
        lift_mean [N]. Rows in the order of ``runs``.
    """
    _require(runs, _RUN_COLUMNS, "The fin run table")
    out = runs.loc[:, list(_RUN_COLUMNS)].reset_index(drop=True).copy()
    alpha = out["angle_deg"].to_numpy(dtype=float)
    re = out["re"].to_numpy(dtype=float)
    cl2d, cd2d = sandia.section_coefficients(alpha, re)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sandia.SandiaRangeWarning)  # already said once
        cl3d, cd3d = finite_span_coefficients(alpha, re, aspect_ratio, e)
        attached = attached_flow(alpha, cl3d, re, aspect_ratio, e)
    cl3d = np.where(attached, cl3d, np.nan)
    cd3d = np.where(attached, cd3d, np.nan)
    out["cl_sandia"] = cl2d
    out["cd_sandia"] = cd2d
    out["cl_3d"] = cl3d
    out["cd_3d"] = cd3d
    out["speed_group"] = speed_groups(out["speed_mean"].to_numpy(dtype=float))
    return out.loc[:, list(FIN_TABLE_COLUMNS)]


def _enough_angles(alpha: np.ndarray) -> bool:
    """A slope needs two or more distinct non-zero angles (one angle gives only a secant)."""
    return bool(np.unique(alpha[alpha != 0]).size >= 2)


def _with_intercept(alpha_rad: np.ndarray) -> bool:
    """Fit an intercept only with three or more distinct angles (else through the origin)."""
    return bool(np.unique(alpha_rad).size >= 3)


class SlopeFit(NamedTuple):
    """An OLS lift slope: value, its interval, standard error and residual degrees of freedom
    [1/rad, 1/rad, 1/rad, 1/rad, -]; NaN where the data cannot tell."""

    value: float
    ci_low: float
    ci_high: float
    std_error: float
    dof: float


def _ols_slope(alpha_rad: np.ndarray, y: np.ndarray, level: float = 0.95) -> SlopeFit:
    """OLS slope of C_L on α with its ``level`` interval; NaN where the data cannot tell.

    NaN unless two or more distinct non-zero angles. With three or more distinct angles the line
    C_L = a·α + c0 is fitted (c0 absorbs a small misalignment of the fin); with two (both
    non-zero), C_L = a·α through the origin, which the symmetric section justifies, so that two
    angles (e.g. 2.5° and 5°) still give a slope and an interval from their repeats and speeds.
    """
    # loaded on use: statsmodels loads while the workers reduce the runs
    from statsmodels.regression.linear_model import OLS

    ok = np.isfinite(alpha_rad) & np.isfinite(y)
    x, y = alpha_rad[ok], y[ok]
    if not _enough_angles(x):
        return SlopeFit(np.nan, np.nan, np.nan, np.nan, np.nan)
    if _with_intercept(x):
        fit = OLS(y, np.column_stack([np.ones_like(x), x])).fit()
        k = 1
    else:
        fit = OLS(y, x[:, None]).fit()
        k = 0
    a = float(fit.params[k])
    if fit.df_resid < 1:
        return SlopeFit(a, np.nan, np.nan, np.nan, float(fit.df_resid))
    low, high = fit.conf_int(alpha=1.0 - level)[k]
    return SlopeFit(a, float(low), float(high), float(fit.bse[k]), float(fit.df_resid))


def _ls_slope(alpha_rad: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y on alpha (same model as :func:`_ols_slope`, no interval)."""
    ok = np.isfinite(alpha_rad) & np.isfinite(y)
    x, y = alpha_rad[ok], y[ok]
    if not _enough_angles(x):
        return np.nan
    if _with_intercept(x):
        return float(np.polyfit(x, y, 1)[0])
    return float(x @ y / (x @ x))


def linear_slope(alpha_deg: npt.ArrayLike, y: npt.ArrayLike) -> float:
    """Least-squares slope of a coefficient on the angle, the model of :func:`fin_curves`' slopes.

    C = a·α + c0 with three or more distinct angles, C = a·α with two non-zero ones, NaN with
    fewer (no secant); non-finite pairs are left out.

    Parameters
    ----------
    alpha_deg : array_like
        Angles of attack [deg].
    y : array_like
        The coefficient at those angles [-] (C_L, or C_D for the plausibility check's swap test).

    Returns
    -------
    float
        dy/dα [1/rad].
    """
    return _ls_slope(np.deg2rad(np.asarray(alpha_deg, dtype=float)), np.asarray(y, dtype=float))


def _stall(alpha_deg: np.ndarray, cl: np.ndarray) -> tuple[float, float, object]:
    """(stall angle [deg], C_L,max, stall reached) from runs folded to (|α|, sign(α)·C_L).

    C_L is averaged over the runs at each |α|; the stall is the first local maximum of that
    curve at a positive angle and a positive C_L (a lift that falls from α = 0 on has not
    stalled: its sign is reversed, and its slope is fitted, negative, for the plausibility
    check to name). (NaN, NaN, pd.NA) without a finite run.
    """
    ok = np.isfinite(alpha_deg) & np.isfinite(cl)
    if not ok.any():
        return np.nan, np.nan, pd.NA
    folded_alpha = np.abs(alpha_deg[ok])
    folded_cl = np.where(alpha_deg[ok] < 0, -cl[ok], cl[ok])
    per_angle = pd.Series(folded_cl).groupby(folded_alpha).mean().sort_index()
    angles = per_angle.index.to_numpy(dtype=float)
    mean_cl = per_angle.to_numpy(dtype=float)
    drops = np.flatnonzero((np.diff(mean_cl) < 0) & (angles[:-1] > 0) & (mean_cl[:-1] > 0))
    if drops.size:
        k = int(drops[0])
        return float(angles[k]), float(mean_cl[k]), True
    k = int(np.argmax(mean_cl))
    return float(angles[k]), float(mean_cl[k]), False


def _angle_list(angles: npt.ArrayLike) -> str:
    """Distinct angles as text, ascending: "0 2.5 5" ("" for none)."""
    values = np.unique(np.asarray(angles, dtype=float))
    return " ".join(f"{v:g}" for v in values[np.isfinite(values)])


def fin_curves(
    fin_df: pd.DataFrame,
    linear_max_deg: float = 10.0,
    *,
    aspect_ratio: float | None = None,
    e: float = 1.0,
    level: float = 0.95,
) -> pd.DataFrame:
    """Lift slope, stall and minimum drag of the fin, one row per speed group.

    Stall: each run is folded to (|α|, sign(α)·C_L) (the section is symmetric) and C_L is
    averaged over the runs at each |α|; the stall angle is the first angle after which C_L falls
    (the first local maximum of C_L(|α|) at α > 0 and C_L > 0: a lift falling from 0° on is
    one of reversed sign, not a stall), and its C_L is C_L,max (positive). Past stall a
    section's lift can rise again towards the flat-plate regime (the Sandia tables peak again
    near 45°), so the global maximum is not the stall. ``stall_reached`` is False when C_L never
    falls within the tested angles.

    Lift slope from the linear range: the group's runs with |α| <= ``linear_max_deg`` and, when
    the stall is reached, |α| strictly below the group's stall angle (a stalled point is never
    fitted). OLS fit of C_L = a α + c0 (α in rad) with three or more distinct angles, of
    C_L = a α with two (both non-zero), with the ``level`` (95 %) t-interval of a from
    statsmodels; NaN with fewer than two distinct non-zero angles (no secant is passed off as a
    slope; :func:`lift_slope_warnings` says why), interval NaN without residual degrees of
    freedom. The angles used are listed in ``slope_angles_deg``. The same straight line through
    the same angles (each run's angle, repeats included) is fitted through the Sandia 2-D
    section (Sheldahl & Klimas [3]_) at the group's mean Re (``lift_slope_sandia_2d``) and
    through the lifting-line expectation (``lift_slope_3d``; Anderson [1]_ section 5.3): with
    ``aspect_ratio`` given it is :func:`finite_span_coefficients` at the group's mean Re,
    otherwise the ``cl_3d`` column of ``fin_df`` (each run's own Re, within the 5 % speed
    grouping of the mean).

    Minimum C_D and its (signed) angle from the means per angle.

    Parameters
    ----------
    fin_df : pandas.DataFrame
        Output of :func:`fin_table` (needs angle_deg [deg], re [-], cl, cd, speed_group [m/s];
        cl_3d unless ``aspect_ratio`` is given).
    linear_max_deg : float, default 10.0
        Largest |angle of attack| of the linear range used for the slope fits [deg]
        (protocol ``[fin] linear_max_deg``).
    aspect_ratio : float, optional
        Effective aspect ratio [-] for the 3-D expectation at the group's mean Re.
    e : float, default 1.0
        Span efficiency factor [-] (with ``aspect_ratio``).
    level : float, default 0.95
        Confidence level of the slope interval [-].

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CURVE_COLUMNS`; slopes in [1/rad], angles in [deg], re_mean [-],
        speed_group [m/s], slope_angles_deg the distinct angles of the slope fit [deg] as text
        ("0 2.5 5"); sorted by speed group.
    """
    _require(fin_df, ("angle_deg", "re", "cl", "cd", "speed_group"), "The fin table")
    if aspect_ratio is None:
        _require(fin_df, ("cl_3d",), "The fin table (without aspect_ratio)")
    rows = []
    for label, group in fin_df.groupby("speed_group", sort=True):
        angle = group["angle_deg"].to_numpy(dtype=float)
        cl = group["cl"].to_numpy(dtype=float)
        re_mean = float(np.nanmean(group["re"].to_numpy(dtype=float)))
        stall_angle, cl_max, reached = _stall(angle, cl)
        linear = _linear_range(angle, cl, linear_max_deg)
        fit_angles = angle[linear]
        a, low, high, _, _ = _ols_slope(np.deg2rad(fit_angles), cl[linear], level)
        slope_2d = slope_3d = np.nan
        if np.isfinite(re_mean) and _enough_angles(fit_angles):
            re_fit = np.full(fit_angles.shape, re_mean)
            cl2d, _ = sandia.section_coefficients(fit_angles, re_fit)
            slope_2d = _ls_slope(np.deg2rad(fit_angles), cl2d)
            if aspect_ratio is not None:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", sandia.SandiaRangeWarning)
                    cl3d, _ = finite_span_coefficients(fit_angles, re_fit, aspect_ratio, e)
                slope_3d = _ls_slope(np.deg2rad(fit_angles), cl3d)
        if aspect_ratio is None:
            slope_3d = _ls_slope(
                np.deg2rad(fit_angles), group["cl_3d"].to_numpy(dtype=float)[linear]
            )

        cd_by = group.groupby("angle_deg")["cd"].mean().dropna()
        cd_min = float(cd_by.min()) if not cd_by.empty else np.nan
        cd_min_angle = float(cd_by.idxmin()) if not cd_by.empty else np.nan
        rows.append(
            {
                "speed_group": float(label),
                "re_mean": re_mean,
                "n_runs": int(len(group)),
                "lift_slope": a,
                "lift_slope_ci_low": low,
                "lift_slope_ci_high": high,
                "lift_slope_sandia_2d": slope_2d,
                "lift_slope_3d": slope_3d,
                "stall_angle_deg": stall_angle,
                "cl_max": cl_max,
                "stall_reached": reached,
                "cd_min": cd_min,
                "cd_min_angle_deg": cd_min_angle,
                "slope_angles_deg": _angle_list(fit_angles),
            }
        )
    out = pd.DataFrame(rows, columns=list(CURVE_COLUMNS))
    out["n_runs"] = out["n_runs"].astype(int)
    out["stall_reached"] = out["stall_reached"].astype("boolean")
    out["slope_angles_deg"] = out["slope_angles_deg"].astype(object)
    return out


def _linear_range(angle: np.ndarray, cl: np.ndarray, linear_max_deg: float) -> np.ndarray:
    """The runs of one speed group in the linear range: finite, |α| ≤ ``linear_max_deg`` and,
    when the group stalls, below its stall angle (a mask)."""
    stall_angle, _, reached = _stall(angle, cl)
    linear = np.isfinite(angle) & np.isfinite(cl) & (np.abs(angle) <= linear_max_deg)
    if reached is True:
        linear &= np.abs(angle) < stall_angle
    return linear


def lift_slope_estimates(fin_df: pd.DataFrame, linear_max_deg: float = 10.0) -> pd.DataFrame:
    """The measured linear-range lift slope of every speed group as an estimate.

    The same OLS fit as :func:`fin_curves`' ``lift_slope`` (its ci_low, ci_high are the 95 %
    intervals of these), with its standard error and residual degrees of freedom.

    Parameters
    ----------
    fin_df : pandas.DataFrame
        Output of :func:`fin_table` (angle_deg [deg], cl [-], speed_group [m/s]).
    linear_max_deg : float, default 10.0
        Largest |α| of the linear range [deg].

    Returns
    -------
    pandas.DataFrame
        Columns speed_group [m/s], value, std_error [1/rad] and dof [-], one row per speed
        group, sorted by speed group.
    """
    _require(fin_df, ("angle_deg", "cl", "speed_group"), "The fin table")
    rows = []
    for label, group in fin_df.groupby("speed_group", sort=True):
        angle = group["angle_deg"].to_numpy(dtype=float)
        cl = group["cl"].to_numpy(dtype=float)
        linear = _linear_range(angle, cl, linear_max_deg)
        fit = _ols_slope(np.deg2rad(angle[linear]), cl[linear])
        rows.append({"speed_group": float(label), "value": fit.value,
                     "std_error": fit.std_error, "dof": fit.dof})
    return pd.DataFrame(rows, columns=["speed_group", "value", "std_error", "dof"])


def _deg_list(text: str) -> list[str]:
    return [f"{float(v):g}°" for v in str(text).split()]


def two_dimensional_warning(curves: pd.DataFrame, aspect_ratio: float) -> list[str]:
    """A sentence when the measured lift slopes match the 2-D section rather than the finite
    span, or an empty list.

    A fin of effective aspect ratio AR should lose lift slope to its tip vortices (lifting
    line, Anderson 5.3: a = a₀/(1 + a₀/(π·e·AR)), 2.42 /rad for AR 1.25 against 6.1 for the
    section). When every speed group's 95 % interval holds the 2-D slope but not the
    finite-span one, the fin behaved as a section: it spans the test section or has end
    plates or a wall at both ends ([fin] mounting), or the data are two-dimensional by
    construction (towtank's synthetic fin day is made from the 2-D Sandia data).
    """
    ok = curves.dropna(subset=["lift_slope_ci_low", "lift_slope_ci_high",
                               "lift_slope_sandia_2d", "lift_slope_3d"])
    if ok.empty:
        return []
    lo, hi = ok["lift_slope_ci_low"], ok["lift_slope_ci_high"]
    holds_2d = ((lo <= ok["lift_slope_sandia_2d"]) & (ok["lift_slope_sandia_2d"] <= hi)).all()
    holds_3d = ((lo <= ok["lift_slope_3d"]) & (ok["lift_slope_3d"] <= hi)).any()
    if not holds_2d or holds_3d:
        return []
    return [
        f"fin: the measured lift slopes ({ok['lift_slope'].min():.2f}–"
        f"{ok['lift_slope'].max():.2f} /rad) match the 2-D NACA 0015 section "
        f"({ok['lift_slope_sandia_2d'].mean():.2f} /rad), not the finite span of effective "
        f"aspect ratio {aspect_ratio:.3g} ({ok['lift_slope_3d'].mean():.2f} /rad): the fin "
        "behaved as a section (it spans the tank's test section, or has end plates or walls "
        "at both ends; or the data are two-dimensional by construction, as towtank's "
        "synthetic fin day is). Check [fin] span_m and mounting before using the finite-span "
        "columns."
    ]


def lift_slope_warnings(curves: pd.DataFrame, linear_max_deg: float = 10.0,
                        rejected: pd.DataFrame | None = None) -> list[str]:
    """One sentence per speed group of :func:`fin_curves` that has no lift slope.

    A group gets no slope when fewer than two distinct non-zero angles lie in its linear range
    (|α| <= ``linear_max_deg`` and below its stall angle); the sentence names the group, the
    angles that remain, the stall angle and the linear range, and the group's rejected fin
    runs within the linear range (their angle is missing for that reason, not for the stall).

    Parameters
    ----------
    curves : pandas.DataFrame
        Output of :func:`fin_curves` (speed_group [m/s], lift_slope [1/rad], stall_angle_deg
        [deg], stall_reached, slope_angles_deg).
    linear_max_deg : float, default 10.0
        The linear range the curves were fitted with [deg].
    rejected : pandas.DataFrame, optional
        The day's rejected fin runs (run, angle_deg [deg], speed_nominal [m/s]); one counts
        in a group when its set speed is within 5 % of the group's.

    Returns
    -------
    list of str
        E.g. "fin lift slope at U ≈ 1.00 m/s: only 5° lies below stall (10°) within the linear
        range (≤ 10°); no slope." (with "; no slope (run 14 at 2.5° was rejected)." when a
        rejected run would have been in the range). In the order of ``curves``.
    """
    _require(curves, ("speed_group", "lift_slope", "stall_angle_deg", "stall_reached",
                      "slope_angles_deg"), "The fin curves")
    out = []
    for row in curves.to_dict("records"):
        if np.isfinite(row["lift_slope"]):
            continue
        left = _deg_list(row["slope_angles_deg"])
        stalled = bool(pd.notna(row["stall_reached"]) and row["stall_reached"])
        where = (f"below stall ({row['stall_angle_deg']:g}°) " if stalled else "") + (
            f"within the linear range (≤ {linear_max_deg:g}°)"
        )
        if not left:
            what = f"no tested angle lies {where}"
        elif len(left) == 1:
            what = f"only {left[0]} lies {where}"
        else:
            what = (f"only {', '.join(left[:-1])} and {left[-1]} lie {where}, fewer than two "
                    "distinct non-zero angles")
        stall = float(row["stall_angle_deg"]) if stalled else np.inf
        lost = _rejected_in_range(rejected, float(row["speed_group"]), linear_max_deg, stall)
        out.append(f"fin lift slope at U ≈ {row['speed_group']:.2f} m/s: {what}; no slope"
                   f"{lost}.")
    return out


def _rejected_in_range(rejected: pd.DataFrame | None, speed: float,
                       linear_max_deg: float, stall_deg: float) -> str:
    """" (run 14 at 5° was rejected)" for the rejected runs of a speed group within the linear
    range (|α| <= ``linear_max_deg`` and below ``stall_deg``; "" for none)."""
    if rejected is None or rejected.empty or not {"run", "angle_deg", "speed_nominal"} <= set(
            rejected.columns):
        return ""
    nominal = rejected["speed_nominal"].to_numpy(dtype=float)
    angle = rejected["angle_deg"].to_numpy(dtype=float)
    mine = ((np.abs(nominal - speed) <= 0.05 * speed) & (np.abs(angle) <= linear_max_deg)
            & (np.abs(angle) < stall_deg))
    if not mine.any():
        return ""
    runs = [f"run {_run_label(r)} at {a:g}°"
            for r, a in zip(rejected["run"][mine], angle[mine], strict=True)]
    listed = runs[0] if len(runs) == 1 else f"{', '.join(runs[:-1])} and {runs[-1]}"
    return f" ({listed} {'was' if len(runs) == 1 else 'were'} rejected)"


def force_vs_speed(fin_df: pd.DataFrame) -> pd.DataFrame:
    """Long table for the "lift and drag against speed at each angle" plots.

    Parameters
    ----------
    fin_df : pandas.DataFrame
        With angle_deg [deg], speed_mean [m/s], drag_mean [N], lift_mean [N].

    Returns
    -------
    pandas.DataFrame
        Columns angle_deg [deg], speed_mean [m/s], drag_mean [N], lift_mean [N], sorted by
        angle then speed.
    """
    cols = ("angle_deg", "speed_mean", "drag_mean", "lift_mean")
    _require(fin_df, cols, "The fin table")
    return (
        fin_df.loc[:, list(cols)]
        .sort_values(["angle_deg", "speed_mean"], kind="stable")
        .reset_index(drop=True)
    )


def _sci(x: float, keep_zero: bool = True) -> str:
    """8.1e4 style: one decimal, no '+' or leading zeros; 1e5 when ``keep_zero`` is False."""
    mantissa, _, exponent = f"{x:.1e}".partition("e")
    if not keep_zero and mantissa.endswith(".0"):
        mantissa = mantissa[:-2]
    return f"{mantissa}e{int(exponent)}"


def _run_label(run: object) -> str:
    if isinstance(run, float | np.floating) and float(run).is_integer():
        return str(int(run))
    return str(run)


def low_reynolds_warnings(fin_df: pd.DataFrame, re_threshold: float = 1e5) -> list[str]:
    """One sentence per run whose chord Reynolds number is below ``re_threshold``.

    Below about 1e5 the NACA 0015 section data of Sheldahl & Klimas [3]_ change fast (and not
    monotonically) with Re, so the run's comparison with the table is weak.

    Parameters
    ----------
    fin_df : pandas.DataFrame
        With ``run`` and ``re`` [-] (on the chord).
    re_threshold : float, default 1e5
        Reynolds number below which a run is flagged [-].

    Returns
    -------
    list of str
        E.g. "run 12: Re = 8.1e4 on the chord is below 1e5, where the section data change fast
        with Re; the comparison with Sandia is weak." In the order of ``fin_df``.
    """
    _require(fin_df, ("run", "re"), "The fin table")
    limit = _sci(re_threshold, keep_zero=False)
    out = []
    for run, re in zip(fin_df["run"], fin_df["re"].to_numpy(dtype=float), strict=True):
        if np.isfinite(re) and re < re_threshold:
            out.append(
                f"run {_run_label(run)}: Re = {_sci(re)} on the chord is below {limit}, where "
                "the section data change fast with Re; the comparison with Sandia is weak."
            )
    return out


# --------------------------------------------------------------------------------------------
# Control derivatives
# --------------------------------------------------------------------------------------------


def control_lift_slope(
    curves: pd.DataFrame, linear_max_deg: float = 10.0
) -> tuple[float, str]:
    """The fin lift slope for the control derivatives, and a sentence saying which it is.

    The mean of the measured linear-range lift slopes of :func:`fin_curves` over the speed
    groups that have one (|alpha| <= ``linear_max_deg`` and below each group's stall; groups
    without a slope are left out, never replaced by a secant).

    Parameters
    ----------
    curves : pandas.DataFrame
        Output of :func:`fin_curves` (speed_group [m/s], lift_slope [1/rad], slope_angles_deg).
    linear_max_deg : float, default 10.0
        The linear range the curves were fitted with [deg].

    Returns
    -------
    slope : float
        dC_L/d(alpha) on the fin's planform area [1/rad]; NaN when no group has a slope.
    source : str
        E.g. "mean of the measured linear-range lift slopes (|α| ≤ 10°, below stall) of the
        speed groups 1.00 m/s (0 2.5 5°), 1.50 m/s (0 2.5 5 7.5°)".
    """
    _require(curves, ("speed_group", "lift_slope", "slope_angles_deg"), "The fin curves")
    ok = curves[np.isfinite(curves["lift_slope"].to_numpy(dtype=float))]
    if ok.empty:
        return np.nan, "no speed group has a linear-range lift slope"
    groups = ", ".join(
        f"{g:.2f} m/s ({a}°)"
        for g, a in zip(ok["speed_group"], ok["slope_angles_deg"], strict=True)
    )
    word = "slope" if len(ok) == 1 else "slopes"
    what = "measured linear-range lift " + word + f" (|α| ≤ {linear_max_deg:g}°, below stall)"
    source = (f"{what} of the speed group {groups}" if len(ok) == 1
              else f"mean of the {what} of the speed groups {groups}")
    return float(ok["lift_slope"].mean()), source


def control_derivatives(
    lift_slope_per_rad: float,
    fin_area_m2: float,
    x_fin_m: float,
    rho: float,
    slope_source: str = "given",
) -> pd.DataFrame:
    """Fin control derivatives in the AUV-model convention of Prestero (2001) [2]_.

    Each fin of a pair gives lift L = 1/2 rho c_La S_fin delta_e u^2; a pair of rudders (or of
    stern planes) therefore gives rho c_La S_fin delta u^2, acting at x_fin. With SNAME body axes
    (x forward, y starboard, z down), the force and moment terms Y = Y_uudr u^2 delta_r,
    Z = Z_uuds u^2 delta_s, M = M_uuds u^2 delta_s, N = N_uudr u^2 delta_r, and moments
    M = -x_fin Z, N = x_fin Y of the fin force:

        Y_uudr =  rho c_La S_fin            [kg/(m rad)]
        Z_uuds = -rho c_La S_fin            [kg/(m rad)]
        M_uuds =  rho c_La S_fin x_fin      [kg/rad]
        N_uudr =  rho c_La S_fin x_fin      [kg/rad]

    (Prestero [2]_, "Control fin forces and moments"; the same expressions are used in the
    REMUS simulation codes derived from it.) x_fin is negative for fins aft of the origin, which
    makes M_uuds and N_uudr negative, the sign pattern of the REMUS values in Prestero's
    coefficient table (Y_uudr = 9.64, Z_uuds = -9.64, M_uuds = N_uudr = -6.15).

    Parameters
    ----------
    lift_slope_per_rad : float
        Fin lift slope dC_L/d(delta) on S_fin [1/rad] (finite-span, measured in the linear
        range, e.g. :func:`control_lift_slope` of :func:`fin_curves`).
    fin_area_m2 : float
        Planform area of one fin, S_fin [m^2].
    x_fin_m : float
        Axial position of the fins' centre of pressure from the body origin [m], negative aft.
    rho : float
        Water density [kg/m^3].
    slope_source : str, default "given"
        Which lift slope this is (see :func:`control_lift_slope`), carried to the table.

    Returns
    -------
    pandas.DataFrame
        Rows Y_uudr, Z_uuds, M_uuds, N_uudr; columns symbol, value, unit, convention,
        lift_slope (the c_La used [1/rad]) and lift_slope_source.
    """
    base = float(rho) * float(lift_slope_per_rad) * float(fin_area_m2)
    x_fin = float(x_fin_m)
    pair = "pair of fins, each L = 1/2 rho c_La S_fin delta u^2; Prestero (2001)"
    rows = [
        ("Y_uudr", base, "kg/(m*rad)", f"Y = Y_uudr u^2 delta_r; rho c_La S_fin; {pair}"),
        ("Z_uuds", -base, "kg/(m*rad)", f"Z = Z_uuds u^2 delta_s; -rho c_La S_fin; {pair}"),
        (
            "M_uuds",
            base * x_fin,
            "kg/rad",
            f"M = M_uuds u^2 delta_s; rho c_La S_fin x_fin (x_fin < 0 aft); {pair}",
        ),
        (
            "N_uudr",
            base * x_fin,
            "kg/rad",
            f"N = N_uudr u^2 delta_r; rho c_La S_fin x_fin (x_fin < 0 aft); {pair}",
        ),
    ]
    out = pd.DataFrame(rows, columns=["symbol", "value", "unit", "convention"])
    out["lift_slope"] = float(lift_slope_per_rad)
    out["lift_slope_source"] = str(slope_source)
    return out
