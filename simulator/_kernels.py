"""Compiled kernels: equations of motion (MODEL.md sections 2–4) and a
Dormand–Prince 5(4) integrator with dense output (MODEL.md section 5).

Everything here is non-dimensional: positions X = x/c, time τ = Ωt, primes
d/dτ. Forces are carried as F/(cΩ²) (units of mass), so an acceleration is
``force / mass``. The parameter vector layout is given by the ``P_*``
indices below and is packed by :func:`simulator.system.pack_parameters`.

State vector (22 entries, every mechanism)::

    q = [X1, Y1, X2, Y2, X4, Y4, X5, Y5, X6, Y6, φ]   y = [q, q']

Node 3 is not a coordinate: it follows from node 4 and the coupling
(``pin``: r3 = r4 + Δ e_r(φ); ``rigid``: φ = τ + φ0; ``aligned`` and
``offset``: r3 = r4). For ``rigid`` φ is still integrated (φ' = 1) so the
state has one layout; for ``aligned`` and ``offset`` φ stays constant.
``offset`` differs from ``aligned`` only in the packed bearing centres (the
exciter's are displaced by Δ in direction φ0: a stationary shaft-line offset).

``flexible`` (26 entries) keeps the stationary offset of ``offset`` but joins
nodes 3 and 4 by a flexible coupling of radial stiffness k_c and damping c_c,
with the kinematic 2X excitation of a double-engagement flexible coupling:
the relative hub displacement the coupling "wants" is u(τ) = (Δ/2)·[cos(2τ+ψ) e_δ
+ sin(2τ+ψ) e_⊥] (e_δ the offset direction), so the coupling force on node 3 is
F3 = k_c (r4 − r3 − u(τ)) + c_c (r4' − r3') and F4 = −F3 (docs/model.md).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rotordiag.core.numerics import NUMBA_OPTIONS

# ----------------------------------------------------------------- parameter layout
P_M1, P_MD1, P_M3, P_M4, P_MD2, P_M6 = 0, 1, 2, 3, 4, 5  # m1, M1, m3, m4, M2, m6 (kg)
P_KBAR = 6      # k̄ / Ω²  (kg)
P_RHO = 7       # ρ
P_BETA0 = 8     # β0 (rad)
P_C1 = 9        # c1 / Ω  (kg)
P_K2 = 10       # k2 / Ω² (kg)
P_C2 = 11       # c2 / Ω  (kg)
P_G = 12        # g / (c Ω²)
P_SB = 13       # 13..16: s_b / (c Ω²) for bearings 1..4 (kg)
P_OFF = 17      # 17..24: bearing-centre offsets (X, Y) / c for bearings 1..4
P_A1 = 25       # A = a / c (generator unbalance)
P_TH1 = 26      # generator unbalance phase (rad)
P_A2 = 27       # exciter unbalance a2 / c
P_TH2 = 28      # exciter unbalance phase θ2 (rad)
P_DELTA = 29    # Δ = δ / c
P_PHI0 = 30     # φ0 for `rigid` (rad)
P_KLIN = 31     # linear bearing stiffness / Ω² (kg)
P_CLIN = 32     # linear bearing damping / Ω (kg)
P_MECH = 33     # 0 aligned, 1 pin, 2 rigid
P_BMODEL = 34   # 0 short (Capone), 1 linear springs
P_KC = 35       # flexible coupling radial stiffness k_c / Ω² (kg)
P_CC = 36       # flexible coupling radial damping c_c / Ω (kg)
P_PSI = 37      # ψ, phase of the flexible coupling's 2X excitation (rad)
N_PARAMS = 38

MECH_ALIGNED, MECH_PIN, MECH_RIGID, MECH_OFFSET, MECH_FLEXIBLE = 0, 1, 2, 3, 4
BEARING_SHORT, BEARING_LINEAR = 0, 1
N_STATE = 22
#: ``flexible`` adds node 3 as a coordinate: y = [22 entries as above, X3, Y3, X3', Y3'].
N_STATE_FLEXIBLE = 26
N_Q = 11

STATUS_OK, STATUS_CONTACT, STATUS_DIVERGED = 0, 1, 2
#: :func:`integrate` stopped because the motion became stiff (internal: the caller goes on
#: with a stiff solver, :mod:`rotordiag.simulator._stiff`; never a run's status).
STATUS_STIFF = 3
#: Dormand–Prince stiffness test (Hairer, Nørsett & Wanner, *Solving ODEs I*, §IV.2 and DOPRI5):
#: h·|λ| estimated from the last two stages above this bound on this many accepted steps.
STIFF_HLAMBDA = 3.25
STIFF_COUNT = 15
#: Eccentricity at which an accepted step ends the run with status "contact".
CONTACT_ECCENTRICITY = 0.999
#: Any non-dimensional coordinate beyond this (in clearances) counts as divergence.
DIVERGENCE_LIMIT = 1.0e4


# ----------------------------------------------------------------- oil film
@njit(**NUMBA_OPTIONS)
def capone_force_ab(X, Y, a, b):
    """Capone short-bearing force for the squeeze–wedge vector (a, b) = (X − 2Y', Y + 2X').

    The film's right-hand side Ω∂h/∂θ + 2∂h/∂t is c·(a sinθ − b cosθ) with a = ΩX − 2Ẏ,
    b = ΩY + 2Ẋ, so the force depends on (X, Y) and on (a, b) alone and is positively
    homogeneous of degree 1 in (a, b). With Ω = 1 this is :func:`capone_force`; the
    dimensional bearings (:mod:`rotordiag.simulator.bearings`) pass a, b in rad/s, which also
    covers Ω ≤ 0 (reverse rotation, pure squeeze).
    """
    h = 1.0 - X * X - Y * Y
    if h <= 0.0:
        return math.nan, math.nan
    n = math.sqrt(a * a + b * b)
    if n == 0.0:
        return 0.0, 0.0
    ca = -a / n
    sa = -b / n
    sq = math.sqrt(h)
    u = Y * ca - X * sa
    G = 2.0 / sq * (0.5 * math.pi + math.atan(u / sq))
    V = (2.0 + u * G) / h
    w = X * ca + Y * sa
    S = w / (1.0 - w * w)
    coef = -n / h
    fx = coef * (3.0 * X * V - sa * G - 2.0 * ca * S)
    fy = coef * (3.0 * Y * V + ca * G - 2.0 * sa * S)
    return fx, fy


@njit(**NUMBA_OPTIONS)
def capone_force(X, Y, Xd, Yd):
    """Capone short-bearing force f = (fx, fy) at journal position (X, Y)
    and velocity (X', Y') (non-dimensional; MODEL.md section 4).

    Returns NaN outside the bearing (X² + Y² ≥ 1), so a trial Runge–Kutta
    stage that leaves the domain gets a non-finite error and is rejected.
    """
    return capone_force_ab(X, Y, X - 2.0 * Yd, Y + 2.0 * Xd)


@njit(**NUMBA_OPTIONS)
def bearing_force(p, b, X, Y, Xd, Yd):
    """Scaled force F/(cΩ²) of bearing ``b`` (0..3) on its journal."""
    Xr = X - p[P_OFF + 2 * b]
    Yr = Y - p[P_OFF + 2 * b + 1]
    if p[P_BMODEL] == BEARING_LINEAR:
        return (-p[P_KLIN] * Xr - p[P_CLIN] * Xd, -p[P_KLIN] * Yr - p[P_CLIN] * Yd)
    fx, fy = capone_force(Xr, Yr, Xd, Yd)
    s = p[P_SB + b]
    return s * fx, s * fy


# ----------------------------------------------------------------- equations of motion
@njit(**NUMBA_OPTIONS)
def node3(tau, y, p):
    """Position and velocity of node 3 (X3, Y3, X3', Y3') from the coupling."""
    mech = p[P_MECH]
    if mech == MECH_FLEXIBLE:
        return y[22], y[23], y[24], y[25]
    X4, Y4, V4x, V4y = y[4], y[5], y[15], y[16]
    if mech == MECH_ALIGNED or mech == MECH_OFFSET:
        return X4, Y4, V4x, V4y
    d = p[P_DELTA]
    if mech == MECH_PIN:
        phi = y[10]
        phid = y[21]
    else:
        phi = tau + p[P_PHI0]
        phid = 1.0
    c = math.cos(phi)
    s = math.sin(phi)
    return X4 + d * c, Y4 + d * s, V4x - d * phid * s, V4y + d * phid * c


@njit(**NUMBA_OPTIONS)
def coupling_excitation(tau, p):
    """u(τ) and u'(τ): the 2X relative hub displacement of the ``flexible`` coupling
    (radius Δ/2, phase ψ, turning at 2Ω in the frame of the offset direction φ0)."""
    h = 0.5 * p[P_DELTA]
    a = 2.0 * tau + p[P_PSI]
    ca, sa = math.cos(a), math.sin(a)
    ce, se = math.cos(p[P_PHI0]), math.sin(p[P_PHI0])
    # e_δ = (ce, se), e_⊥ = (−se, ce)
    ux = h * (ca * ce - sa * se)
    uy = h * (ca * se + sa * ce)
    return ux, uy, -2.0 * uy, 2.0 * ux


@njit(**NUMBA_OPTIONS)
def coupling_force(tau, y, p):
    """Scaled force of the ``flexible`` coupling on node 3 (the reaction −F acts on node 4):
    F3 = k_c (r4 − r3 − u(τ)) + c_c (r4' − r3' − u'(τ))."""
    ux, uy, udx, udy = coupling_excitation(tau, p)
    kc = p[P_KC]
    cc = p[P_CC]
    fx = kc * (y[4] - y[22] - ux) + cc * (y[15] - y[24] - udx)
    fy = kc * (y[5] - y[23] - uy) + cc * (y[16] - y[25] - udy)
    return fx, fy


@njit(**NUMBA_OPTIONS)
def rhs(tau, y, p, dy):
    """Right-hand side y' = f(τ, y) of the 22-entry non-dimensional state."""
    m1, M1, m3, m4, M2, m6 = p[P_M1], p[P_MD1], p[P_M3], p[P_M4], p[P_MD2], p[P_M6]
    g = p[P_G]
    X1, Y1, X2, Y2 = y[0], y[1], y[2], y[3]
    X4, Y4, X5, Y5, X6, Y6 = y[4], y[5], y[6], y[7], y[8], y[9]
    V1x, V1y, V2x, V2y = y[11], y[12], y[13], y[14]
    V4x, V4y, V5x, V5y, V6x, V6y = y[15], y[16], y[17], y[18], y[19], y[20]
    X3, Y3, V3x, V3y = node3(tau, y, p)

    # Generator shaft: K1(θ) = k̄ [[1 + ρ cos2θ, ρ sin2θ], [ρ sin2θ, 1 − ρ cos2θ]]
    th2 = 2.0 * (tau + p[P_BETA0])
    kb = p[P_KBAR]
    rc = p[P_RHO] * math.cos(th2)
    rs = p[P_RHO] * math.sin(th2)
    k11 = kb * (1.0 + rc)
    k12 = kb * rs
    k22 = kb * (1.0 - rc)
    d21x, d21y = X2 - X1, Y2 - Y1
    d23x, d23y = X2 - X3, Y2 - Y3
    s21x, s21y = k11 * d21x + k12 * d21y, k12 * d21x + k22 * d21y
    s23x, s23y = k11 * d23x + k12 * d23y, k12 * d23x + k22 * d23y

    # Exciter shaft (isotropic)
    k2 = p[P_K2]
    e54x, e54y = X5 - X4, Y5 - Y4
    e56x, e56y = X5 - X6, Y5 - Y6

    b1x, b1y = bearing_force(p, 0, X1, Y1, V1x, V1y)
    b2x, b2y = bearing_force(p, 1, X3, Y3, V3x, V3y)
    b3x, b3y = bearing_force(p, 2, X4, Y4, V4x, V4y)
    b4x, b4y = bearing_force(p, 3, X6, Y6, V6x, V6y)

    ang1 = tau + p[P_TH1]
    ang2 = tau + p[P_TH2]
    F1x = s21x + b1x
    F1y = s21y + b1y - m1 * g
    F2x = -s21x - s23x - p[P_C1] * V2x + M1 * p[P_A1] * math.cos(ang1)
    F2y = -s21y - s23y - p[P_C1] * V2y + M1 * p[P_A1] * math.sin(ang1) - M1 * g
    F3x = s23x + b2x
    F3y = s23y + b2y - m3 * g
    F4x = k2 * e54x + b3x
    F4y = k2 * e54y + b3y - m4 * g
    F5x = -k2 * (e54x + e56x) - p[P_C2] * V5x + M2 * p[P_A2] * math.cos(ang2)
    F5y = -k2 * (e54y + e56y) - p[P_C2] * V5y + M2 * p[P_A2] * math.sin(ang2) - M2 * g
    F6x = k2 * e56x + b4x
    F6y = k2 * e56y + b4y - m6 * g

    mech = p[P_MECH]
    if mech == MECH_FLEXIBLE:
        fcx, fcy = coupling_force(tau, y, p)
        F3x += fcx
        F3y += fcy
        F4x -= fcx
        F4y -= fcy

    for i in range(N_Q):
        dy[i] = y[N_Q + i]
    dy[11] = F1x / m1
    dy[12] = F1y / m1
    dy[13] = F2x / M1
    dy[14] = F2y / M1
    dy[17] = F5x / M2
    dy[18] = F5y / M2
    dy[19] = F6x / m6
    dy[20] = F6y / m6

    m34 = m3 + m4
    if mech == MECH_FLEXIBLE:
        dy[15] = F4x / m4
        dy[16] = F4y / m4
        dy[21] = 0.0
        dy[22] = y[24]
        dy[23] = y[25]
        dy[24] = F3x / m3
        dy[25] = F3y / m3
    elif mech == MECH_PIN:
        d = p[P_DELTA]
        phi = y[10]
        phid = y[21]
        c = math.cos(phi)
        s = math.sin(phi)
        # φ'' = e_t · (P3/m3 − P4/m4) / Δ,  e_t = (−sin φ, cos φ)
        phidd = (-s * (F3x / m3 - F4x / m4) + c * (F3y / m3 - F4y / m4)) / d
        # (m3 + m4) r4'' = P3 + P4 − m3 Δ (φ'' e_t − φ'² e_r)
        dy[15] = (F3x + F4x - m3 * d * (-phidd * s - phid * phid * c)) / m34
        dy[16] = (F3y + F4y - m3 * d * (phidd * c - phid * phid * s)) / m34
        dy[21] = phidd
    elif mech == MECH_RIGID:
        d = p[P_DELTA]
        phi = tau + p[P_PHI0]
        dy[15] = (F3x + F4x + m3 * d * math.cos(phi)) / m34
        dy[16] = (F3y + F4y + m3 * d * math.sin(phi)) / m34
        dy[21] = 0.0
    else:
        dy[15] = (F3x + F4x) / m34
        dy[16] = (F3y + F4y) / m34
        dy[21] = 0.0


@njit(**NUMBA_OPTIONS)
def bearing_forces(tau, y, p):
    """Scaled forces F/(cΩ²) of bearings 1..4 on their journals, shape (4, 2)."""
    X3, Y3, V3x, V3y = node3(tau, y, p)
    out = np.empty((4, 2))
    out[0, 0], out[0, 1] = bearing_force(p, 0, y[0], y[1], y[11], y[12])
    out[1, 0], out[1, 1] = bearing_force(p, 1, X3, Y3, V3x, V3y)
    out[2, 0], out[2, 1] = bearing_force(p, 2, y[4], y[5], y[15], y[16])
    out[3, 0], out[3, 1] = bearing_force(p, 3, y[8], y[9], y[19], y[20])
    return out


@njit(**NUMBA_OPTIONS)
def bearing_forces_many(taus, ys, p):
    """:func:`bearing_forces` at many samples: shape (n, 4, 2)."""
    n = ys.shape[0]
    out = np.empty((n, 4, 2))
    for i in range(n):
        out[i] = bearing_forces(taus[i], ys[i], p)
    return out


@njit(**NUMBA_OPTIONS)
def max_eccentricity(tau, y, p):
    """Largest journal eccentricity ε = |r_b − r_b,centre| / c over the four bearings."""
    X3, Y3, _, _ = node3(tau, y, p)
    xs = (y[0], X3, y[4], y[8])
    ys = (y[1], Y3, y[5], y[9])
    emax = 0.0
    for b in range(4):
        ex = xs[b] - p[P_OFF + 2 * b]
        ey = ys[b] - p[P_OFF + 2 * b + 1]
        e = math.sqrt(ex * ex + ey * ey)
        if e > emax:
            emax = e
    return emax


# ----------------------------------------------------------------- Dormand–Prince 5(4)
# Coefficients of Dormand & Prince (1980) with Shampine's (1986) quartic dense output,
# the same tableau as scipy.integrate.RK45.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
_P = np.array([
    [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])

_SAFETY = 0.9
_MIN_FACTOR = 0.2
_MAX_FACTOR = 10.0


@njit(**NUMBA_OPTIONS)
def _dense(y_old, K, h, theta, out_row):
    """Dense-output value at τ_old + θh into ``out_row`` (quartic interpolant)."""
    n = y_old.shape[0]
    t1 = theta
    t2 = t1 * theta
    t3 = t2 * theta
    t4 = t3 * theta
    for i in range(n):
        acc = 0.0
        for j in range(7):
            kij = K[j, i]
            if kij != 0.0:
                acc += kij * (_P[j, 0] * t1 + _P[j, 1] * t2 + _P[j, 2] * t3 + _P[j, 3] * t4)
        out_row[i] = y_old[i] + h * acc


@njit(**NUMBA_OPTIONS)
def dp_trial_step(tau, h, y, p, K, Ys, y_new, rtol, atol):
    """One Dormand–Prince 5(4) trial step from ``(tau, y)``, with ``K[0] = f(tau, y)`` (FSAL).

    Fills the stage derivatives ``K[1..6]``, the stage states ``Ys[0..5]`` (``Ys[0] = y``) and
    the 5th-order solution ``y_new``; returns the RMS norm of the embedded error estimate,
    scaled by ``atol + rtol·max(|y|, |y_new|)`` (< 1: accept). Shared by :func:`integrate` and
    the variational integrator of :mod:`rotordiag.simulator.steady` (6 calls of ``rhs``).
    """
    n = y.shape[0]
    for i in range(n):
        Ys[0, i] = y[i]
    for s in range(1, 6):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += _A[s, j] * K[j, i]
            Ys[s, i] = y[i] + h * acc
        rhs(tau + _C[s] * h, Ys[s], p, K[s])
    for i in range(n):
        acc = 0.0
        for j in range(6):
            acc += _B[j] * K[j, i]
        y_new[i] = y[i] + h * acc
    rhs(tau + h, y_new, p, K[6])
    err2 = 0.0
    for i in range(n):
        e = 0.0
        for j in range(7):
            e += _E[j] * K[j, i]
        e *= h
        sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        err2 += (e / sc) ** 2
    return math.sqrt(err2 / n)


@njit(**NUMBA_OPTIONS)
def accepted_state_status(tau, y, p):
    """``(status, emax)`` after an accepted step: contact when a journal reached
    ``CONTACT_ECCENTRICITY``, diverged when the state is non-finite or beyond ``DIVERGENCE_LIMIT``."""
    emax = max_eccentricity(tau, y, p)
    if emax >= CONTACT_ECCENTRICITY:
        return STATUS_CONTACT, emax
    for i in range(y.shape[0]):
        if not math.isfinite(y[i]) or abs(y[i]) > DIVERGENCE_LIMIT:
            return STATUS_DIVERGED, emax
    return STATUS_OK, emax


@njit(**NUMBA_OPTIONS)
def dp_step_factor(err, step_rejected):
    """Growth factor of the next step after an accepted step with error norm ``err``."""
    if err == 0.0:
        factor = _MAX_FACTOR
    else:
        factor = min(_MAX_FACTOR, _SAFETY * err ** -0.2)
    if step_rejected:
        factor = min(1.0, factor)
    return factor


@njit(**NUMBA_OPTIONS)
def integrate(y0, tau0, p, rtol, atol, h0, grid_t0, grid_dt, grid_out, pc_t0, pc_dt, pc_out,
              tau_end, max_steps, stiff_steps=0, stiff_window=2.0 * math.pi):
    """Integrate from ``tau0`` to ``tau_end`` with adaptive Dormand–Prince 5(4).

    Samples at τ_k = grid_t0 + k·grid_dt (k < len(grid_out)) and Poincaré
    points at τ_j = pc_t0 + j·pc_dt (j < len(pc_out)) are written by dense
    output into ``grid_out`` / ``pc_out`` (rows are full states).

    With ``stiff_steps`` > 0 the run stops early with ``STATUS_STIFF`` when it has become
    stiff: more than ``stiff_steps`` trial steps within one window of ``stiff_window`` (τ)
    **and** the stiffness test (h·|λ| > ``STIFF_HLAMBDA`` on ``STIFF_COUNT`` accepted steps
    without 6 non-stiff ones between them) — an explicit method then crawls along its
    stability limit (whirl near the bushing wall: film eigenvalues of −4e4 per radian).

    Returns
    -------
    status, tau, y, nfev, n_accepted, n_rejected, n_grid, n_pc, emax, h
        ``status``: 0 ok, 1 contact (an accepted state reached ε ≥ 0.999 or
        the step size collapsed near the bushing), 2 diverged (non-finite or
        unbounded state, step-size collapse, or ``max_steps`` exceeded), 3 stiff
        (``stiff_steps``; ``tau``/``y`` are the last accepted state).
    """
    n = y0.shape[0]
    y = y0.copy()
    y_new = np.empty(n)
    K = np.zeros((7, n))
    Ys = np.empty((6, n))
    tau = tau0
    rhs(tau, y, p, K[0])
    nfev = 1
    nacc = 0
    nrej = 0
    ng = 0
    npc = 0
    n_grid = grid_out.shape[0]
    n_pc = pc_out.shape[0]
    h = h0
    step_rejected = False
    status = STATUS_OK
    emax = max_eccentricity(tau, y, p)
    # Emit output points that sit exactly at the start.
    while ng < n_grid and grid_t0 + ng * grid_dt <= tau:
        for i in range(n):
            grid_out[ng, i] = y[i]
        ng += 1
    while npc < n_pc and pc_t0 + npc * pc_dt <= tau:
        for i in range(n):
            pc_out[npc, i] = y[i]
        npc += 1
    hmin_rel = 1e-13
    win_tau = tau
    win_steps = 0
    n_stiff = 0
    n_nonstiff = 0
    while tau < tau_end:
        if nacc + nrej >= max_steps:
            status = STATUS_DIVERGED
            break
        if stiff_steps > 0:
            if tau >= win_tau + stiff_window:
                win_tau = tau
                win_steps = 0
            win_steps += 1
            if win_steps > stiff_steps and n_stiff >= STIFF_COUNT:
                status = STATUS_STIFF
                break
        hmin = hmin_rel * max(1.0, abs(tau))
        if h < hmin:
            status = STATUS_CONTACT if emax > 0.99 else STATUS_DIVERGED
            break
        if h > tau_end - tau:
            h = tau_end - tau
            if h < hmin:  # floating-point remainder of the interval
                tau = tau_end
                break
        err = dp_trial_step(tau, h, y, p, K, Ys, y_new, rtol, atol)
        nfev += 6
        if not math.isfinite(err):
            h *= _MIN_FACTOR
            nrej += 1
            step_rejected = True
            continue
        if err < 1.0:
            factor = dp_step_factor(err, step_rejected)
            tau_new = tau + h
            # dense output for the samples inside (tau, tau_new]
            while ng < n_grid:
                tk = grid_t0 + ng * grid_dt
                if tk > tau_new:
                    break
                _dense(y, K, h, (tk - tau) / h, grid_out[ng])
                ng += 1
            while npc < n_pc:
                tk = pc_t0 + npc * pc_dt
                if tk > tau_new:
                    break
                _dense(y, K, h, (tk - tau) / h, pc_out[npc])
                npc += 1
            tau = tau_new
            for i in range(n):
                y[i] = y_new[i]
                K[0, i] = K[6, i]
            if stiff_steps > 0:  # DOPRI5's test: h·ρ ≈ h‖f(y_new) − f(Ys5)‖ / ‖y_new − Ys5‖ (c6 = 1)
                num = 0.0
                den = 0.0
                for i in range(n):
                    num += (K[6, i] - K[5, i]) ** 2
                    den += (y_new[i] - Ys[5, i]) ** 2
                if den > 0.0 and h * math.sqrt(num / den) > STIFF_HLAMBDA:
                    n_stiff += 1
                    n_nonstiff = 0
                else:
                    n_nonstiff += 1
                    if n_nonstiff >= 6:
                        n_stiff = 0
            nacc += 1
            step_rejected = False
            h *= factor
            status, emax = accepted_state_status(tau, y, p)
            if status != STATUS_OK:
                break
        else:
            h *= max(_MIN_FACTOR, _SAFETY * err ** -0.2)
            nrej += 1
            step_rejected = True
    return status, tau, y, nfev, nacc, nrej, ng, npc, emax, h


@njit(**NUMBA_OPTIONS)
def rhs_alloc(tau, y, p):
    """``rhs`` returning a new array (for Python callers: solve_ivp, Jacobians)."""
    dy = np.empty_like(y)
    rhs(tau, y, p, dy)
    return dy
