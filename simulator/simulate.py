"""``simulate``: steady-state response of the rotor at one operating point."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL

from .params import JOURNAL_NODES, Plant
from .system import TWO_PI, RotorSystem


@dataclass
class SimulationResult:
    """Output of :func:`simulate`.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Sample times (t = 0 at the start of the transient, so t·Ω ≡ 0 mod 2π
        at the Poincaré points and the generator unbalance points along +x then).
    positions_m : ndarray, shape (n, 6, 2)
        Absolute positions of nodes 1..6 (x horizontal, y vertical up), metres.
    phi_rad : ndarray, shape (n,)
        Coupling angle φ; NaN when aligned (Δ = 0).
    poincare_m : ndarray, shape (record_revs, 6, 2)
        Node positions once per revolution (τ ≡ 0 mod 2π); NaN rows after an early stop.
    status : {"ok", "contact", "diverged"}
    message : str
    final_state : ndarray, shape (22,)
        Non-dimensional state at the end (pass as ``initial_state`` to continue).
    final_tau : float
    states : ndarray or None, shape (n, 22) (26 for ``flexible``)
        Non-dimensional states at the samples (only with ``record_state=True``).
    nfev, n_accepted, n_rejected : int
        Right-hand-side evaluations and integrator steps (transient + record).
    wall_time_s : float
    inputs : dict
        Every input of the run (plant as a dict, operating point, options).
    clearance_m : float
    bearing_offset_m : ndarray, shape (4, 2)
        Bearing centres (m): the plant's offsets plus, for ``offset``/``flexible``,
        the stationary exciter shaft-line offset.
    mean_bearing_load_n : ndarray, shape (4, 2)
        Mean force of each bearing on its journal over the record (N): the static
        bearing reactions. ``static_eccentricity`` and ``attitude_angle_deg`` derive
        the static journal positions from it and the mean journal positions.
    """

    time_s: np.ndarray
    positions_m: np.ndarray
    phi_rad: np.ndarray
    poincare_m: np.ndarray
    status: str
    message: str
    final_state: np.ndarray
    final_tau: float
    nfev: int
    n_accepted: int
    n_rejected: int
    wall_time_s: float
    inputs: dict[str, Any] = field(default_factory=dict)
    states: np.ndarray | None = None
    clearance_m: float = 0.0
    bearing_offset_m: np.ndarray = field(default_factory=lambda: np.zeros((4, 2)))
    mean_bearing_load_n: np.ndarray = field(default_factory=lambda: np.full((4, 2), np.nan))

    @property
    def static_position_m(self) -> np.ndarray:
        """Mean journal position relative to its bearing centre over the record, m, shape (4, 2)."""
        d = self.journal_displacements_m
        return d.mean(axis=0) if len(d) else np.full((4, 2), np.nan)

    @property
    def static_eccentricity(self) -> np.ndarray:
        """Static (mean) journal eccentricity ε = |mean position − centre| / c, bearings 1..4."""
        return np.hypot(*self.static_position_m.T) / self.clearance_m

    @property
    def attitude_angle_deg(self) -> np.ndarray:
        """Static attitude angle of each journal, degrees: the angle from the mean bearing load
        (the direction the film pushes the journal, reversed) to the mean journal displacement,
        positive in the direction of rotation (+x toward +y). About 90° for a lightly loaded
        short bearing, toward 0° as the load grows; NaN where the load is zero."""
        pos = self.static_position_m
        load = -self.mean_bearing_load_n  # the journal's load on the film
        a = np.arctan2(pos[:, 1], pos[:, 0]) - np.arctan2(load[:, 1], load[:, 0])
        out = np.degrees(np.angle(np.exp(1j * a)))
        out[np.hypot(*load.T) == 0] = np.nan
        return out

    @property
    def speed_rpm(self) -> float:
        return float(self.inputs["speed_rpm"])

    @property
    def journal_displacements_m(self) -> np.ndarray:
        """Journals of bearings 1..4 relative to their bearing centres, shape (n, 4, 2):
        what a pair of proximity probes at each bearing sees."""
        idx = [n - 1 for n in JOURNAL_NODES]
        return self.positions_m[:, idx, :] - self.bearing_offset_m[None, :, :]

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def simulate(
    plant: Plant,
    speed_rpm: float,
    misalignment: float,
    unbalance: float,
    *,
    mechanism: str = "pin",
    transient_revs: int = 400,
    record_revs: int = 128,
    samples_per_rev: int = 128,
    sample_rate_hz: float | None = None,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    stiff_solver: bool = True,
    initial_state: np.ndarray | None = None,
    unbalance_phase_rad: float = 0.0,
    exciter_unbalance: float = 0.0,
    exciter_unbalance_phase_rad: float = 0.0,
    offset_angle_rad: float = 0.0,
    record_state: bool = False,
    settle_tol: float | None = None,
    coupling_phase_rad: float = 0.0,
    angular_misalignment_mrad: float = 0.0,
) -> SimulationResult:
    """Simulate the generator–exciter rotor and record its steady state.

    Parameters
    ----------
    plant : Plant
        Plant parameters (``Plant.default()`` for MODEL.md's).
    speed_rpm : float
        Running speed Ω, r/min, in [100, 6000].
    misalignment : float
        Non-dimensional parallel misalignment Δ = δ/c, in [0, 0.9].
    unbalance : float
        Non-dimensional generator unbalance A = a/c, in [0, 0.5].
    mechanism : {"pin", "rigid", "aligned", "offset", "flexible"}
        Coupling model (docs/model.md); Δ = 0 without an angular offset always runs ``aligned``.

        - ``pin``: the paper's holonomic constraint |r3 − r4| = δ (MODEL.md 3a).
        - ``rigid``: the offset is fixed in the rotating shaft: kinematically a
          **rotating coupling eccentricity** (a once-per-revolution runout of radius δ
          at the coupling), which the field reads as unbalance/runout, not misalignment.
        - ``offset``: a **stationary** parallel offset of the shaft lines: the exciter's
          bearing centres are displaced by δ in direction ``offset_angle_rad``, the
          coupling is rigid in translation. Changes static journal positions and loads.
          With ``angular_misalignment_mrad`` the exciter line is also tilted about the coupling.
        - ``flexible``: the stationary offset of ``offset`` across a flexible coupling
          of radial stiffness ``plant.coupling_stiffness_n_m``, with its kinematic 2X
          misalignment reaction (amplitude k_c·δ/2, phase ``coupling_phase_rad``).
    transient_revs : int
        Revolutions discarded before recording (the paper: 400).
    record_revs : int
        Revolutions recorded (≥ 1).
    samples_per_rev : int
        Samples per revolution at exact phases τ = 2πk/S (dense output).
    sample_rate_hz : float, optional
        If given, record at this fixed rate instead (what a data-acquisition
        system does); ``samples_per_rev`` is then ignored.
    rtol, atol : float
        Integrator tolerances (atol on the non-dimensional state X = x/c).
    stiff_solver : bool
        Go on with LSODA where the explicit Dormand–Prince integration becomes stiff
        (a journal whirling near its bushing wall; ``simulator._stiff``). ``False`` keeps the
        explicit integrator throughout (the behaviour before; 10–100× slower on such runs).
    initial_state : ndarray, shape (22,), optional
        Non-dimensional start state (e.g. ``final_state`` of a previous run);
        default MODEL.md section 5's.
    unbalance_phase_rad : float
        Angle of the generator unbalance at t = 0 (from +x toward +y).
    exciter_unbalance, exciter_unbalance_phase_rad : float
        Exciter unbalance a2/c (0–0.5) and its phase θ2.
    offset_angle_rad : float
        Direction φ0 of the offset from +x toward +y: of the rotating eccentricity at
        t = 0 (``rigid``), or of the stationary exciter shaft-line offset (``offset``,
        ``flexible``; 0 horizontal, −π/2 downward).
    coupling_phase_rad : float
        ``flexible`` only: phase ψ of the coupling's 2X excitation at t = 0.
    angular_misalignment_mrad : float
        ``offset``/``flexible`` only: a stationary **angular** offset: the exciter shaft line
        tilted about the coupling by α (mrad) in direction ``offset_angle_rad`` — bearing 3
        (at the coupling) stays, bearing 4's centre moves by α·``plant.exciter_bearing_span_m``
        (on top of the parallel δ). |α|·L ≤ 0.9 c. May be used with Δ = 0 (pure angular offset).
    record_state : bool
        Also keep the full non-dimensional states at the samples.
    settle_tol : float, optional
        Early end of the transient: once the once-per-revolution map has
        converged (every non-dimensional coordinate and velocity changes by
        less than ``settle_tol`` between consecutive revolutions, for
        ``SETTLE_REVS`` revolutions in a row, after at least ``MIN_TRANSIENT_REVS``),
        recording starts at once; capped at ``transient_revs``. Only period-1
        motion settles this way; other motion runs the full transient. The
        recorded times then start earlier (``inputs["transient_revs_used"]``).

    Returns
    -------
    SimulationResult
        With ``status`` "ok", "contact" (a journal reached ε ≥ 0.999) or
        "diverged"; after an early stop the arrays hold the samples recorded
        up to that point (never NaN-padded positions).

    Raises
    ------
    ValueError
        For inputs outside their documented ranges, naming the parameter.
    """
    start = time.perf_counter()
    transient_revs = _count("transient_revs", transient_revs, 0)
    record_revs = _count("record_revs", record_revs, 1)
    system = RotorSystem(
        plant, speed_rpm, misalignment, unbalance, mechanism=mechanism,
        unbalance_phase_rad=unbalance_phase_rad, exciter_unbalance=exciter_unbalance,
        exciter_unbalance_phase_rad=exciter_unbalance_phase_rad, offset_angle_rad=offset_angle_rad,
        coupling_phase_rad=coupling_phase_rad, angular_misalignment_mrad=angular_misalignment_mrad,
        rtol=rtol, atol=atol, stiff_solver=stiff_solver,
    )
    if sample_rate_hz is None:
        samples_per_rev = _count("samples_per_rev", samples_per_rev, 4)
        grid_samples_per_rev: int | None = samples_per_rev
        grid_dt = TWO_PI / samples_per_rev
        n_grid = record_revs * samples_per_rev
    else:
        fs = float(sample_rate_hz)
        min_fs = 8.0 * system.speed_rad_s / TWO_PI
        if not (math.isfinite(fs) and fs >= min_fs):
            raise ValueError(f"sample_rate_hz must be ≥ {min_fs:.1f} Hz (8 samples per revolution), got {sample_rate_hz!r}")
        grid_dt = system.speed_rad_s / fs
        n_grid = int(math.floor(record_revs * TWO_PI / grid_dt + 1e-9))
        grid_samples_per_rev = None  # a sample-rate grid is not synchronous
    y0 = system.initial_state() if initial_state is None else system.check_state(initial_state)

    tau0 = 0.0
    nfev = nacc = nrej = 0
    if settle_tol is not None and transient_revs > MIN_TRANSIENT_REVS:
        y0, tau0, counts, failed = _settle(system, y0, transient_revs, float(settle_tol))
        nfev, nacc, nrej = counts
        transient_used = int(round(tau0 / TWO_PI))
    else:
        transient_used = transient_revs
    tau_rec = TWO_PI * transient_used
    tau_end = tau_rec + TWO_PI * record_revs
    # One integration from τ0 through the record window; the record grid
    # starts at τ_rec, so the transient is not sampled.
    y, grid, pcs, stats, ng, npc = system.integrate(
        y0, tau0, tau_end, grid_t0=tau_rec, grid_dt=grid_dt, n_grid=n_grid,
        pc_t0=tau_rec, n_poincare=record_revs,
    )
    tau = tau_rec + grid_dt * np.arange(ng)
    states = grid[:ng]
    positions = system.node_positions(tau, states)
    pc = np.full((record_revs, 6, 2), np.nan)
    if npc:
        pc[:npc] = system.node_positions(tau_rec + TWO_PI * np.arange(npc), pcs[:npc])
    message = _message(stats.status, stats.tau, system.speed_rad_s, stats.max_eccentricity, tau_rec)
    inputs = dict(
        plant=plant.to_dict(), speed_rpm=system.speed_rpm, misalignment=system.misalignment,
        unbalance=system.unbalance, mechanism=system.mechanism, requested_mechanism=mechanism,
        transient_revs=transient_revs, record_revs=record_revs, samples_per_rev=grid_samples_per_rev,
        sample_rate_hz=None if sample_rate_hz is None else float(sample_rate_hz), rtol=system.rtol,
        atol=system.atol, unbalance_phase_rad=float(unbalance_phase_rad),
        exciter_unbalance=float(exciter_unbalance),
        exciter_unbalance_phase_rad=float(exciter_unbalance_phase_rad),
        offset_angle_rad=float(offset_angle_rad), initial_state_given=initial_state is not None,
        settle_tol=settle_tol, transient_revs_used=transient_used,
        coupling_phase_rad=float(coupling_phase_rad),
        angular_misalignment_mrad=system.angular_misalignment_mrad,
        stiff_solver=bool(stiff_solver),
        stiff_from_rev=None if math.isnan(stats.stiff_from_tau) else stats.stiff_from_tau / TWO_PI,
    )
    loads = system.bearing_forces_n(tau, states).mean(axis=0) if ng else np.full((4, 2), np.nan)
    return SimulationResult(
        time_s=tau / system.speed_rad_s,
        positions_m=positions,
        phi_rad=system.coupling_angle(tau, states),
        poincare_m=pc,
        status=stats.status,
        message=message,
        final_state=y,
        final_tau=stats.tau,
        nfev=stats.nfev + nfev,
        n_accepted=stats.n_accepted + nacc,
        n_rejected=stats.n_rejected + nrej,
        wall_time_s=time.perf_counter() - start,
        inputs=inputs,
        states=states.copy() if record_state else None,
        clearance_m=plant.clearance_m,
        bearing_offset_m=system.bearing_centres_m.copy(),
        mean_bearing_load_n=loads,
    )


#: Early transient end: revolutions always run, and consecutive settled revolutions required.
MIN_TRANSIENT_REVS = 30
SETTLE_REVS = 5


def _settle(system: RotorSystem, y: np.ndarray, transient_revs: int, tol: float):
    """Advance revolution by revolution until the Poincaré map has converged (see ``settle_tol``)."""
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"settle_tol must be a positive number, got {tol!r}")
    y, _, _, st, _, _ = system.integrate(y, 0.0, TWO_PI * MIN_TRANSIENT_REVS)
    counts = [st.nfev, st.n_accepted, st.n_rejected]
    rev, settled = MIN_TRANSIENT_REVS, 0
    while rev < transient_revs and st.status == "ok":
        y_new, _, _, st, _, _ = system.integrate(y, TWO_PI * rev, TWO_PI * (rev + 1))
        counts = [counts[0] + st.nfev, counts[1] + st.n_accepted, counts[2] + st.n_rejected]
        change = np.abs(y_new - y)
        change[10] = abs(math.remainder(y_new[10] - y[10], TWO_PI))  # φ: rigid turns once per rev, pin may race
        settled = settled + 1 if change.max() < tol else 0
        y, rev = y_new, rev + 1
        if settled >= SETTLE_REVS:
            break
    return y, TWO_PI * rev, tuple(counts), st.status != "ok"


def _count(name: str, value: int, minimum: int) -> int:
    try:
        v = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an integer ≥ {minimum}, got {value!r}") from None
    if v != value or v < minimum or v > 10_000_000:
        raise ValueError(f"{name} must be an integer in [{minimum}, 10000000], got {value!r}")
    return v


def _message(status: str, tau: float, w: float, emax: float, tau_rec: float) -> str:
    t = tau / w
    rev = tau / TWO_PI
    if status == "ok":
        return "completed"
    where = "during the transient" if tau < tau_rec else "during the record"
    if status == "contact":
        return (f"journal reached its bushing (eccentricity {emax:.4f}) at t = {t:.4f} s "
                f"(revolution {rev:.1f}, {where}); samples up to that point are kept")
    return (f"integration diverged at t = {t:.4f} s (revolution {rev:.1f}, {where}); "
            f"samples up to that point are kept")


def order_amplitudes(result: SimulationResult, orders: tuple[int, ...] = (1, 2, 3)) -> np.ndarray:
    """Zero-to-peak amplitudes (m) of the given running-speed orders at the four journals.

    Exact for a record of whole revolutions sampled synchronously
    (``samples_per_rev`` mode): order k falls on FFT bin k·record_revs.

    Returns
    -------
    ndarray, shape (4, 2, len(orders))
        Bearings 1..4, directions (x, y), orders.
    """
    revs = result.inputs["record_revs"]
    spr = result.inputs["samples_per_rev"]
    if spr is None:
        raise ValueError("order_amplitudes needs a synchronously sampled result (samples_per_rev mode)")
    d = result.journal_displacements_m
    n = d.shape[0]
    if n != revs * spr:
        raise ValueError("the run stopped early; its record is not whole revolutions")
    spec = np.fft.rfft(d, axis=0) * (2.0 / n)
    return np.stack([np.abs(spec[k * revs]) for k in orders], axis=-1)
