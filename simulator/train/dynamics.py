"""Time response of a train on its nonlinear bearings: the Craig–Bampton model in compiled kernels.

The reduced equations M p̈ + C(Ω) ṗ + K(t) p = f(t) + Σ_b f_b are integrated in time with an adaptive
Dormand–Prince 5(4) (the paper model's integrator and tolerances, ``rotordiag.core.numerics``), the
bearing films evaluated by ``rotordiag.simulator.bearings.bearing_force`` inside the kernel. The record
is sampled at exact shaft phases (``samples_per_rev`` per revolution, t = 0 at the start of the
transient, so t·Ω ≡ 0 mod 2π at the keyphasor); the journals are read relative to their bearing
housings, DC included. A plain bearing's journal reaching ε ≥ 0.999 ends the run as ``contact``; the other
films return NaN outside their bores, which ends it as ``diverged``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from numba import njit

from rotordiag.core.numerics import DEFAULT_RTOL, MAX_STEPS_PER_REV, NUMBA_OPTIONS

from ..bearings import BEARING_PLAIN, bearing_force
from .fe import Assembly, assemble
from .linear import bearing_coefficients
from .model import Train, TrainError
from .reduced import Reduced, reduce
from .static import static_state

# Dormand–Prince 5(4) tableau
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.array([
    [0, 0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
], dtype=float)
_E = np.array([71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
# dense output (Hairer's DOPRI5 continuous extension)
_D = np.array([-12715105075 / 11282082432, 0, 87487479700 / 32700410799, -10690763975 / 1880347072,
               701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423])

STATUS = ("ok", "contact", "diverged")
_ADAPTIVE_LEVELS = 13  # step-doubling ETD: 1, 2, …, 4096 steps per sample interval


@njit(**NUMBA_OPTIONS)
def _rhs(t, s, n, AK, AKc, AKs, AC, Minv, f0, U, ub, omega, sup, centres, codes, poff, pall, cpl, cplp, out):
    """ṡ for s = [p, ṗ]: accelerations from the precomputed M⁻¹-products."""
    th = omega * t
    c2 = math.cos(2.0 * th)
    s2 = math.sin(2.0 * th)
    for i in range(n):
        out[i] = s[n + i]
    f = f0.copy()
    for k in range(ub.shape[0]):
        a = th + ub[k, 1]
        amp = ub[k, 0] * omega * omega
        ca = amp * math.cos(a)
        sa = amp * math.sin(a)
        for i in range(n):
            f[i] += ca * U[k, 0, i] + sa * U[k, 1, i]
    for b in range(sup.shape[0]):
        j = sup[b]
        x = s[j] - centres[b, 0]
        y = s[j + 1] - centres[b, 1]
        fx, fy = bearing_force(codes[b], pall[poff[b]:poff[b + 1]], x, y, s[n + j], s[n + j + 1], omega)
        for i in range(n):
            f[i] += Minv[i, j] * fx + Minv[i, j + 1] * fy
    for k in range(cpl.shape[0]):
        ja = cpl[k, 0]
        jb = cpl[k, 1]
        kc, cc, d, psi, gam = cplp[k, 0], cplp[k, 1], cplp[k, 2], cplp[k, 3], cplp[k, 4]
        a = 2.0 * th + psi + gam
        ux = 0.5 * d * math.cos(a)
        uy = 0.5 * d * math.sin(a)
        udx = -d * omega * math.sin(a)
        udy = d * omega * math.cos(a)
        fx = kc * ux + cc * udx
        fy = kc * uy + cc * udy
        for i in range(n):
            f[i] += (Minv[i, jb] - Minv[i, ja]) * fx + (Minv[i, jb + 1] - Minv[i, ja + 1]) * fy
    for i in range(n):
        acc = f[i]
        for j in range(n):
            acc -= (AK[i, j] + c2 * AKc[i, j] + s2 * AKs[i, j]) * s[j] + AC[i, j] * s[n + j]
        out[n + i] = acc


@njit(**NUMBA_OPTIONS)
def _integrate(s0, t_end, h0, rtol, atol, grid_dt, grid_t0, grid, max_steps, args_n, AK, AKc, AKs, AC, Minv, f0,
               U, ub, omega, sup, centres, codes, poff, pall, cpl, cplp, clear, A, C, E, D):
    """Adaptive Dormand–Prince 5(4) from t = 0 to ``t_end``; rows of ``grid`` at t = grid_t0 + k·grid_dt.
    Returns status (0 ok, 1 contact, 2 diverged), final state, accepted and rejected steps, evaluations."""
    m = s0.shape[0]
    n = args_n
    s = s0.copy()
    K = np.zeros((7, m))
    tmp = np.empty(m)
    s_new = np.empty(m)
    t = 0.0
    h = h0
    _rhs(t, s, n, AK, AKc, AKs, AC, Minv, f0, U, ub, omega, sup, centres, codes, poff, pall, cpl, cplp, K[0])
    nfev = 1
    nacc = 0
    nrej = 0
    ng = 0
    n_grid = grid.shape[0]
    while ng < n_grid and grid_t0 + ng * grid_dt <= t:
        grid[ng] = s
        ng += 1
    status = 0
    while t < t_end:
        if nacc + nrej > max_steps:
            status = 2
            break
        if t + h > t_end:
            h = t_end - t
        for st in range(1, 7):
            for i in range(m):
                acc = s[i]
                for j in range(st):
                    acc += h * A[st, j] * K[j, i]
                tmp[i] = acc
            _rhs(t + C[st] * h, tmp, n, AK, AKc, AKs, AC, Minv, f0, U, ub, omega, sup, centres, codes, poff, pall,
                 cpl, cplp, K[st])
        nfev += 6
        for i in range(m):
            s_new[i] = tmp[i]
        err = 0.0
        for i in range(m):
            e = 0.0
            for j in range(7):
                e += E[j] * K[j, i]
            sc = atol + rtol * max(abs(s[i]), abs(s_new[i]))
            err += (h * e / sc) ** 2
        err = math.sqrt(err / m)
        if not math.isfinite(err):
            h *= 0.2
            nrej += 1
            if h < 1e-14 * max(1.0, t_end):
                status = 2
                break
            continue
        if err <= 1.0:
            # dense output for the grid points inside (t, t + h]
            while ng < n_grid and grid_t0 + ng * grid_dt <= t + h:
                th = (grid_t0 + ng * grid_dt - t) / h
                th1 = 1.0 - th
                for i in range(m):
                    r1 = s_new[i] - s[i]
                    k0 = h * K[0, i]
                    r2 = k0 - r1
                    r3 = r1 - h * K[6, i] - r2
                    dd = 0.0
                    for j in range(7):
                        dd += D[j] * K[j, i]
                    r4 = h * dd
                    grid[ng, i] = s[i] + th * (r1 + th1 * (r2 + th * (r3 + th1 * r4)))
                ng += 1
            t += h
            for i in range(m):
                s[i] = s_new[i]
                K[0, i] = K[6, i]
            nacc += 1
            for b in range(sup.shape[0]):
                j = sup[b]
                ex = (s[j] - centres[b, 0]) / clear[b]
                ey = (s[j + 1] - centres[b, 1]) / clear[b]
                if ex * ex + ey * ey >= 0.999 * 0.999 and codes[b] == BEARING_PLAIN:
                    status = 1
            if status != 0:
                break
            fac = 0.9 * err ** -0.2 if err > 0 else 5.0
            h *= min(5.0, max(0.2, fac))
        else:
            nrej += 1
            h *= max(0.2, 0.9 * err ** -0.2)
    return status, t, s, nacc, nrej, nfev, ng


@njit(**NUMBA_OPTIONS)
def _mv(A, x, out):
    for i in range(A.shape[0]):
        acc = 0.0
        for j in range(A.shape[1]):
            acc += A[i, j] * x[j]
        out[i] = acc


@njit(**NUMBA_OPTIONS)
def _remainder(t, s, n, Lb, f, args_tuple, out):
    """N(t, s): the accelerations of the full right-hand side minus the linear operator's (bottom half)."""
    AK, AKc, AKs, AC, Minv, f0, U, ub, omega, sup, centres, codes, poff, pall, cpl, cplp = args_tuple
    _rhs(t, s, n, AK, AKc, AKs, AC, Minv, f0, U, ub, omega, sup, centres, codes, poff, pall, cpl, cplp, f)
    for i in range(n):
        acc = f[n + i]
        for j in range(2 * n):
            acc -= Lb[i, j] * s[j]
        out[i] = acc


@njit(**NUMBA_OPTIONS)
def _etd_step(u, t, h, n, Lb, E, E2, P1h, F1, F2, F3, args_tuple, W, out):
    """One ETDRK4 step (Cox & Matthews 2002) of s' = L s + N(t, s) from ``u`` at ``t`` into ``out``;
    E = e^{hL}, E2 = e^{hL/2}, P1h = (h/2)·φ1(hL/2)[:, n:], F1..F3 = h·(φ1 − 3φ2 + 4φ3, φ2 − 2φ3,
    −φ2 + 4φ3)(hL)[:, n:] (only the lower half of N is non-zero); ``W`` (9, 2n) is workspace."""
    m = 2 * n
    f = W[0]
    Nu = W[1, :n]
    Na = W[2, :n]
    Nb = W[3, :n]
    Nc = W[4, :n]
    tmpn = W[5, :n]
    Eu = W[6]
    b = W[7]
    tmp = W[8]
    a = out  # ``out`` holds the first stage, then the result
    _remainder(t, u, n, Lb, f, args_tuple, Nu)
    _mv(E2, u, Eu)
    _mv(P1h, Nu, tmp)
    for i in range(m):
        a[i] = Eu[i] + tmp[i]
    _remainder(t + 0.5 * h, a, n, Lb, f, args_tuple, Na)
    _mv(P1h, Na, tmp)
    for i in range(m):
        b[i] = Eu[i] + tmp[i]
    _remainder(t + 0.5 * h, b, n, Lb, f, args_tuple, Nb)
    _mv(E2, a, Eu)  # c, stored in Eu (no longer needed)
    for i in range(n):
        tmpn[i] = 2.0 * Nb[i] - Nu[i]
    _mv(P1h, tmpn, tmp)
    for i in range(m):
        Eu[i] += tmp[i]
    _remainder(t + h, Eu, n, Lb, f, args_tuple, Nc)
    _mv(E, u, a)
    _mv(F1, Nu, tmp)
    for i in range(m):
        a[i] += tmp[i]
    for i in range(n):
        tmpn[i] = Na[i] + Nb[i]
    _mv(F2, tmpn, tmp)
    for i in range(m):
        a[i] += 2.0 * tmp[i]
    _mv(F3, Nc, tmp)
    for i in range(m):
        out[i] = a[i] + tmp[i]


@njit(**NUMBA_OPTIONS)
def _check(u, sup, centres, clear, codes):
    """0 when the state is finite and every plain journal inside ε < 0.999, 1 contact, 2 diverged."""
    for i in range(u.shape[0]):
        if not math.isfinite(u[i]):
            return 2
    for bb in range(sup.shape[0]):
        j = sup[bb]
        ex = (u[j] - centres[bb, 0]) / clear[bb]
        ey = (u[j + 1] - centres[bb, 1]) / clear[bb]
        if ex * ex + ey * ey >= 0.999 * 0.999 and codes[bb] == BEARING_PLAIN:
            return 1
    return 0


@njit(**NUMBA_OPTIONS)
def _integrate_etd(s0, h, n_steps, grid_every, grid_first, grid, n, Lb, E, E2, P1h, F1, F2, F3, args_tuple,
                   sup, centres, clear, codes):
    """Fixed-step ETDRK4 (:func:`_etd_step`). Grid rows every ``grid_every`` steps from step ``grid_first``.
    Returns status (0 ok, 1 contact, 2 diverged), the final state and the step count."""
    m = 2 * n
    u = s0.copy()
    v = np.empty(m)
    W = np.empty((9, m))
    ng = 0
    status = 0
    k = 0
    for k in range(n_steps + 1):
        if k >= grid_first and (k - grid_first) % grid_every == 0 and ng < grid.shape[0]:
            grid[ng] = u
            ng += 1
        if k == n_steps:
            break
        _etd_step(u, k * h, h, n, Lb, E, E2, P1h, F1, F2, F3, args_tuple, W, v)
        u[:] = v
        status = _check(u, sup, centres, clear, codes)
        if status != 0:
            break
    return status, u, k


@njit(**NUMBA_OPTIONS)
def _etd_span(u, t, dt, level, n, Lb, Es, E2s, P1hs, F1s, F2s, F3s, args_tuple, W, v, out):
    """2**level ETDRK4 steps of dt / 2**level from ``u`` at ``t`` into ``out``."""
    k_steps = 1 << level
    h = dt / k_steps
    out[:] = u
    for k in range(k_steps):
        _etd_step(out, t + k * h, h, n, Lb, Es[level], E2s[level], P1hs[level], F1s[level], F2s[level],
                  F3s[level], args_tuple, W, v)
        out[:] = v


@njit(**NUMBA_OPTIONS)
def _integrate_etd_adaptive(s0, dt, n_intervals, grid_first, grid, level0, n, Lb, Es, E2s, P1hs, F1s, F2s, F3s,
                            rtol, scale, args_tuple, sup, centres, clear, codes):
    """ETDRK4 with step-doubling error control over the sample intervals of length ``dt``: each interval
    is integrated with 2**l and 2**(l+1) steps; the difference (the coarse solution's local error, 16×
    the fine one's for a fourth-order method) must be ≤ 1 in the weighted RMS norm
    |Δ|/(rtol·(scale + |s|)); the finer solution is kept. l rises until the test passes (status 3 when
    the finest level available fails) and falls by one after an interval passing with a 32× margin.
    Grid rows at the interval ends from interval ``grid_first``. Returns status (0 ok, 1 contact,
    2 diverged, 3 tolerance not met), final state, steps taken, the largest level used."""
    m = 2 * n
    n_levels = Es.shape[0]
    u = s0.copy()
    coarse = np.empty(m)
    fine = np.empty(m)
    v = np.empty(m)
    W = np.empty((9, m))
    level = min(level0, n_levels - 2)
    ng = 0
    status = 0
    steps = 0
    lmax = level
    for k in range(n_intervals + 1):
        if k >= grid_first and ng < grid.shape[0]:
            grid[ng] = u
            ng += 1
        if k == n_intervals:
            break
        t = k * dt
        _etd_span(u, t, dt, level, n, Lb, Es, E2s, P1hs, F1s, F2s, F3s, args_tuple, W, v, coarse)
        steps += 1 << level
        while True:
            _etd_span(u, t, dt, level + 1, n, Lb, Es, E2s, P1hs, F1s, F2s, F3s, args_tuple, W, v, fine)
            steps += 1 << (level + 1)
            err = 0.0
            for i in range(m):
                sc = rtol * (scale[i] + max(abs(fine[i]), abs(u[i])))
                err += ((fine[i] - coarse[i]) / sc) ** 2
            err = math.sqrt(err / m)
            if err <= 1.0:
                break
            if level + 2 >= n_levels:
                status = 3 if math.isfinite(err) else 2
                break
            level += 1
            coarse[:] = fine
        if level + 1 > lmax:
            lmax = level + 1
        u[:] = fine
        if status == 0:
            status = _check(u, sup, centres, clear, codes)
        if status != 0:
            break
        if err < 1.0 / 32.0 and level > 0:
            level -= 1
    return status, u, steps, lmax


@dataclass
class TrainRun:
    """Output of :func:`simulate_train`.

    ``journal_m`` (n, n_bearings, 2): each journal relative to its bearing housing, DC included (what a
    pair of x/y proximity probes reads); ``keyphasor_s``: times of the once-per-revolution mark
    (t·Ω ≡ 0 mod 2π, the unbalance angles' reference). ``log_decrement``: the least-damped mode's about
    the static state (≤ 0: beyond the linear stability threshold, said in ``message``).
    """

    time_s: np.ndarray
    journal_m: np.ndarray
    keyphasor_s: np.ndarray
    status: str
    speed_rpm: float
    clearance_m: np.ndarray
    bearing_names: list
    final_state: np.ndarray
    n_accepted: int
    n_rejected: int
    nfev: int
    wall_time_s: float
    inputs: dict = field(default_factory=dict)
    states: np.ndarray | None = None
    basis: np.ndarray | None = None
    log_decrement: float = math.nan
    message: str = ""

    def node_m(self, node: int) -> np.ndarray:
        """(x, y) of any node of the full model at the samples, m (needs ``record_state=True``)."""
        if self.states is None or self.basis is None:
            raise ValueError("run simulate_train with record_state=True to read interior nodes")
        n = self.basis.shape[1]
        return self.states[:, :n] @ self.basis[4 * node: 4 * node + 2].T

    def probe_m(self, bearing: int, angle_deg: float) -> np.ndarray:
        """Signal of a proximity probe at ``angle_deg`` (from +x toward +y) at ``bearing``: the journal
        displacement along the probe's axis, m, DC included."""
        a = math.radians(angle_deg)
        return self.journal_m[:, bearing, 0] * math.cos(a) + self.journal_m[:, bearing, 1] * math.sin(a)

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@dataclass
class Kernel:
    """The compiled system's arrays at one speed (build once, integrate many times)."""

    red: Reduced
    speed_rad_s: float
    args: tuple
    clear: np.ndarray
    static_q: np.ndarray | None = None
    journal_m: np.ndarray | None = None
    etd: dict = field(default_factory=dict)
    stability: tuple[float, float] | None = None


#: a log decrement within this of 0 is an undamped mode read through round-off (|Re λ| ~ ε |λ|), not a whirl
UNDAMPED_LOGDEC = 1e-9


def linear_stability(kern: Kernel, speed_rpm: float) -> tuple[float, float]:
    """Log decrement and frequency (Hz) of the least-damped oscillating mode of the reduced train
    linearised at its static state (bearings by their coefficients there): a log decrement ≤ 0 puts the
    speed beyond the linear stability threshold (oil whirl/whip grows from the static state)."""
    if kern.stability is None:
        _ensure_static(kern, speed_rpm)
        lam = np.linalg.eigvals(_linear_operator(kern))
        osc = lam[lam.imag > 1e-6]
        logdec = -2 * math.pi * osc.real / osc.imag
        # an undamped mode (a stiff element without damping: the chord springs' MHz and an overhung coupling's GHz
        # modes) has a log decrement of 0 up to round-off, whose sign is the machine's: not a growing whirl
        damped = np.abs(logdec) > UNDAMPED_LOGDEC
        if damped.any():
            osc, logdec = osc[damped], logdec[damped]
        k = int(np.argmin(logdec))
        kern.stability = (float(logdec[k]), float(osc[k].imag / (2 * math.pi)))
    return kern.stability


def _linear_operator(kern: Kernel) -> np.ndarray:
    """L (2n × 2n) of the reduced train linearised at its static state (bearings by their coefficients
    there, asymmetry at its mean)."""
    red = kern.red
    asm = red.assembly
    w = kern.speed_rad_s
    eta = asm.train.internal_damping_s
    K = red.mean_stiffness(w, eta)
    C = red.damping(w, eta)
    journal = kern.journal_m if kern.journal_m is not None else np.zeros((len(asm.bearings), 2))
    for b, j in enumerate(red.support_index):
        kb, cb = bearing_coefficients(asm.bearings[b], float(journal[b, 0]), float(journal[b, 1]), w)
        K[j: j + 2, j: j + 2] += kb
        C[j: j + 2, j: j + 2] += cb
    n = red.n
    Minv = np.linalg.inv(red.M)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])


def _phi(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """e^A, φ1(A), φ2(A), φ3(A) from one exponential of the augmented block matrix (Saad 1992)."""
    m = A.shape[0]
    Z = np.zeros((4 * m, 4 * m))
    Z[:m, :m] = A
    for k in range(3):
        Z[k * m:(k + 1) * m, (k + 1) * m:(k + 2) * m] = np.eye(m)
    X = sla.expm(Z)
    return X[:m, :m], X[:m, m:2 * m], X[:m, 2 * m:3 * m], X[:m, 3 * m:]


def etd_matrices(kern: Kernel, h: float) -> tuple:
    """The ETDRK4 matrices of step ``h`` (cached on the kernel)."""
    key = round(h * 1e15)
    if key not in kern.etd:
        L = _linear_operator(kern)
        n = kern.red.n
        E, p1, p2, p3 = _phi(h * L)
        E2, q1, _, _ = _phi(0.5 * h * L)
        kern.etd[key] = (np.ascontiguousarray(L[n:]), E, E2, np.ascontiguousarray(0.5 * h * q1[:, n:]),
                         np.ascontiguousarray(h * (p1 - 3 * p2 + 4 * p3)[:, n:]),
                         np.ascontiguousarray(h * (p2 - 2 * p3)[:, n:]),
                         np.ascontiguousarray(h * (-p2 + 4 * p3)[:, n:]))
    return kern.etd[key]


def build_kernel(train: Train | Assembly | Reduced, speed_rpm: float, n_modes: int = 12) -> Kernel:
    """Precompute the reduced system's M⁻¹-products and the bearing kernels at ``speed_rpm``."""
    if isinstance(train, Reduced):
        red = train
    else:
        asm = train if isinstance(train, Assembly) else assemble(train)
        red = reduce(asm, n_modes)
    asm = red.assembly
    w = speed_rpm * math.pi / 30.0
    eta = asm.train.internal_damping_s
    Minv = np.linalg.inv(red.M)
    AK = Minv @ red.mean_stiffness(w, eta)
    AKc = Minv @ red.K_cos
    AKs = Minv @ red.K_sin
    AC = Minv @ red.damping(w, eta)
    f0 = Minv @ red.gravity_n
    n_u = len(asm.unbalance_nodes)
    U = np.zeros((max(n_u, 0), 2, red.n))
    for k, node in enumerate(asm.unbalance_nodes):
        U[k, 0] = Minv @ red.T[4 * node]
        U[k, 1] = Minv @ red.T[4 * node + 1]
    ub = np.stack([asm.unbalance_kg_m, asm.unbalance_angle_rad], axis=1) if n_u else np.zeros((0, 2))
    codes, params, offs = [], [], [0]
    for brg in asm.bearings:
        if not hasattr(brg, "kernel"):
            raise TrainError(f"bearing {brg!r} has no compiled kernel: use one of rotordiag.simulator.bearings")
        c, p = brg.kernel()
        codes.append(int(c))
        params.append(np.asarray(p, dtype=float))
        offs.append(offs[-1] + len(p))
    pall = np.concatenate(params) if params else np.zeros(0)
    cpl = red.coupling_index.reshape(-1, 2) if len(red.coupling_index) else np.zeros((0, 2), dtype=np.int64)
    cplp = np.array([[f[2], f[3], f[4], f[5], f[6]] for f in asm.flexible], dtype=float).reshape(-1, 5)
    args = (red.n, np.ascontiguousarray(AK), np.ascontiguousarray(AKc), np.ascontiguousarray(AKs),
            np.ascontiguousarray(AC), np.ascontiguousarray(Minv), f0, U, ub, w,
            red.support_index.astype(np.int64), np.ascontiguousarray(asm.support_centres_m),
            np.array(codes, dtype=np.int64), np.array(offs, dtype=np.int64), pall, cpl.astype(np.int64), cplp)
    clear = np.array([float(b.clearance_m) for b in asm.bearings])
    return Kernel(red=red, speed_rad_s=w, args=args, clear=clear)


def initial_state(kernel: Kernel, speed_rpm: float) -> np.ndarray:
    """Reduced state at the train's static state (zero velocities): boundary DOFs taken from the full
    Newton solution, modal coordinates by least squares."""
    red = kernel.red
    q = _ensure_static(kernel, speed_rpm)
    p, *_ = np.linalg.lstsq(red.T, q, rcond=None)
    return np.concatenate([p, np.zeros(red.n)])


def _ensure_static(kernel: Kernel, speed_rpm: float) -> np.ndarray:
    """The full model's static displacements (solved once per kernel)."""
    if kernel.static_q is None:
        st = static_state(kernel.red.assembly, speed_rpm)
        kernel.static_q = st.q
        kernel.journal_m = st.journal_m
    return kernel.static_q


def simulate_train(train: Train | Assembly | Reduced | Kernel, speed_rpm: float, *, transient_revs: int = 320,
                   record_revs: int = 128, samples_per_rev: int = 128, n_modes: int = 12,
                   rtol: float = DEFAULT_RTOL, atol_m: float = 1e-10,
                   initial: np.ndarray | None = None, record_state: bool = False, method: str = "etd",
                   steps_per_sample: int = 1) -> TrainRun:
    """Steady response of the train at ``speed_rpm``: ``transient_revs`` revolutions discarded, then
    ``record_revs`` recorded at ``samples_per_rev``. Starts from the static state unless ``initial`` is
    given. ``atol_m`` is the absolute tolerance on every reduced coordinate and velocity; ``record_state``
    keeps the reduced states at the samples (``TrainRun.node_m`` reads any node from them).

    ``method``: ``"etd"`` (default) integrates with fixed-step exponential Runge–Kutta (ETDRK4, the stiff
    linearised film and shaft taken exactly, ``steps_per_sample`` steps between samples) where the static
    state is linearly stable, and with ``"dopri"`` — adaptive Dormand–Prince 5(4) at ``rtol``/``atol_m`` —
    where it is not (in whip the orbit leaves the static neighbourhood: the fixed step's error grows and the
    film's stiffness there is far from the frozen linearisation's); ``"etd"`` falls back to ``"dopri"`` if it
    diverges. ``"etd_adaptive"`` (on request) is ETDRK4 with step-doubling error control over each sample
    interval at ``rtol``/``atol_m`` (1 to 4096 steps per sample); it meets the tolerance near the static
    state and hands over to ``"dopri"`` (said in ``message``) when it cannot. The oil-film damping on the light journal DOFs makes the explicit method take several
    hundred steps per revolution for stability alone (eigenvalues of −2·10⁴…−10⁵ s⁻¹). A speed beyond the
    linear stability threshold (least log decrement ≤ 0) is said in ``TrainRun.message``."""
    t0 = time.perf_counter()
    if not (np.isfinite(speed_rpm) and speed_rpm > 0):
        raise TrainError(f"speed_rpm must be positive (got {speed_rpm!r})")
    if transient_revs < 0 or record_revs < 1 or samples_per_rev < 4:
        raise TrainError("transient_revs ≥ 0, record_revs ≥ 1 and samples_per_rev ≥ 4 are needed")
    kern = train if isinstance(train, Kernel) else build_kernel(train, speed_rpm, n_modes)
    if abs(kern.speed_rad_s - speed_rpm * math.pi / 30.0) > 1e-9 * kern.speed_rad_s:
        raise TrainError("the kernel was built for another speed")
    s0 = initial_state(kern, speed_rpm) if initial is None else np.asarray(initial, dtype=float)
    w = kern.speed_rad_s
    T_rev = 2 * math.pi / w
    t_end = (transient_revs + record_revs) * T_rev
    n_samples = record_revs * samples_per_rev
    grid = np.full((n_samples, s0.shape[0]), np.nan)
    if method not in ("etd", "etd_adaptive", "dopri"):
        raise TrainError(f"method must be 'etd', 'etd_adaptive' or 'dopri' (got {method!r})")
    if steps_per_sample < 1:
        raise TrainError("steps_per_sample must be ≥ 1")
    if not (np.isfinite(rtol) and 0 < rtol < 1 and np.isfinite(atol_m) and atol_m > 0):
        raise TrainError(f"rtol must be in (0, 1) and atol_m positive (got {rtol!r}, {atol_m!r})")
    logdec, f_mode = linear_stability(kern, speed_rpm)
    message = ""
    if logdec <= 0:
        message = (f"{speed_rpm:.0f} r/min is beyond the linear stability threshold: the least-damped mode "
                   f"({f_mode:.1f} Hz) has log decrement {logdec:.3f} ≤ 0 about the static state, so a "
                   "whirl/whip grows from it; the response is a self-excited orbit, not the forced one")
        if method == "etd":  # the frozen linearisation no longer holds: explicit error-controlled steps
            method = "dopri"
    status = 2
    max_sps = 0  # the most steps per sample interval the ETD integrators took (0: Dormand–Prince)
    if method == "etd_adaptive":
        dt = T_rev / samples_per_rev
        levels = [etd_matrices(kern, dt / 2 ** lv) for lv in range(_ADAPTIVE_LEVELS)]
        Lb = levels[0][0]
        Es, E2s, P1hs, F1s, F2s, F3s = (np.stack([lv[k] for lv in levels]) for k in range(1, 7))
        nr = kern.red.n
        scale = np.concatenate([np.full(nr, atol_m / rtol), np.full(nr, atol_m * w / rtol)])
        level0 = max(0, min(_ADAPTIVE_LEVELS - 2, int(round(math.log2(steps_per_sample)))))
        status, s, nacc, lmax = _integrate_etd_adaptive(
            s0.copy(), dt, (transient_revs + record_revs) * samples_per_rev, transient_revs * samples_per_rev,
            grid, level0, nr, Lb, Es, E2s, P1hs, F1s, F2s, F3s, rtol, scale, kern.args[1:], kern.args[10],
            kern.args[11], kern.clear, kern.args[12])
        nrej, nfev, max_sps = 0, 4 * int(nacc), 2 ** int(lmax)
        if status == 3:
            message = (message + "; " if message else "") + (
                f"the time step's error control did not meet rtol={rtol:g} at {2 ** (_ADAPTIVE_LEVELS - 1)} "
                "steps per sample: retried with Dormand–Prince")
            status = 2
        if status == 2:
            grid[:] = np.nan
    if method == "etd":
        _ensure_static(kern, speed_rpm)
        h = T_rev / (samples_per_rev * steps_per_sample)
        Lb, E, E2, P1h, F1, F2, F3 = etd_matrices(kern, h)
        n_steps = (transient_revs + record_revs) * samples_per_rev * steps_per_sample
        grid_first = transient_revs * samples_per_rev * steps_per_sample
        status, s, nacc = _integrate_etd(s0.copy(), h, n_steps, steps_per_sample, grid_first, grid, kern.red.n, Lb,
                                         E, E2, P1h, F1, F2, F3, kern.args[1:], kern.args[10], kern.args[11],
                                         kern.clear, kern.args[12])
        nrej, nfev, max_sps = 0, 4 * int(nacc), steps_per_sample
        if status == 2:
            grid[:] = np.nan
    if status == 2:
        method = "dopri"
        max_sps = 0
        status, _, s, nacc, nrej, nfev, _ = _integrate(
            s0.copy(), t_end, T_rev / 200, rtol, atol_m, T_rev / samples_per_rev, transient_revs * T_rev, grid,
            MAX_STEPS_PER_REV * (transient_revs + record_revs), *kern.args, kern.clear, _A, _C, _E, _D)
    red = kern.red
    asm = red.assembly
    journal = np.stack([grid[:, j: j + 2] for j in red.support_index], axis=1) - asm.support_centres_m[None]
    times = transient_revs * T_rev + np.arange(n_samples) * T_rev / samples_per_rev
    kp = (transient_revs + np.arange(record_revs)) * T_rev
    names = [s_.name or f"B{k + 1}" for k, (_, s_) in enumerate(asm.train.supports())]
    return TrainRun(time_s=times, journal_m=journal, keyphasor_s=kp, status=STATUS[status], speed_rpm=float(speed_rpm),
                    clearance_m=kern.clear, bearing_names=names, final_state=s, n_accepted=int(nacc),
                    n_rejected=int(nrej), nfev=int(nfev), wall_time_s=time.perf_counter() - t0,
                    inputs={"speed_rpm": float(speed_rpm), "transient_revs": transient_revs,
                            "record_revs": record_revs, "samples_per_rev": samples_per_rev, "n_modes": n_modes,
                            "rtol": rtol, "atol_m": atol_m, "method": method,
                            "steps_per_sample": steps_per_sample, "max_steps_per_sample": max_sps},
                    states=grid if record_state else None, basis=red.T if record_state else None,
                    log_decrement=logdec, message=message)
