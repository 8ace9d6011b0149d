"""Pseudo-arclength continuation of fixed points of Pⁿ, with bifurcation detection and location.

Written here, small, because no library on the package index fits (docs/reproduction.md,
"Continuation"): ``bice`` continues equilibria of a residual with Jacobian-eigenvalue
stability (no Floquet multipliers, so no period-doubling or torus test, and it needs
numpy ≥ 2.4.2); ``pacopy`` is proprietary-licensed with a licence manager; ``bifpy`` is an
interface to AUTO-07p, which needs a Fortran build and continues periodic orbits of a
vector field by collocation — not a compiled Poincaré map.

The unknowns are u = (x, s): the reduced state and the scaled parameter s = p / scale.
A point satisfies F(x, p) = Pⁿ(x; p) − x = 0; the pseudo-arclength corrector adds the
hyperplane t·(u − u_pred) = 0 through the predictor u_pred = u_k + ds·t (t the unit
tangent), so folds are passed. ∂F/∂x = M − I comes from the variational equations,
∂F/∂p from one forward difference in p.

Test functions between consecutive points (each changes sign at one bifurcation):

* fold (saddle-node, the amplitude jump): the tangent's parameter component t_s;
* period doubling (a real multiplier through −1): Π(μᵢ + 1) = det(M + I);
* Neimark–Sacker (a complex pair through the unit circle): the number of non-real
  multipliers outside the circle changes; located on Π_{i<j}(μᵢμⱼ − 1) (the
  bialternate product), which vanishes when μᵢμ̄ᵢ = 1.

A detected event is located by regula falsi (Illinois) on its test function along the
arclength between the two points, each trial point corrected onto the branch.
:func:`switch_period_doubling` starts the period-2n branch from a located PD point
along the eigenvector of μ = −1.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from .maps import PeriodicMap
from .shooting import NEWTON_TOL, find_fixed_point, floquet_multipliers, stability_verdict

__all__ = ["MapFamily", "BranchPoint", "Bifurcation", "Branch", "continue_branch", "switch_period_doubling",
           "KINDS"]

#: event kinds and their labels
KINDS = {"fold": "LP", "period_doubling": "PD", "neimark_sacker": "NS"}


class MapFamily(Protocol):
    """A one-parameter family of stroboscopic maps."""

    #: parameter name (e.g. "speed_rpm")
    parameter: str
    #: the continuation works on s = p / scale (so that ds weighs states and parameter alike)
    scale: float

    def at(self, value: float) -> PeriodicMap: ...


@dataclass
class BranchPoint:
    """One corrected point of a branch."""

    parameter: float
    x: np.ndarray
    multipliers: np.ndarray
    sections: np.ndarray
    tangent: np.ndarray

    @property
    def stability(self) -> str:
        return stability_verdict(self.multipliers)


@dataclass
class Bifurcation:
    """A located bifurcation: ``kind`` in :data:`KINDS`, between branch points ``index`` and ``index + 1``."""

    kind: str
    index: int
    parameter: float
    x: np.ndarray
    multipliers: np.ndarray
    sections: np.ndarray
    located: bool
    test_value: float

    @property
    def label(self) -> str:
        return KINDS[self.kind]


@dataclass
class Branch:
    """A continued branch of period-n fixed points."""

    parameter: str
    n_periods: int
    points: list[BranchPoint] = field(default_factory=list)
    bifurcations: list[Bifurcation] = field(default_factory=list)
    message: str = ""

    @property
    def values(self) -> np.ndarray:
        return np.array([p.parameter for p in self.points])

    @property
    def states(self) -> np.ndarray:
        return np.array([p.x for p in self.points])

    @property
    def sections(self) -> np.ndarray:
        """(n_points, n, m): the n section points of each orbit."""
        return np.array([p.sections for p in self.points])

    @property
    def stability(self) -> np.ndarray:
        return np.array([p.stability for p in self.points])

    @property
    def max_multiplier(self) -> np.ndarray:
        return np.array([float(np.abs(p.multipliers).max()) for p in self.points])


# ---------------------------------------------------------------- test functions
def _pd_test(mu: np.ndarray) -> float:
    return float(np.real(np.prod(mu + 1.0)))


def _ns_count(mu: np.ndarray) -> int:
    return int(np.sum((np.abs(mu.imag) > 1e-9 * np.maximum(1.0, np.abs(mu))) & (np.abs(mu) > 1.0)))


def _ns_test(mu: np.ndarray) -> float:
    prods = np.outer(mu, mu)[np.triu_indices(len(mu), 1)] - 1.0
    return float(np.real(np.prod(prods)))


# ---------------------------------------------------------------- the corrector
#: the corrector accepts its best iterate at a residual up to this × tol once Newton stagnates
#: (integration noise of the map: rtol 1e-6 gives max |Pⁿ(x) − x| ≈ 1e-9 to 1e-8 on an orbit
#: with |μ| ≈ 80, where tol is 1e-9)
NOISE_FLOOR_FACTOR = 100.0
#: a branch ends after this many consecutive points at ds_min that each needed ≥ 5 corrector steps
#: (far out on a strongly unstable branch, e.g. |μ| ≈ 250 on the light-exciter plant's Δ branch
#: below 0.034, the corrector converges only linearly: the branch would crawl to max_points)
MAX_CRAWL_POINTS = 10
#: Newton has stagnated when an iteration cuts the residual by less than this factor
STAGNATION_RATIO = 0.5

class _Problem:
    def __init__(self, family: MapFamily, n_periods: int, tol: float) -> None:
        self.family = family
        self.n = int(n_periods)
        self.tol = tol
        self.dp_rel = 1e-6

    def residual_jacobian(self, u: np.ndarray):
        """F(u), [∂F/∂x | ∂F/∂s], multipliers, sections; None when the map fails."""
        x, s = u[:-1], float(u[-1])
        p = s * self.family.scale
        pmap = self.family.at(p)
        ev = pmap.evaluate(x, self.n, monodromy=True)
        if not ev.ok or ev.monodromy is None:
            return None
        dp = self.dp_rel * max(1.0, abs(p))
        ev2 = self.family.at(p + dp).evaluate(x, self.n)
        if not ev2.ok:
            return None
        f = pmap.difference(ev.value, x)
        fp = pmap.difference(ev2.value, ev.value) / dp * self.family.scale
        jac = np.hstack([ev.monodromy - np.eye(x.size), fp[:, None]])
        return f, jac, ev.monodromy, ev.sections

    def tangent(self, jac: np.ndarray, prev: np.ndarray) -> np.ndarray:
        a = np.vstack([jac, prev[None, :]])
        rhs = np.zeros(a.shape[0])
        rhs[-1] = 1.0
        try:
            t = np.linalg.solve(a, rhs)
        except np.linalg.LinAlgError:
            t = np.linalg.svd(jac)[2][-1]
        t /= np.linalg.norm(t)
        return t if t @ prev >= 0 else -t

    def correct(self, u_pred: np.ndarray, t: np.ndarray, max_iter: int = 8):
        """Newton on [F(u); t·(u − u_pred)] = 0. Returns (u, jac, M, sections, effort) or None.

        ``effort`` (what the step control reads) is the number of Newton steps to a residual
        within :data:`NOISE_FLOOR_FACTOR` × ``tol``: the last one or two steps below that only
        chase the integration noise, and counting them kept the step from ever growing again
        where the noise floor is near ``tol``.

        Converged: max |F| ≤ ``tol``; or, once Newton has stopped converging (the residual
        fell by less than :data:`STAGNATION_RATIO` in an iteration) at a residual within
        :data:`NOISE_FLOOR_FACTOR` × ``tol``, the best iterate: there the residual is the
        integration error of the map (amplified on a strongly unstable orbit) and no step
        size helps (the stall of docs/reproduction.md, light-exciter plant at Δ ≈ 0.0386).
        """
        u = u_pred.copy()
        best: tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int] | None = None
        prev = math.inf
        effort = max_iter
        for it in range(max_iter + 1):
            out = self.residual_jacobian(u)
            if out is None:
                return None
            f, jac, mono, sections = out
            fn = float(np.max(np.abs(f)))
            if it > 0 and (best is None or fn < best[0]):
                best = (fn, u.copy(), jac, mono, sections, it)
            if it > 0 and fn <= NOISE_FLOOR_FACTOR * self.tol:
                effort = min(effort, it)
            if fn <= self.tol and it > 0:
                return u, jac, mono, sections, effort
            if it > 1 and fn > STAGNATION_RATIO * prev and best is not None \
                    and best[0] <= NOISE_FLOOR_FACTOR * self.tol:
                return best[1], best[2], best[3], best[4], effort
            prev = fn
            g = np.append(f, t @ (u - u_pred))
            try:
                du = np.linalg.solve(np.vstack([jac, t[None, :]]), -g)
            except np.linalg.LinAlgError:
                return None
            if not np.all(np.isfinite(du)) or np.max(np.abs(du)) > 0.5:
                return None
            u = u + du
            if np.max(np.abs(du)) < 0.1 * self.tol and fn <= 10 * self.tol:
                out = self.residual_jacobian(u)
                if out is None:
                    return None
                return u, out[1], out[2], out[3], min(effort, it + 1)
        if best is not None and best[0] <= NOISE_FLOOR_FACTOR * self.tol:
            return best[1], best[2], best[3], best[4], effort
        return None


def _point(problem: _Problem, u: np.ndarray, jac: np.ndarray, mono: np.ndarray, sections: np.ndarray,
           t: np.ndarray) -> BranchPoint:
    return BranchPoint(float(u[-1] * problem.family.scale), u[:-1].copy(), floquet_multipliers(mono),
                       sections.copy(), t.copy())


def _locate(problem: _Problem, a: BranchPoint, ds: float, fn: Callable[[BranchPoint], float],
            fa: float, fb: float, max_iter: int = 12) -> tuple[BranchPoint | None, float]:
    """Regula falsi (Illinois) on fn along the arclength s ∈ (0, ds) from point ``a``."""
    scale = problem.family.scale
    ua = np.append(a.x, a.parameter / scale)
    lo, hi = 0.0, ds
    flo, fhi = fa, fb
    best: BranchPoint | None = None
    side = 0
    for _ in range(max_iter):
        s = hi - fhi * (hi - lo) / (fhi - flo) if fhi != flo else 0.5 * (lo + hi)
        if not (min(lo, hi) < s < max(lo, hi)):
            s = 0.5 * (lo + hi)
        up = ua + s * a.tangent
        res = problem.correct(up, a.tangent)
        if res is None:
            return best, abs(hi - lo)
        u, jac, mono, sec, _ = res
        best = _point(problem, u, jac, mono, sec, problem.tangent(jac, a.tangent))
        fs = fn(best)
        if abs(hi - lo) < 1e-7 * max(1.0, abs(ds)) or fs == 0.0:
            break
        if (fs > 0) == (fhi > 0):
            hi, fhi = s, fs
            if side == 1:
                flo *= 0.5
            side = 1
        else:
            lo, flo = s, fs
            if side == -1:
                fhi *= 0.5
            side = -1
    return best, abs(hi - lo)


def continue_branch(
    family: MapFamily,
    x0: np.ndarray,
    p0: float,
    *,
    n_periods: int = 1,
    p_min: float = -math.inf,
    p_max: float = math.inf,
    direction: int = 1,
    ds: float = 0.02,
    ds_min: float = 1e-5,
    ds_max: float = 0.1,
    max_points: int = 200,
    tol: float = NEWTON_TOL,
    locate: bool = True,
    initial_tangent: np.ndarray | None = None,
    progress: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    """Follow the period-n fixed points of ``family`` from (x0, p0).

    Parameters
    ----------
    family : MapFamily
    x0 : ndarray
        Start state (reduced); corrected at p0 first (unless ``initial_tangent`` is given:
        then (x0, p0) is taken as a point of the branch, e.g. a PD point to switch from).
    p0 : float
        Start parameter value.
    n_periods : int
        n of Pⁿ.
    p_min, p_max : float
        Stop when the parameter leaves this interval.
    direction : {1, -1}
        Initial direction of the parameter.
    ds, ds_min, ds_max : float
        Arclength step in (x, p/scale) and its limits (halved on a failed corrector,
        ×1.5 after an easy one).
    max_points : int
    tol : float
        Corrector tolerance on max |Pⁿ(x) − x|.
    locate : bool
        Locate each detected bifurcation (regula falsi); else report the bracketing point.
    initial_tangent : ndarray, optional
        Start direction in (x, s) (branch switching).
    progress : callable, optional
        Called with each new point.
    """
    if direction not in (1, -1):
        raise ValueError(f"direction must be 1 or -1, got {direction!r}")
    problem = _Problem(family, n_periods, tol)
    branch = Branch(family.parameter, int(n_periods))
    scale = family.scale
    if initial_tangent is None:
        fp = find_fixed_point(family.at(p0), x0, n_periods, tol=tol)
        if not fp.converged:  # the map's noise floor may lie above tol (see _Problem.correct)
            fp = find_fixed_point(family.at(p0), fp.x, n_periods, tol=NOISE_FLOOR_FACTOR * tol)
        if not fp.converged:
            branch.message = f"no fixed point at the start: {fp.message}"
            return branch
        x0 = fp.x
    u = np.append(np.asarray(x0, dtype=float), p0 / scale)
    out = problem.residual_jacobian(u)
    if out is None:
        branch.message = "the map failed at the start point"
        return branch
    f, jac, mono, sections = out
    if initial_tangent is None:
        guess = np.zeros(u.size)
        guess[-1] = float(direction)
        t = problem.tangent(jac, guess)
    else:
        t = np.asarray(initial_tangent, dtype=float) / np.linalg.norm(initial_tangent)
    current = _point(problem, u, jac, mono, sections, t)
    branch.points.append(current)
    if progress:
        progress(current)
    h = float(ds)
    crawl = 0
    while len(branch.points) < max_points:
        u_pred = u + h * t
        res = problem.correct(u_pred, t)
        if res is None:
            h *= 0.5
            if h < ds_min:
                branch.message = f"step size below ds_min at {family.parameter} = {current.parameter:.6g}"
                break
            continue
        u_new, jac, mono, sections, iters = res
        t_new = problem.tangent(jac, t)
        new = _point(problem, u_new, jac, mono, sections, t_new)
        _detect(problem, branch, current, new, h, locate)
        branch.points.append(new)
        if progress:
            progress(new)
        u, t, current = u_new, t_new, new
        if iters <= 2:
            h = min(ds_max, 1.5 * h)
        elif iters >= 5:
            h = max(ds_min, 0.5 * h)
        if not p_min <= new.parameter <= p_max:
            branch.message = f"left [{p_min:g}, {p_max:g}]"
            break
        if len(branch.points) > 4 and _closes(problem, branch.points[0], branch.points[-2], new):
            branch.message = f"closed: the branch returned to its start (an isola) after {len(branch.points)} points"
            break
        crawl = crawl + 1 if h <= ds_min and iters >= 5 else 0
        if crawl >= MAX_CRAWL_POINTS:
            branch.message = (f"crawling at ds_min at {family.parameter} = {new.parameter:.6g} (the corrector "
                              f"converges only slowly; max |μ| = {np.abs(new.multipliers).max():.3g})")
            break
    else:
        branch.message = f"max_points = {max_points} reached"
    return branch


def _closes(problem: _Problem, first: BranchPoint, a: BranchPoint, b: BranchPoint) -> bool:
    """True when the step a → b passed the branch's first orbit (a closed branch, an isola): one of
    the first orbit's n section points (a period-n orbit returns cyclically shifted after one lap)
    lies within a quarter of the step's length of the segment a–b, in (x, p/scale), angles mod 2π."""
    pmap = problem.family.at(b.parameter)
    scale = problem.family.scale
    seg = np.append(pmap.difference(b.x, a.x), (b.parameter - a.parameter) / scale)
    length = float(np.linalg.norm(seg))
    if length == 0.0:
        return False
    for x in first.sections:
        w = np.append(pmap.difference(x, a.x), (first.parameter - a.parameter) / scale)
        lam = float(np.clip(w @ seg / length**2, 0.0, 1.0))
        if 0.0 < lam <= 1.0 and float(np.linalg.norm(w - lam * seg)) < 0.25 * length:
            return True
    return False


def _detect(problem: _Problem, branch: Branch, a: BranchPoint, b: BranchPoint, ds: float, locate: bool) -> None:
    idx = len(branch.points) - 1
    tests: list[tuple[str, Callable[[BranchPoint], float]]] = []
    if a.tangent[-1] * b.tangent[-1] < 0:  # (a switched branch starts with t_s = 0 exactly: no fold)
        tests.append(("fold", lambda q: float(q.tangent[-1])))
    if (_pd_test(a.multipliers) > 0) != (_pd_test(b.multipliers) > 0):
        tests.append(("period_doubling", lambda q: _pd_test(q.multipliers)))
    if _ns_count(a.multipliers) != _ns_count(b.multipliers):
        tests.append(("neimark_sacker", lambda q: _ns_test(q.multipliers)))
    for kind, fn in tests:
        fa, fb = fn(a), fn(b)
        where: BranchPoint | None = None
        located = False
        if locate and (fa > 0) != (fb > 0):
            where, _ = _locate(problem, a, ds, fn, fa, fb)
            located = where is not None
        if where is None:
            where = b
        branch.bifurcations.append(Bifurcation(kind, idx, where.parameter, where.x.copy(), where.multipliers.copy(),
                                               where.sections.copy(), located, fn(where)))


def switch_period_doubling(family: MapFamily, branch: Branch, bif: Bifurcation, *, ds: float = 0.02,
                           **kwargs) -> Branch:
    """Start the period-2n branch at a located period-doubling point.

    At the PD point the period-2n branch crosses the period-n one with tangent (v, 0),
    v the eigenvector of μ = −1; the first predictor steps along it (both signs give the
    two points of the same 2-cycle). ``kwargs`` go to :func:`continue_branch`.
    """
    if bif.kind != "period_doubling":
        raise ValueError(f"not a period-doubling point: {bif.kind!r}")
    n = branch.n_periods
    pmap = family.at(bif.parameter)
    ev = pmap.evaluate(bif.x, n, monodromy=True)
    if ev.monodromy is None:
        raise ValueError("the map failed at the period-doubling point")
    mu, vec = np.linalg.eig(ev.monodromy)
    k = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(vec[:, k])
    v /= np.linalg.norm(v)
    tangent = np.append(v, 0.0)
    return continue_branch(family, bif.x, bif.parameter, n_periods=2 * n, initial_tangent=tangent, ds=ds,
                           **kwargs)
