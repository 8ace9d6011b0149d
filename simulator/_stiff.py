"""The stiff leg of a run: scipy's LSODA from where Dormand–Prince became stiff.

A journal whirling close to its bushing wall (ε ≳ 0.95) sits on an oil film whose
squeeze-film damping gives the light journal masses eigenvalues of −10⁴…−10⁵ per radian
of shaft rotation. The explicit Dormand–Prince 5(4) of :func:`_kernels.integrate` then
crawls along its stability limit (h·|λ| ≈ 3.3): 10⁵–2·10⁵ steps per revolution, a fifth
of them rejected, ~0.1–0.3 s per revolution. :func:`_kernels.integrate` stops when it
detects this (``STATUS_STIFF``) and :func:`continue_stiff` goes on with LSODA (Petzold's
automatic Adams/BDF switching, ODEPACK through :class:`scipy.integrate.LSODA`) whose BDF
steps are limited by accuracy, not stability — 20–50× fewer right-hand-side calls there.

The outputs keep the explicit integrator's contract: samples on the record grid and
Poincaré points by the solver's dense output, ``contact`` once an accepted state reaches
ε ≥ ``CONTACT_ECCENTRICITY``, ``diverged`` for a non-finite or unbounded state or a spent
step budget. Non-stiff runs never get here, so their results are unchanged to the bit.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.integrate import LSODA

from rotordiag.core.numerics import NUMBA_OPTIONS

from . import _kernels as K
from .steady._variational import jacobian_times

#: LSODA runs at this fraction of the explicit integrator's rtol and atol: its per-step error
#: control with lower-order formulas loses more over a revolution than Dormand–Prince at the
#: same tolerances. Measured on a near-wall whirl (tests/test_stiff.py's plant, 3 revolutions
#: from revolution 50, against Radau IIA at rtol 1e-10): LSODA at the explicit tolerances
#: 1.2e-4, at 1/100 of them 1.2e-6; Dormand–Prince 0.8e-6 — at 4 ms against 160 ms per revolution.
TOLERANCE_FACTOR = 0.01


@njit(**NUMBA_OPTIONS)
def _jacobian(tau, y, p):
    """∂f/∂y by forward differences of ``rhs`` (the variational code's directional ones)."""
    n = y.shape[0]
    eye = np.eye(n)
    out = np.empty((n, n))
    f0 = np.empty(n)
    K.rhs(tau, y, p, f0)
    jacobian_times(tau, y, f0, eye, p, out, False, np.empty(n), np.empty(n), np.empty(n))
    return out


def continue_stiff(
    p: np.ndarray, y: np.ndarray, tau: float, tau_end: float, rtol: float, atol: float, max_steps: int,
    grid_t0: float, grid_dt: float, grid: np.ndarray, ng: int, pc_t0: float, pc_dt: float, pcs: np.ndarray,
    npc: int,
) -> tuple[int, float, np.ndarray, int, int, int, int, float]:
    """Integrate from (``tau``, ``y``) to ``tau_end`` with LSODA at ``TOLERANCE_FACTOR`` × the given
    tolerances, filling ``grid``/``pcs`` from rows ``ng``/``npc`` on (the explicit leg's counts).

    Returns
    -------
    status, tau, y, nfev, n_steps, n_grid, n_pc, emax
        ``status`` as :func:`_kernels.integrate` (0 ok, 1 contact, 2 diverged).
    """
    p = np.ascontiguousarray(p, dtype=float)
    solver = LSODA(lambda t, s: K.rhs_alloc(t, s, p), float(tau), np.array(y, dtype=float), float(tau_end),
                   rtol=rtol * TOLERANCE_FACTOR, atol=atol * TOLERANCE_FACTOR, jac=lambda t, s: _jacobian(t, s, p))
    n_grid, n_pc = grid.shape[0], pcs.shape[0]
    status, emax, steps = K.STATUS_OK, K.max_eccentricity(tau, np.asarray(y, dtype=float), p), 0
    y_out = np.array(y, dtype=float)
    while solver.status == "running":
        if steps >= max_steps:
            status = K.STATUS_DIVERGED
            break
        solver.step()
        steps += 1
        if solver.status == "failed":  # step size underflow: as the explicit leg's collapse
            status = K.STATUS_CONTACT if emax > 0.99 else K.STATUS_DIVERGED
            break
        t_new = solver.t
        due_grid = ng < n_grid and grid_t0 + ng * grid_dt <= t_new
        due_pc = npc < n_pc and pc_t0 + npc * pc_dt <= t_new
        if due_grid or due_pc:
            dense = solver.dense_output()
            while ng < n_grid and grid_t0 + ng * grid_dt <= t_new:
                grid[ng] = dense(grid_t0 + ng * grid_dt)
                ng += 1
            while npc < n_pc and pc_t0 + npc * pc_dt <= t_new:
                pcs[npc] = dense(pc_t0 + npc * pc_dt)
                npc += 1
        y_out = solver.y
        status, emax = K.accepted_state_status(t_new, y_out, p)
        if status != K.STATUS_OK:
            break
    tau_out = float(solver.t)
    if status == K.STATUS_OK and not math.isclose(tau_out, tau_end, rel_tol=0.0, abs_tol=1e-9 * max(1.0, tau_end)):
        status = K.STATUS_DIVERGED
    return status, tau_out, np.array(y_out, dtype=float), int(solver.nfev + solver.njev * (len(y_out) + 1)), steps, ng, npc, emax
