"""Compiled Dormand–Prince 5(4) integration of the state *and* its sensitivity matrix.

:func:`integrate_variational` advances y' = f(τ, y) with the same tableau and step
control as :func:`simulator._kernels.integrate` and, alongside, the variational
equations Φ' = J(τ, y) Φ (J = ∂f/∂y) with the *same* steps and stages. The step
size is controlled on y and Φ together (see below).

The Jacobian is never formed: each stage needs J·Ψ for the m columns of the stage
sensitivity Ψ, and every column is one directional finite difference of the
compiled right-hand side, J v ≈ (f(Y + ηv) − f(Y)) / η (forward) or
(f(Y + ηv) − f(Y − ηv)) / (2η) (central), with η chosen so that ‖ηv‖ is
≈ √ε·max(1, ‖Y‖) (forward) or ε^(1/3)·max(1, ‖Y‖) (central). This is what the
issue calls the variational equations with a documented equivalent: an exact
analytic Jacobian of the five mechanisms (the ``pin`` constraint, Capone's film
with its α branch) would be a second copy of the equations of motion to keep in
step with ``_kernels.rhs``; the directional differences reuse that one copy and
are accurate to ~1e-8 relative (forward) / ~1e-10 (central), far below what the
Floquet multipliers and Newton need. Because Φ follows the discrete
Runge–Kutta map of y step by step, it is the derivative of the *computed*
Poincaré map (Bock's internal numerical differentiation), not of a re-run with
other steps, so Newton converges quadratically on the map the integrator computes.

Φ is error-controlled with y (same tolerances, per entry): at an equilibrium y' = 0 and y
alone would allow one step per revolution, far outside the stability region of the fast
journal modes that Φ does see. Its stages are computed only for a step that y accepts.

Cost: 6 base stages + 6·m (forward) or 12·m (central) right-hand sides per step that y
accepts (the seventh Φ stage is the next step's first, as for y).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rotordiag.core.numerics import NUMBA_OPTIONS

from .._kernels import (
    _A,
    _B,
    _C,
    _E,
    _MIN_FACTOR,
    _SAFETY,
    STATUS_CONTACT,
    STATUS_DIVERGED,
    STATUS_OK,
    accepted_state_status,
    dp_step_factor,
    dp_trial_step,
    max_eccentricity,
    rhs,
)

_SQRT_EPS = math.sqrt(2.220446049250313e-16)
_CBRT_EPS = 2.220446049250313e-16 ** (1.0 / 3.0)


@njit(**NUMBA_OPTIONS)
def jacobian_times(tau, Y, fY, Psi, p, out, central, work_y, work_f, work_g):
    """out[:, c] = J(τ, Y) Psi[:, c] by directional finite differences of ``rhs``."""
    n, m = Psi.shape
    ny = 0.0
    for i in range(n):
        ny += Y[i] * Y[i]
    scale = max(1.0, math.sqrt(ny))
    for c in range(m):
        nv = 0.0
        for i in range(n):
            nv += Psi[i, c] * Psi[i, c]
        nv = math.sqrt(nv)
        if nv == 0.0:
            for i in range(n):
                out[i, c] = 0.0
            continue
        if central:
            eta = _CBRT_EPS * scale / nv
            for i in range(n):
                work_y[i] = Y[i] + eta * Psi[i, c]
            rhs(tau, work_y, p, work_f)
            for i in range(n):
                work_y[i] = Y[i] - eta * Psi[i, c]
            rhs(tau, work_y, p, work_g)
            for i in range(n):
                out[i, c] = (work_f[i] - work_g[i]) / (2.0 * eta)
        else:
            eta = _SQRT_EPS * scale / nv
            for i in range(n):
                work_y[i] = Y[i] + eta * Psi[i, c]
            rhs(tau, work_y, p, work_f)
            ok = True
            for i in range(n):
                if not math.isfinite(work_f[i]):
                    ok = False
            if not ok:  # outside the film's domain: step the other way
                eta = -eta
                for i in range(n):
                    work_y[i] = Y[i] + eta * Psi[i, c]
                rhs(tau, work_y, p, work_f)
            for i in range(n):
                out[i, c] = (work_f[i] - fY[i]) / eta


@njit(**NUMBA_OPTIONS)
def integrate_variational(y0, phi0, tau0, tau_end, p, rtol, atol, h0, max_steps, central, pc_out):
    """Integrate y and Φ = ∂y/∂(start) · phi0 from ``tau0`` to ``tau_end``.

    ``pc_out`` (shape (k, n)) receives y at τ0 + 2πj, j = 1..k (whole revolutions
    after the start, taken at step ends: the last step of each revolution is cut there).

    Returns
    -------
    status, tau, y, Phi, nfev, n_accepted, n_rejected, emax
    """
    n = y0.shape[0]
    m = phi0.shape[1]
    y = y0.copy()
    Phi = phi0.copy()
    y_new = np.empty(n)
    K = np.zeros((7, n))
    Ys = np.zeros((6, n))
    KV = np.zeros((7, n, m))
    Psi = np.empty((n, m))
    Phi_new = np.empty((n, m))
    work_y = np.empty(n)
    work_f = np.empty(n)
    work_g = np.empty(n)
    tau = tau0
    rhs(tau, y, p, K[0])
    nfev = 1
    if m > 0:
        jacobian_times(tau, y, K[0], Phi, p, KV[0], central, work_y, work_f, work_g)
        nfev += 2 * m if central else m
    nacc = 0
    nrej = 0
    h = h0
    step_rejected = False
    status = STATUS_OK
    emax = max_eccentricity(tau, y, p)
    n_pc = pc_out.shape[0]
    npc = 0
    two_pi = 2.0 * math.pi
    while tau < tau_end:
        if nacc + nrej >= max_steps:
            status = STATUS_DIVERGED
            break
        hmin = 1e-13 * max(1.0, abs(tau))
        if h < hmin:
            status = STATUS_CONTACT if emax > 0.99 else STATUS_DIVERGED
            break
        # stop exactly at the next whole revolution (Poincaré points) and at the end
        t_stop = tau_end
        if npc < n_pc:
            t_stop = min(t_stop, tau0 + two_pi * (npc + 1))
        if h > t_stop - tau:
            h = t_stop - tau
            if h < hmin:
                tau = t_stop
                if npc < n_pc and t_stop < tau_end:
                    for i in range(n):
                        pc_out[npc, i] = y[i]
                    npc += 1
                continue
        err = dp_trial_step(tau, h, y, p, K, Ys, y_new, rtol, atol)
        nfev += 6
        if not math.isfinite(err):
            h *= _MIN_FACTOR
            nrej += 1
            step_rejected = True
            continue
        if err < 1.0 and m > 0:
            # the sensitivities through the same stages (stage 0 is carried over, FSAL); their
            # error counts too: at an equilibrium y' = 0 and y alone would allow one step per revolution
            for s in range(1, 6):
                for i in range(n):
                    for c in range(m):
                        acc = 0.0
                        for j in range(s):
                            acc += _A[s, j] * KV[j, i, c]
                        Psi[i, c] = Phi[i, c] + h * acc
                jacobian_times(tau + _C[s] * h, Ys[s], K[s], Psi, p, KV[s], central, work_y, work_f, work_g)
            for i in range(n):
                for c in range(m):
                    acc = 0.0
                    for j in range(6):
                        acc += _B[j] * KV[j, i, c]
                    Phi_new[i, c] = Phi[i, c] + h * acc
            jacobian_times(tau + h, y_new, K[6], Phi_new, p, KV[6], central, work_y, work_f, work_g)
            nfev += 6 * (2 * m if central else m)
            errv2 = 0.0
            for i in range(n):
                for c in range(m):
                    e = 0.0
                    for j in range(7):
                        e += _E[j] * KV[j, i, c]
                    e *= h
                    sc = atol + rtol * max(abs(Phi[i, c]), abs(Phi_new[i, c]))
                    errv2 += (e / sc) ** 2
            err = max(err, math.sqrt(errv2 / (n * m)))
            if not math.isfinite(err):
                err = 2.0
        if err < 1.0:
            for i in range(n):
                for c in range(m):
                    Phi[i, c] = Phi_new[i, c]
                    KV[0, i, c] = KV[6, i, c]
            factor = dp_step_factor(err, step_rejected)
            tau = tau + h
            for i in range(n):
                y[i] = y_new[i]
                K[0, i] = K[6, i]
            nacc += 1
            step_rejected = False
            h *= factor
            if npc < n_pc and tau >= tau0 + two_pi * (npc + 1) - 1e-12 * max(1.0, abs(tau)):
                for i in range(n):
                    pc_out[npc, i] = y[i]
                npc += 1
            status, emax = accepted_state_status(tau, y, p)
            if status != STATUS_OK:
                break
        else:
            h *= max(_MIN_FACTOR, _SAFETY * err ** -0.2)
            nrej += 1
            step_rejected = True
    return status, tau, y, Phi, nfev, nacc, nrej, emax
