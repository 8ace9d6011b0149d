"""A configured rotor: plant + operating point + coupling, packed for the kernels.

:class:`RotorSystem` is the flow map other code builds on (``simulate``, the
Lyapunov exponent, sweeps with continuation): it owns the non-dimensional
parameter vector and advances states by whole revolutions.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL, MAX_STEPS_PER_REV

from . import _kernels as K
from .params import (
    MECHANISMS,
    MISALIGNMENT_RANGE,
    SPEED_RANGE_RPM,
    UNBALANCE_RANGE,
    Plant,
    check_range,
)

TWO_PI = 2.0 * math.pi
#: The explicit integrator hands a run to LSODA (:mod:`._stiff`) once a revolution needs more
#: trial steps than this while its stiffness test holds (a period-1 revolution takes 100–400
#: steps, a whirl away from the bushing wall 300–3000, one against it 10⁵–2·10⁵).
STIFF_STEPS_PER_REV = 6000
STATUS_NAMES = {K.STATUS_OK: "ok", K.STATUS_CONTACT: "contact", K.STATUS_DIVERGED: "diverged"}


def speed_rad_s(speed_rpm: float) -> float:
    """Ω = π·rpm/30."""
    return math.pi * speed_rpm / 30.0


def _finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return v


#: Kernel code of each mechanism name.
MECHANISM_CODES: dict[str, int] = {
    "aligned": K.MECH_ALIGNED, "pin": K.MECH_PIN, "rigid": K.MECH_RIGID,
    "offset": K.MECH_OFFSET, "flexible": K.MECH_FLEXIBLE,
}
MECHANISM_NAMES: dict[int, str] = {v: k for k, v in MECHANISM_CODES.items()}


def resolve_mechanism(mechanism: str, misalignment: float, angular_misalignment_mrad: float = 0.0) -> int:
    """Kernel code of the coupling mechanism; no offset at all (Δ = 0 and no angular offset) is
    always ``aligned``. An angular offset is a stationary shaft-line offset: ``offset`` or ``flexible`` only."""
    if mechanism not in MECHANISMS:
        raise ValueError(f"mechanism must be one of {MECHANISMS}, got {mechanism!r}")
    if mechanism == "aligned" and misalignment != 0.0:
        raise ValueError(f"mechanism 'aligned' needs misalignment = 0, got {misalignment!r}")
    if angular_misalignment_mrad != 0.0 and mechanism not in ("offset", "flexible"):
        raise ValueError("angular_misalignment_mrad is a stationary shaft-line offset: it needs mechanism "
                         f"'offset' or 'flexible', got {mechanism!r}")
    if (misalignment == 0.0 and angular_misalignment_mrad == 0.0) or mechanism == "aligned":
        return K.MECH_ALIGNED
    return MECHANISM_CODES[mechanism]


def mechanism_bearing_offsets(plant: Plant, misalignment: float, mechanism_code: int,
                              offset_angle_rad: float, angular_misalignment_mrad: float = 0.0) -> np.ndarray:
    """Bearing centres (m, shape (4, 2)) the kernels use: the plant's offsets, plus, for the
    stationary shaft-line mechanisms (``offset``, ``flexible``), the exciter shaft line moved in
    direction φ0: parallel by δ = Δ·c (both exciter bearings) and tilted about the coupling by
    α = ``angular_misalignment_mrad`` (bearing 3, at the coupling, by 0; bearing 4 by α·L with
    L = ``plant.exciter_bearing_span_m``)."""
    centres = np.asarray(plant.bearing_offset_m, dtype=float).copy()
    if mechanism_code in (K.MECH_OFFSET, K.MECH_FLEXIBLE):
        e = np.array([math.cos(offset_angle_rad), math.sin(offset_angle_rad)])
        d = misalignment * plant.clearance_m
        centres[2] += d * e
        centres[3] += (d + 1e-3 * angular_misalignment_mrad * plant.exciter_bearing_span_m) * e
    return centres


def check_angular_misalignment(plant: Plant, angular_misalignment_mrad: float) -> float:
    """Validate α (mrad): finite, and the far exciter bearing's displacement |α|·L at most 0.9 c
    (the bound Δ ≤ 0.9 puts on the parallel offset). Raises ValueError naming the parameter."""
    a = _finite("angular_misalignment_mrad", angular_misalignment_mrad)
    limit = 0.9 * plant.clearance_m / plant.exciter_bearing_span_m * 1e3
    if abs(a) > limit:
        raise ValueError(
            f"angular_misalignment_mrad must be within ±{limit:.4g} mrad for this plant (the far exciter bearing "
            f"moves by α·L, L = exciter_bearing_span_m = {plant.exciter_bearing_span_m:g} m, at most 0.9 of the "
            f"clearance {plant.clearance_m:g} m), got {angular_misalignment_mrad!r}")
    return a


def pack_parameters(
    plant: Plant,
    speed_rpm: float,
    misalignment: float,
    unbalance: float,
    *,
    mechanism: str = "pin",
    unbalance_phase_rad: float = 0.0,
    exciter_unbalance: float = 0.0,
    exciter_unbalance_phase_rad: float = 0.0,
    offset_angle_rad: float = 0.0,
    coupling_phase_rad: float = 0.0,
    angular_misalignment_mrad: float = 0.0,
) -> np.ndarray:
    """Validate inputs and pack the non-dimensional parameter vector of the kernels."""
    if not isinstance(plant, Plant):
        raise ValueError(f"plant must be a simulator.Plant, got {type(plant).__name__}")
    speed_rpm = check_range("speed_rpm", speed_rpm, *SPEED_RANGE_RPM)
    misalignment = check_range("misalignment", misalignment, *MISALIGNMENT_RANGE)
    unbalance = check_range("unbalance", unbalance, *UNBALANCE_RANGE)
    exciter_unbalance = check_range("exciter_unbalance", exciter_unbalance, *UNBALANCE_RANGE)
    unbalance_phase_rad = _finite("unbalance_phase_rad", unbalance_phase_rad)
    exciter_unbalance_phase_rad = _finite("exciter_unbalance_phase_rad", exciter_unbalance_phase_rad)
    offset_angle_rad = _finite("offset_angle_rad", offset_angle_rad)
    coupling_phase_rad = _finite("coupling_phase_rad", coupling_phase_rad)
    angular_misalignment_mrad = check_angular_misalignment(plant, angular_misalignment_mrad)
    mech = resolve_mechanism(mechanism, misalignment, angular_misalignment_mrad)

    w = speed_rad_s(speed_rpm)
    c = plant.clearance_m
    p = np.zeros(K.N_PARAMS)
    p[K.P_M1] = plant.journal1_mass_kg
    p[K.P_MD1] = plant.generator_mass_kg
    p[K.P_M3] = plant.journal3_mass_kg
    p[K.P_M4] = plant.journal4_mass_kg
    p[K.P_MD2] = plant.exciter_mass_kg
    p[K.P_M6] = plant.journal6_mass_kg
    p[K.P_KBAR] = plant.generator_stiffness_n_m / w**2
    p[K.P_RHO] = plant.asymmetry
    p[K.P_BETA0] = plant.stiff_axis_angle_rad
    p[K.P_C1] = plant.generator_damping_n_s_m / w
    p[K.P_K2] = plant.exciter_stiffness_n_m / w**2
    p[K.P_C2] = plant.exciter_damping_n_s_m / w
    p[K.P_G] = plant.gravity_m_s2 / (c * w**2)
    p[K.P_SB:K.P_SB + 4] = plant.bearing_force_scale_n(w) / (c * w**2)
    p[K.P_OFF:K.P_OFF + 8] = mechanism_bearing_offsets(plant, misalignment, mech, offset_angle_rad,
                                                        angular_misalignment_mrad).ravel() / c
    p[K.P_A1] = unbalance
    p[K.P_TH1] = unbalance_phase_rad
    p[K.P_A2] = exciter_unbalance
    p[K.P_TH2] = exciter_unbalance_phase_rad
    p[K.P_DELTA] = misalignment
    p[K.P_PHI0] = offset_angle_rad
    p[K.P_KLIN] = plant.linear_bearing_stiffness_n_m / w**2
    p[K.P_CLIN] = plant.linear_bearing_damping_n_s_m / w
    p[K.P_MECH] = mech
    p[K.P_BMODEL] = K.BEARING_LINEAR if plant.bearing_model == "linear" else K.BEARING_SHORT
    p[K.P_KC] = plant.coupling_stiffness_n_m / w**2
    p[K.P_CC] = plant.coupling_damping_n_s_m / w
    p[K.P_PSI] = coupling_phase_rad
    return p


@dataclass(frozen=True)
class AdvanceStats:
    """Integrator diagnostics of one call."""

    status: str
    tau: float
    nfev: int
    n_accepted: int
    n_rejected: int
    max_eccentricity: float
    #: τ where the run became stiff and went on with LSODA (:mod:`._stiff`); NaN if it never did.
    stiff_from_tau: float = math.nan


class RotorSystem:
    """The rotor at one operating point, as a flow map in τ = Ωt.

    The equations are 2π-periodic in τ, so advancing by whole revolutions
    from τ ≡ 0 (mod 2π) is the Poincaré (once-per-revolution) map.

    Parameters
    ----------
    plant : Plant
    speed_rpm : float
        Running speed Ω in r/min (100–6000).
    misalignment : float
        Δ = δ/c (0–0.9).
    unbalance : float
        Generator unbalance A = a/c (0–0.5).
    mechanism : {"pin", "rigid", "aligned", "offset", "flexible"}
        Coupling model (docs/model.md). Δ = 0 without an angular offset always uses ``aligned``.
    unbalance_phase_rad, exciter_unbalance, exciter_unbalance_phase_rad, offset_angle_rad : float
        Generator unbalance phase, exciter unbalance a2/c and its phase θ2,
        and the offset direction φ0: of the rotating eccentricity at t = 0
        (``rigid``) or of the stationary exciter shaft-line offset (``offset``,
        ``flexible``; 0 = +x horizontal, −π/2 = downward). All angles from +x toward +y.
    coupling_phase_rad : float
        ``flexible`` only: phase ψ of the coupling's 2X excitation.
    angular_misalignment_mrad : float
        ``offset``/``flexible`` only: tilt α of the exciter shaft line about the coupling, mrad,
        in direction φ0 (bearing 4's centre moves by α·``plant.exciter_bearing_span_m``).
    rtol, atol : float
        Integrator tolerances (atol on the non-dimensional state).
    """

    def __init__(
        self,
        plant: Plant,
        speed_rpm: float,
        misalignment: float,
        unbalance: float,
        *,
        mechanism: str = "pin",
        unbalance_phase_rad: float = 0.0,
        exciter_unbalance: float = 0.0,
        exciter_unbalance_phase_rad: float = 0.0,
        offset_angle_rad: float = 0.0,
        coupling_phase_rad: float = 0.0,
        angular_misalignment_mrad: float = 0.0,
        rtol: float = DEFAULT_RTOL,
        atol: float = DEFAULT_ATOL,
        stiff_solver: bool = True,
    ) -> None:
        self.params = pack_parameters(
            plant, speed_rpm, misalignment, unbalance, mechanism=mechanism,
            unbalance_phase_rad=unbalance_phase_rad, exciter_unbalance=exciter_unbalance,
            exciter_unbalance_phase_rad=exciter_unbalance_phase_rad, offset_angle_rad=offset_angle_rad,
            coupling_phase_rad=coupling_phase_rad, angular_misalignment_mrad=angular_misalignment_mrad,
        )
        rtol = _finite("rtol", rtol)
        atol = _finite("atol", atol)
        if not 1e-14 <= rtol <= 1e-2:
            raise ValueError(f"rtol must be in [1e-14, 1e-2], got {rtol!r}")
        if not 0 < atol <= 1e-2:
            raise ValueError(f"atol must be in (0, 1e-2], got {atol!r}")
        self.plant = plant
        self.speed_rpm = float(speed_rpm)
        self.speed_rad_s = speed_rad_s(self.speed_rpm)
        self.misalignment = float(misalignment)
        self.unbalance = float(unbalance)
        self.mechanism_code = int(self.params[K.P_MECH])
        self.mechanism = MECHANISM_NAMES[self.mechanism_code]
        #: Length of the state vector: 22, or 26 for ``flexible`` (node 3 is a coordinate).
        self.n_state = K.N_STATE_FLEXIBLE if self.mechanism_code == K.MECH_FLEXIBLE else K.N_STATE
        #: Bearing centres used by the kernels (m, shape (4, 2)): plant offsets + stationary shaft-line offset.
        self.angular_misalignment_mrad = float(angular_misalignment_mrad)
        self.bearing_centres_m = mechanism_bearing_offsets(plant, self.misalignment, self.mechanism_code,
                                                           float(offset_angle_rad), self.angular_misalignment_mrad)
        self.rtol = rtol
        self.atol = atol
        #: Trial steps per revolution above which a stiff run goes on with LSODA (0: never;
        #: :mod:`._stiff`); ``stiff_solver=False`` keeps the explicit integrator throughout.
        self.stiff_steps_per_rev = STIFF_STEPS_PER_REV if stiff_solver else 0
        self._h = TWO_PI / 200.0  # last step size, reused between calls

    # ---------------------------------------------------------------- states
    def initial_state(self) -> np.ndarray:
        """MODEL.md section 5's deterministic start (journals at X = 0.3, Y = −0.3)."""
        pl = self.plant
        c = pl.clearance_m
        g = pl.gravity_m_s2
        y = np.zeros(self.n_state)
        for j in (0, 4, 8):  # journals 1, 4, 6
            y[j], y[j + 1] = 0.3, -0.3
        y[2] = 0.3
        y[3] = -0.3 - pl.generator_mass_kg * g / (2.0 * pl.generator_stiffness_n_m * c)
        y[6] = 0.3
        y[7] = -0.3 - pl.exciter_mass_kg * g / (2.0 * pl.exciter_stiffness_n_m * c)
        if self.mechanism_code == K.MECH_PIN:
            y[10] = -0.5 * math.pi + 0.3
            d = self.params[K.P_DELTA]
            er = np.array([math.cos(y[10]), math.sin(y[10])])
            if np.hypot(*(y[4:6] + d * er)) >= 0.9:
                # Large Δ: MODEL.md's start would put journal 3 outside its bushing;
                # centre the coupling link on the start point instead (docs/model.md).
                y[4:6] = np.array([0.3, -0.3]) - 0.5 * d * er
        elif self.mechanism_code == K.MECH_RIGID:
            y[10] = self.params[K.P_PHI0]
            y[21] = 1.0
        if self.mechanism_code in (K.MECH_OFFSET, K.MECH_FLEXIBLE):
            # Exciter nodes start where the aligned start puts them relative to the displaced centres.
            moved = (self.bearing_centres_m - np.asarray(self.plant.bearing_offset_m)) / self.plant.clearance_m
            shift, shift_far = moved[2], moved[3]
            if self.mechanism_code == K.MECH_FLEXIBLE:
                y[22:24] = y[4:6]  # node 3 stays with its (undisplaced) generator bearing
            y[4:6] += shift
            y[6:8] += 0.5 * (shift + shift_far)  # exciter body half-way along the (tilted) line
            y[8:10] += shift_far
            if self.mechanism_code == K.MECH_OFFSET:
                # journals 3 and 4 are one point between two bearing centres δ apart: start half-way
                y[4:6] = np.array([0.0, -0.3]) + 0.5 * shift
        return y

    def check_state(self, state: np.ndarray) -> np.ndarray:
        """Validate a user-supplied state vector (shape (22,), finite).

        φ' (component 21) is set to 1 for ``rigid`` and 0 for the mechanisms without coupling
        dynamics; for ``pin`` it is a state variable and is kept (a run resumed from a
        ``final_state`` continues the same trajectory).
        """
        arr = np.asarray(state, dtype=float)
        if arr.shape != (self.n_state,):
            raise ValueError(f"initial_state must have shape ({self.n_state},) for mechanism "
                             f"{self.mechanism!r}, got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError("initial_state must be finite")
        arr = arr.copy()
        if self.mechanism_code == K.MECH_RIGID:
            arr[21] = 1.0  # φ' = 1 by construction; φ itself is re-derived from τ
        elif self.mechanism_code != K.MECH_PIN:  # pin: φ' is a dynamic variable and is kept
            arr[21] = 0.0
        return arr

    def rhs(self, tau: float, state: np.ndarray) -> np.ndarray:
        """Compiled right-hand side y' = f(τ, y) (a new array)."""
        return K.rhs_alloc(float(tau), np.ascontiguousarray(state, dtype=float), self.params)

    # ---------------------------------------------------------------- integration
    def integrate(
        self,
        state: np.ndarray,
        tau_start: float,
        tau_end: float,
        *,
        grid_t0: float = 0.0,
        grid_dt: float = 1.0,
        n_grid: int = 0,
        pc_t0: float = 0.0,
        n_poincare: int = 0,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, AdvanceStats, int, int]:
        """Integrate and sample; returns (final state, grid samples, Poincaré samples, stats, n_grid, n_pc)."""
        grid = np.full((n_grid, self.n_state), np.nan)
        pcs = np.full((n_poincare, self.n_state), np.nan)
        revs = max(1.0, (tau_end - tau_start) / TWO_PI)
        max_steps = int(MAX_STEPS_PER_REV * revs) + 1000
        status, tau, y, nfev, nacc, nrej, ng, npc, emax, h = K.integrate(
            np.ascontiguousarray(state, dtype=float), float(tau_start), self.params, self.rtol,
            self.atol, self._h, float(grid_t0), float(grid_dt), grid, float(pc_t0), TWO_PI, pcs,
            float(tau_end), max_steps, self.stiff_steps_per_rev, TWO_PI,
        )
        stiff_tau = math.nan
        if status == K.STATUS_STIFF:
            from ._stiff import continue_stiff  # here: _stiff needs steady, which needs this module

            stiff_tau = tau
            status, tau, y, nfev_s, n_s, ng, npc, emax = continue_stiff(
                self.params, y, tau, float(tau_end), self.rtol, self.atol, max_steps - nacc - nrej,
                float(grid_t0), float(grid_dt), grid, ng, float(pc_t0), TWO_PI, pcs, npc)
            nfev, nacc = nfev + nfev_s, nacc + n_s
        elif status == K.STATUS_OK and h > 0:
            self._h = min(h, TWO_PI / 20.0)
        stats = AdvanceStats(STATUS_NAMES[status], tau, nfev, nacc, nrej, emax, stiff_tau)
        return y, grid, pcs, stats, ng, npc

    def advance(self, state: np.ndarray, tau_start: float, n_revs: float) -> tuple[np.ndarray, str]:
        """Advance ``state`` from ``tau_start`` by ``n_revs`` revolutions.

        Returns
        -------
        state : ndarray, shape (22,)
        status : {"ok", "contact", "diverged"}
        """
        y, _, _, stats, _, _ = self.integrate(state, tau_start, tau_start + TWO_PI * n_revs)
        return y, stats.status

    # ---------------------------------------------------------------- conversions
    def node_positions(self, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        """Absolute positions of nodes 1..6 in metres, shape (n, 6, 2)."""
        c = self.plant.clearance_m
        states = np.atleast_2d(states)
        tau = np.broadcast_to(np.asarray(tau, dtype=float), (states.shape[0],))
        out = np.empty((states.shape[0], 6, 2))
        out[:, 0] = states[:, 0:2]
        out[:, 1] = states[:, 2:4]
        out[:, 3] = states[:, 4:6]
        out[:, 4] = states[:, 6:8]
        out[:, 5] = states[:, 8:10]
        d = self.misalignment
        if self.mechanism_code == K.MECH_PIN:
            phi = states[:, 10]
        elif self.mechanism_code == K.MECH_RIGID:
            phi = tau + self.params[K.P_PHI0]
        else:
            phi = np.zeros(states.shape[0])
            d = 0.0
        out[:, 2, 0] = states[:, 4] + d * np.cos(phi)
        out[:, 2, 1] = states[:, 5] + d * np.sin(phi)
        if self.mechanism_code == K.MECH_FLEXIBLE:
            out[:, 2] = states[:, 22:24]
        return out * c

    def bearing_forces_n(self, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        """Force of each bearing's oil film (or spring) on its journal, N, shape (n, 4, 2)."""
        states = np.atleast_2d(np.asarray(states, dtype=float))
        tau = np.broadcast_to(np.asarray(tau, dtype=float), (states.shape[0],))
        out = K.bearing_forces_many(np.ascontiguousarray(tau), np.ascontiguousarray(states), self.params)
        w = self.speed_rad_s
        return out * self.plant.clearance_m * w * w

    def coupling_angle(self, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        """φ (rad) along the samples; NaN when aligned."""
        states = np.atleast_2d(states)
        if self.mechanism_code == K.MECH_PIN:
            return states[:, 10].copy()
        if self.mechanism_code == K.MECH_RIGID:
            return np.asarray(tau, dtype=float) + self.params[K.P_PHI0]
        return np.full(states.shape[0], np.nan)

    def coupling_force_n(self, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        """``flexible``: force of the coupling on node 3 (generator side), N, shape (n, 2); zeros otherwise."""
        states = np.atleast_2d(np.asarray(states, dtype=float))
        tau = np.broadcast_to(np.asarray(tau, dtype=float), (states.shape[0],))
        out = np.zeros((states.shape[0], 2))
        if self.mechanism_code == K.MECH_FLEXIBLE:
            for i in range(states.shape[0]):
                out[i] = K.coupling_force(float(tau[i]), np.ascontiguousarray(states[i]), self.params)
        w = self.speed_rad_s
        return out * self.plant.clearance_m * w * w


def build_system(plant: Plant, speed_rpm: float, misalignment: float, unbalance: float, **kwargs) -> RotorSystem:
    """Build a :class:`RotorSystem` (same arguments as its constructor)."""
    return RotorSystem(plant, speed_rpm, misalignment, unbalance, **kwargs)
