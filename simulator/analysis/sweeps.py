"""Parameter sweeps of the rotor: bifurcation data, LLE and amplitudes vs Ω or Δ.

Every operating point is an independent run from MODEL.md §5's deterministic
initial state (no continuation), so points are run in parallel through the
shared Dask runner (:func:`simulator.runner.run_tasks`) and the result does not
depend on the number of workers or the completion order.

At each point: the steady start (by default the shooting start of
:func:`rotordiag.simulator.steady.start.steady_start`: the period-1 orbit where the
transient approaches a stable one, else the rest of the transient), then ``simulate``
(``record_revs`` recorded);
the Poincaré points (τ ≡ 0 mod 2π) of all nodes; optionally the largest
Lyapunov exponent of the Poincaré map (Benettin, continuing from the recorded
steady state); the motion type (:func:`classify_motion` on the 12 node
coordinates of the section, with the orbit's peak-to-peak as its size); the
peak-to-peak and the 1X/2X/3X amplitudes of the chosen node and direction.

Public functions: :func:`speed_sweep`, :func:`misalignment_sweep`,
:func:`amplitude_speed_curves`, :func:`run_points` (any list of operating
points), :func:`rotor_lyapunov` (LLE at one operating point).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .lyapunov import FlowMapError, LyapunovResult, largest_lyapunov
from .motion import classify_motion

if TYPE_CHECKING:
    from ..system import RotorSystem

__all__ = [
    "PointTask", "PointResult", "SweepResult", "run_point", "run_points", "speed_sweep",
    "misalignment_sweep", "amplitude_speed_curves", "rotor_lyapunov", "rotor_flow_map",
    "LLE_RTOL", "LLE_ATOL", "LLE_SEPARATION", "DIRECTIONS",
]

#: integrator tolerances of the Lyapunov runs (tighter than the paper's 1e-6 so
#: that the neighbour separation is far above the integration error)
LLE_RTOL = 1e-8
LLE_ATOL = 1e-10
#: neighbour separation on the non-dimensional state (clearances, clearances/rad)
LLE_SEPARATION = 1e-6
#: direction name -> index in the last axis of positions (x horizontal, y vertical up)
DIRECTIONS = {"x": 0, "y": 1}
#: journal node -> bearing index 0..3 (MODEL.md: bearing b at node (1, 3, 4, 6)[b-1])
_JOURNAL_BEARING = {1: 0, 3: 1, 4: 2, 6: 3}
#: state components that are not dynamic in a mechanism (φ, φ'): kept out of the perturbation
_INACTIVE = {"aligned": (10, 21), "rigid": (10, 21), "pin": (), "offset": (10, 21), "flexible": (10, 21)}


# --------------------------------------------------------------------- tasks
@dataclass(frozen=True)
class PointTask:
    """One operating point of a sweep (picklable; runs on a Dask worker)."""

    plant: Any
    speed_rpm: float
    misalignment: float
    unbalance: float
    mechanism: str = "pin"
    transient_revs: int = 400
    record_revs: int = 128
    samples_per_rev: int = 128
    rtol: float = 1e-6
    atol: float = 1e-8
    node: int = 3
    direction: str = "x"
    lle_revs: int = 0
    lle_seed: int = 0
    keep_waveform: bool = False
    sim_kwargs: tuple = ()
    steady_start: str = "shooting"


@dataclass
class PointResult:
    """Outcome of one operating point (all lengths non-dimensional, X = x/c, unless named _um).

    Attributes
    ----------
    speed_rpm, misalignment : float
    status : str
        Simulator status ("ok", "contact", "diverged").
    sections : ndarray, shape (record_revs, 6, 2)
        Poincaré points of nodes 1..6 (x, y) / c; NaN rows after an early stop.
    motion : str
        "period-n" label (e.g. "period-3"), "quasi-periodic", "chaotic",
        "unresolved", or the simulator status when the run failed.
    period : int
        n for period-n, else 0.
    lle_per_rev, lle_per_s, lle_stderr_per_rev : float
        NaN when not computed.
    pkpk : float
        Peak-to-peak of the chosen node/direction over the record.
    orders : ndarray, shape (3,)
        Zero-to-peak 1X, 2X, 3X amplitudes of the chosen node/direction (NaN for disks
        or a failed run).
    waveform : ndarray or None, shape (record_revs * samples_per_rev, 2)
        x, y / c of the chosen node (only with ``keep_waveform``).
    wall_time_s : float
    evidence : str
    steady_start : str
        How the record started: "shooting" (on the period-1 orbit, no transient) or
        "integrate" (after the transient; see :func:`rotordiag.simulator.steady.start.steady_start`).
    """

    speed_rpm: float
    misalignment: float
    status: str
    sections: np.ndarray
    motion: str
    period: int
    lle_per_rev: float
    lle_per_s: float
    lle_stderr_per_rev: float
    pkpk: float
    orders: np.ndarray
    waveform: np.ndarray | None
    wall_time_s: float
    evidence: str = ""
    steady_start: str = ""


def _check_node_direction(node: int, direction: str) -> None:
    if isinstance(node, bool) or int(node) != node or not 1 <= node <= 6:
        raise ValueError(f"node must be a node number 1..6 (MODEL.md; 3 = generator journal at the coupling), "
                         f"got {node!r}")
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be 'x' (horizontal) or 'y' (vertical), got {direction!r}")


def rotor_flow_map(system: RotorSystem, state: np.ndarray) -> tuple[Callable[[np.ndarray], np.ndarray], np.ndarray]:
    """Poincaré map of a :class:`simulator.RotorSystem` on its dynamic state components.

    Returns ``(flow, reduced_state)``: ``flow`` advances a reduced state by one
    revolution from τ ≡ 0 and raises :class:`FlowMapError` on contact or
    divergence. For ``aligned`` and ``rigid`` the φ components are not dynamic and
    are left out (a perturbation there would never decay and fake a zero exponent).
    """
    full = np.array(state, dtype=float, copy=True)
    inactive = _INACTIVE[system.mechanism]
    active = np.array([i for i in range(full.size) if i not in inactive])

    def flow(reduced: np.ndarray) -> np.ndarray:
        x = full.copy()
        x[active] = reduced
        y, status = system.advance(x, 0.0, 1)
        if status != "ok":
            raise FlowMapError(f"rotor run ended with status {status!r} during the Lyapunov run")
        return y[active]

    return flow, full[active]


def rotor_lyapunov(
    plant: Any,
    speed_rpm: float,
    misalignment: float,
    unbalance: float,
    *,
    n_revs: int = 150,
    transient_revs: int = 400,
    initial_state: np.ndarray | None = None,
    mechanism: str = "pin",
    rtol: float = LLE_RTOL,
    atol: float = LLE_ATOL,
    separation: float = LLE_SEPARATION,
    seed: int = 0,
    progress: Callable[[int], None] | None = None,
    **system_kwargs: Any,
) -> LyapunovResult:
    """Largest Lyapunov exponent of the rotor's once-per-revolution map at one operating point.

    Starts from ``initial_state`` (e.g. a ``simulate`` run's ``final_state``,
    which is at τ ≡ 0) or MODEL.md's initial state, discards ``transient_revs``
    revolutions, then averages ``n_revs`` revolutions. Per revolution and per
    second (interval = 60/rpm s).
    """
    from rotordiag.simulator import build_system

    system = build_system(plant, speed_rpm, misalignment, unbalance, mechanism=mechanism, rtol=rtol, atol=atol,
                          **system_kwargs)
    x0 = system.initial_state() if initial_state is None else system.check_state(initial_state)
    flow, reduced = rotor_flow_map(system, x0)
    return largest_lyapunov(flow, reduced, n_intervals=int(n_revs), interval_s=60.0 / float(speed_rpm),
                            transient_intervals=int(transient_revs), separation=separation, seed=seed,
                            progress=progress)


def run_point(task: PointTask) -> PointResult:
    """Run one operating point (the function the Dask workers execute)."""
    from rotordiag.simulator import build_system, simulate
    from rotordiag.simulator.simulate import order_amplitudes
    from rotordiag.simulator.steady.start import steady_start

    start = time.perf_counter()
    kwargs = dict(task.sim_kwargs)  # RotorSystem keywords (validated by _tasks)
    system = build_system(task.plant, task.speed_rpm, task.misalignment, task.unbalance, mechanism=task.mechanism,
                          rtol=task.rtol, atol=task.atol, **kwargs)
    st = steady_start(system, task.transient_revs, task.steady_start)
    from_start = st.path == "integrate" and st.warmup_revs == 0  # exactly the brute-force run
    res = simulate(task.plant, task.speed_rpm, task.misalignment, task.unbalance, mechanism=task.mechanism,
                   transient_revs=st.transient_revs, record_revs=task.record_revs,
                   samples_per_rev=task.samples_per_rev, rtol=task.rtol, atol=task.atol,
                   initial_state=None if from_start else st.state, **kwargs)
    c = res.clearance_m
    sections = res.poincare_m / c
    d = DIRECTIONS[task.direction]
    wave = res.positions_m[:, task.node - 1, :] / c
    nan3 = np.full(3, np.nan)
    if res.status != "ok":
        return PointResult(task.speed_rpm, task.misalignment, res.status, sections, res.status, 0,
                           math.nan, math.nan, math.nan, math.nan, nan3,
                           wave.copy() if task.keep_waveform else None,
                           time.perf_counter() - start, res.message, st.path)
    pkpk = float(np.ptp(wave[:, d]))
    if task.node in _JOURNAL_BEARING:
        orders = order_amplitudes(res)[_JOURNAL_BEARING[task.node], d] / c
    else:
        orders = nan3
    lle = None
    lle_vals = (math.nan, math.nan, math.nan)
    evidence_extra = ""
    if task.lle_revs > 0:
        try:
            lle = rotor_lyapunov(task.plant, task.speed_rpm, task.misalignment, task.unbalance,
                                 n_revs=task.lle_revs, transient_revs=0, initial_state=res.final_state,
                                 mechanism=task.mechanism, seed=task.lle_seed, **kwargs)
            lle_vals = (lle.lle_per_interval, lle.lle_per_s, lle.stderr_per_interval)
        except FlowMapError as exc:
            evidence_extra = f"; LLE not computed: {exc}"
    orbit_size = float(np.max(np.ptp(res.positions_m / c, axis=0)))
    motion = classify_motion(sections, lle, orbit_size=orbit_size)
    return PointResult(task.speed_rpm, task.misalignment, "ok", sections, motion.label, motion.period or 0,
                       *lle_vals, pkpk, np.asarray(orders, dtype=float),
                       wave.copy() if task.keep_waveform else None,
                       time.perf_counter() - start, motion.evidence + evidence_extra, st.path)


def run_points(
    tasks: Sequence[PointTask],
    *,
    n_workers: int | None = None,
    scheduler_address: str | None = None,
    client: Any = None,
    progress: bool = True,
    desc: str = "operating points",
) -> list[PointResult]:
    """Run operating points in parallel on Dask; results in task order.

    ``n_workers=0`` runs them one after the other in this process (no Dask;
    the baseline of the benchmark, and handy in notebooks).
    """
    tasks = list(tasks)
    out: list[PointResult | None] = [None] * len(tasks)
    if n_workers == 0:
        from tqdm.auto import tqdm

        for i, task in enumerate(tqdm(tasks, desc=desc, unit="point", disable=not progress)):
            out[i] = run_point(task)
    else:
        from rotordiag.simulator.runner import run_tasks

        for i, result in run_tasks(run_point, tasks, n_workers=n_workers, scheduler_address=scheduler_address,
                                   client=client, progress=progress, desc=desc, unit="point"):
            out[i] = result
    return out  # type: ignore[return-value]


# --------------------------------------------------------------------- results
@dataclass
class SweepResult:
    """Bifurcation / LLE / amplitude data of a one-parameter sweep.

    Attributes
    ----------
    parameter : {"speed_rpm", "misalignment"}
    values : ndarray, shape (n_points,)
        The swept parameter.
    speed_rpm, misalignment : ndarray, shape (n_points,)
    poincare : ndarray, shape (n_points, record_revs)
        Once-per-revolution X = x/c (or Y) of ``node`` — the bifurcation diagram.
    sections : ndarray, shape (n_points, record_revs, 6, 2)
        Poincaré points of all nodes / c.
    status, motion : ndarray of str, shape (n_points,)
    period : ndarray of int, shape (n_points,)  (0 when not period-n)
    lle_per_rev, lle_per_s, lle_stderr_per_rev : ndarray, shape (n_points,)  (NaN when not computed)
    pkpk : ndarray, shape (n_points,)
        Peak-to-peak of ``node``/``direction`` / c.
    orders : ndarray, shape (n_points, 3)
        Zero-to-peak 1X, 2X, 3X / c.
    wall_time_s : ndarray, shape (n_points,)
    steady_start : ndarray of str, shape (n_points,)
        "shooting" or "integrate": how each point's record started (files written before
        this field read as "integrate").
    inputs : dict
        unbalance, mechanism, node, direction, revolutions, tolerances, plant.
    """

    parameter: str
    values: np.ndarray
    speed_rpm: np.ndarray
    misalignment: np.ndarray
    poincare: np.ndarray
    sections: np.ndarray
    status: np.ndarray
    motion: np.ndarray
    period: np.ndarray
    lle_per_rev: np.ndarray
    lle_per_s: np.ndarray
    lle_stderr_per_rev: np.ndarray
    pkpk: np.ndarray
    orders: np.ndarray
    wall_time_s: np.ndarray
    steady_start: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=str))
    inputs: dict = field(default_factory=dict)

    _ARRAYS = ("values", "speed_rpm", "misalignment", "poincare", "sections", "status", "motion", "period",
               "lle_per_rev", "lle_per_s", "lle_stderr_per_rev", "pkpk", "orders", "wall_time_s", "steady_start")

    @property
    def clearance_m(self) -> float:
        return float(self.inputs["plant"]["clearance_m"])

    @classmethod
    def from_points(cls, parameter: str, points: Sequence[PointResult], inputs: dict) -> SweepResult:
        node = inputs["node"]
        d = DIRECTIONS[inputs["direction"]]
        sections = np.stack([p.sections for p in points])
        speeds = np.array([p.speed_rpm for p in points], dtype=float)
        deltas = np.array([p.misalignment for p in points], dtype=float)
        return cls(
            parameter=parameter,
            values=speeds if parameter == "speed_rpm" else deltas,
            speed_rpm=speeds,
            misalignment=deltas,
            poincare=sections[:, :, node - 1, d].copy(),
            sections=sections,
            status=np.array([p.status for p in points]),
            motion=np.array([p.motion for p in points]),
            period=np.array([p.period for p in points], dtype=int),
            lle_per_rev=np.array([p.lle_per_rev for p in points], dtype=float),
            lle_per_s=np.array([p.lle_per_s for p in points], dtype=float),
            lle_stderr_per_rev=np.array([p.lle_stderr_per_rev for p in points], dtype=float),
            pkpk=np.array([p.pkpk for p in points], dtype=float),
            orders=np.stack([p.orders for p in points]).astype(float),
            wall_time_s=np.array([p.wall_time_s for p in points], dtype=float),
            steady_start=np.array([p.steady_start for p in points]),
            inputs=dict(inputs),
        )

    def to_hdf5(self, path: str | Path) -> None:
        """Write the sweep to HDF5 (datasets named as the attributes; inputs as JSON in ``attrs``)."""
        import json

        import h5py

        with h5py.File(path, "w") as f:
            f.attrs["format"] = "rotordiag-sweep-1"
            f.attrs["parameter"] = self.parameter
            f.attrs["inputs_json"] = json.dumps(self.inputs)
            for name in self._ARRAYS:
                arr = getattr(self, name)
                if arr.dtype.kind == "U":
                    f.create_dataset(name, data=arr.astype("S"))
                else:
                    f.create_dataset(name, data=arr)

    @classmethod
    def from_hdf5(cls, path: str | Path) -> SweepResult:
        """Read a file written by :meth:`to_hdf5`."""
        import json

        import h5py

        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != "rotordiag-sweep-1":
                raise ValueError(f"{path} is not a rotordiag sweep file")
            data = {}
            for name in cls._ARRAYS:
                if name == "steady_start" and name not in f:  # written before the shooting start existed
                    data[name] = np.full(len(f["values"]), "integrate")
                    continue
                arr = f[name][()]
                data[name] = arr.astype(str) if arr.dtype.kind == "S" else arr
            return cls(parameter=str(f.attrs["parameter"]), inputs=json.loads(f.attrs["inputs_json"]), **data)


# --------------------------------------------------------------------- sweeps
def _values(name: str, values: Iterable[float], lo: float, hi: float) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(list(values) if not isinstance(values, np.ndarray) else values, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D list of numbers")
    if not np.all(np.isfinite(arr)) or arr.min() < lo or arr.max() > hi:
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}], got [{arr.min():g}, {arr.max():g}]")
    return arr


def _tasks(plant: Any, pairs: Iterable[tuple[float, float]], unbalance: float, *, mechanism: str,
           transient_revs: int, record_revs: int, samples_per_rev: int, rtol: float, atol: float, node: int,
           direction: str, lle_revs: int, seed: int, keep_waveform: bool = False,
           sim_kwargs: dict | None = None, steady_start: str = "shooting") -> list[PointTask]:
    from rotordiag.simulator.steady.start import STEADY_STARTS

    _check_node_direction(node, direction)
    if steady_start not in STEADY_STARTS:
        raise ValueError(f"steady_start must be one of {STEADY_STARTS}, got {steady_start!r}")
    if isinstance(lle_revs, bool) or int(lle_revs) != lle_revs or lle_revs < 0:
        raise ValueError(f"lle_revs must be an integer >= 0 (0 = no Lyapunov exponent), got {lle_revs!r}")
    if int(record_revs) != record_revs or record_revs < 8:
        raise ValueError(f"record_revs must be an integer >= 8 (the motion-type test needs cycles), "
                         f"got {record_revs!r}")
    base = PointTask(plant=plant, speed_rpm=0.0, misalignment=0.0, unbalance=float(unbalance),
                     mechanism=mechanism, transient_revs=int(transient_revs), record_revs=int(record_revs),
                     samples_per_rev=int(samples_per_rev), rtol=float(rtol), atol=float(atol), node=int(node),
                     direction=direction, lle_revs=int(lle_revs), lle_seed=int(seed),
                     keep_waveform=keep_waveform, sim_kwargs=tuple(sorted((sim_kwargs or {}).items())),
                     steady_start=steady_start)
    tasks = [replace(base, speed_rpm=float(s), misalignment=float(d)) for s, d in pairs]
    # validate the operating points here, in the caller's process, with the simulator's own messages
    from rotordiag.simulator import build_system

    for t in {(t.speed_rpm, t.misalignment) for t in tasks}:
        build_system(plant, t[0], t[1], unbalance, mechanism=mechanism, rtol=rtol, atol=atol, **(sim_kwargs or {}))
    return tasks


def _inputs(plant: Any, unbalance: float, **kw: Any) -> dict:
    return dict(plant=plant.to_dict(), unbalance=float(unbalance), **kw)


_RUN_KW = ("n_workers", "scheduler_address", "client", "progress")


def speed_sweep(
    plant: Any,
    speeds_rpm: Iterable[float],
    misalignment: float,
    unbalance: float,
    *,
    mechanism: str = "pin",
    node: int = 3,
    direction: str = "x",
    transient_revs: int = 400,
    record_revs: int = 128,
    samples_per_rev: int = 64,
    rtol: float = 1e-6,
    atol: float = 1e-8,
    lle_revs: int = 0,
    seed: int = 0,
    steady_start: str = "shooting",
    n_workers: int | None = None,
    scheduler_address: str | None = None,
    client: Any = None,
    progress: bool = True,
    **sim_kwargs: Any,
) -> SweepResult:
    """Bifurcation data against running speed Ω at fixed Δ (paper Figs 4, 5, 9, 10).

    Parameters
    ----------
    plant : simulator.Plant
    speeds_rpm : sequence of float
        Running speeds, r/min.
    misalignment, unbalance : float
        Δ = δ/c and A = a/c.
    mechanism : {"pin", "rigid", "aligned", "offset", "flexible"}
    node : int
        Node whose Poincaré points form the diagram (default 3, generator journal at the coupling).
    direction : {"x", "y"}
        Default "x", the paper's horizontal direction.
    transient_revs, record_revs, samples_per_rev, rtol, atol
        As for :func:`simulator.simulate` (the paper: 400 transient revolutions, rtol 1e-6).
    lle_revs : int
        Revolutions of the Benettin LLE at each point (0: not computed).
    steady_start : {"shooting", "integrate"}
        "shooting" (default): start each record on the period-1 orbit found by shooting where
        the transient approaches a clearly stable one, else integrate the rest of the transient
        (:func:`rotordiag.simulator.steady.start.steady_start`; ``SweepResult.steady_start``
        says which); "integrate": always the whole transient from MODEL.md's start.
    seed : int
        Seed of the LLE's initial perturbation direction.
    n_workers, scheduler_address, client, progress
        Where the points run (:func:`run_points`).
    **sim_kwargs
        Further ``simulate`` keywords (e.g. ``offset_angle_rad``).

    Returns
    -------
    SweepResult
    """
    speeds = _values("speeds_rpm", speeds_rpm, 100.0, 6000.0)
    tasks = _tasks(plant, [(s, misalignment) for s in speeds], unbalance, mechanism=mechanism,
                   transient_revs=transient_revs, record_revs=record_revs, samples_per_rev=samples_per_rev,
                   rtol=rtol, atol=atol, node=node, direction=direction, lle_revs=lle_revs, seed=seed,
                   sim_kwargs=sim_kwargs, steady_start=steady_start)
    points = run_points(tasks, n_workers=n_workers, scheduler_address=scheduler_address, client=client,
                        progress=progress, desc=f"speed sweep Δ={misalignment:g}")
    return SweepResult.from_points("speed_rpm", points, _inputs(
        plant, unbalance, mechanism=mechanism, node=node, direction=direction, transient_revs=transient_revs,
        record_revs=record_revs, samples_per_rev=samples_per_rev, rtol=rtol, atol=atol, lle_revs=lle_revs,
        seed=seed, misalignment=float(misalignment), steady_start=steady_start, **sim_kwargs))


def misalignment_sweep(
    plant: Any,
    speed_rpm: float,
    misalignments: Iterable[float],
    unbalance: float,
    *,
    mechanism: str = "pin",
    node: int = 3,
    direction: str = "x",
    transient_revs: int = 400,
    record_revs: int = 128,
    samples_per_rev: int = 64,
    rtol: float = 1e-6,
    atol: float = 1e-8,
    lle_revs: int = 0,
    seed: int = 0,
    steady_start: str = "shooting",
    n_workers: int | None = None,
    scheduler_address: str | None = None,
    client: Any = None,
    progress: bool = True,
    **sim_kwargs: Any,
) -> SweepResult:
    """Bifurcation data against misalignment Δ at fixed speed (paper Fig 14).

    Same parameters as :func:`speed_sweep`, with ``speed_rpm`` fixed and
    ``misalignments`` (Δ values in [0, 0.9]) swept.
    """
    deltas = _values("misalignments", misalignments, 0.0, 0.9)
    tasks = _tasks(plant, [(speed_rpm, d) for d in deltas], unbalance, mechanism=mechanism,
                   transient_revs=transient_revs, record_revs=record_revs, samples_per_rev=samples_per_rev,
                   rtol=rtol, atol=atol, node=node, direction=direction, lle_revs=lle_revs, seed=seed,
                   sim_kwargs=sim_kwargs, steady_start=steady_start)
    points = run_points(tasks, n_workers=n_workers, scheduler_address=scheduler_address, client=client,
                        progress=progress, desc=f"Δ sweep {speed_rpm:g} r/min")
    return SweepResult.from_points("misalignment", points, _inputs(
        plant, unbalance, mechanism=mechanism, node=node, direction=direction, transient_revs=transient_revs,
        record_revs=record_revs, samples_per_rev=samples_per_rev, rtol=rtol, atol=atol, lle_revs=lle_revs,
        seed=seed, speed_rpm=float(speed_rpm), steady_start=steady_start, **sim_kwargs))


def amplitude_speed_curves(
    plant: Any,
    speeds_rpm: Iterable[float],
    misalignments: Iterable[float],
    unbalance: float,
    **kwargs: Any,
) -> dict[float, SweepResult]:
    """Peak-to-peak and 1X/2X/3X amplitude against speed for several Δ (paper Fig 15).

    All (Δ, Ω) points run in one parallel pass. Keywords as :func:`speed_sweep`.
    Returns ``{Δ: SweepResult}``; use ``.pkpk`` and ``.orders`` of each.
    """
    speeds = _values("speeds_rpm", speeds_rpm, 100.0, 6000.0)
    deltas = _values("misalignments", misalignments, 0.0, 0.9)
    run_kw = {k: kwargs.pop(k) for k in _RUN_KW if k in kwargs}
    sim_kw = {k: kwargs.pop(k) for k in list(kwargs) if k not in _SWEEP_OPTIONS}
    opts = {**_SWEEP_DEFAULTS, **kwargs}
    tasks = _tasks(plant, [(s, d) for d in deltas for s in speeds], unbalance, sim_kwargs=sim_kw, **opts)
    points = run_points(tasks, desc="amplitude-speed", **run_kw)
    out = {}
    n = speeds.size
    for k, d in enumerate(deltas):
        out[float(d)] = SweepResult.from_points("speed_rpm", points[k * n:(k + 1) * n], _inputs(
            plant, unbalance, misalignment=float(d), **opts, **sim_kw))
    return out


_SWEEP_DEFAULTS = dict(mechanism="pin", node=3, direction="x", transient_revs=400, record_revs=128,
                       samples_per_rev=64, rtol=1e-6, atol=1e-8, lle_revs=0, seed=0, steady_start="shooting")
_SWEEP_OPTIONS = set(_SWEEP_DEFAULTS)
