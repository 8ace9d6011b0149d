"""Plots of sweeps and the paper's figure set (``rotordiag figures``).

Plot helpers draw on a Matplotlib ``Axes`` (:func:`plot_bifurcation`,
:func:`plot_lle`, :func:`plot_orbit`, :func:`plot_spectrum`,
:func:`plot_amplitudes`); :func:`paper_figures` computes every operating point
of the paper's Figs 4–15 in one parallel pass (one progress bar) and writes the
PNGs, the sweep data (HDF5) and a ``summary.json`` of the numbers that
``docs/reproduction.md`` quotes (motion windows, LLE signs, 2X/1X, jumps).
"""
from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .sweeps import PointResult, PointTask, SweepResult, _inputs, _tasks, run_points

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from ..params import Plant

__all__ = ["plot_bifurcation", "plot_campbell", "plot_train_sweep", "train_figures", "plot_lle", "plot_orbit", "plot_spectrum", "plot_amplitudes", "motion_windows",
           "FigureSettings", "QUICK", "FULL", "paper_figures"]

COLOURS = {0.0: "tab:red", 0.02: "black", 0.10: "tab:blue", 0.20: "tab:green"}


def _clearance_axes(ax: Any, b: int, names: Any, clear: Any) -> None:
    """One bearing's panel of a clearance-circle figure: the bearing centre, equal axes, its name and clearance."""
    ax.plot(0, 0, "+", c="k")
    ax.set_aspect("equal")
    ax.set_title(f"{names[b]} (c = {clear[b]:.0f} µm)", fontsize=9)
    ax.set_xlabel("x (µm)")
    if b == 0:
        ax.set_ylabel("y (µm, up)")
    ax.grid(alpha=0.3)


def _colour(delta: float, default: str = "black") -> str:
    for k, v in COLOURS.items():
        if abs(k - delta) < 1e-12:
            return v
    return default


def _label_param(sweep: SweepResult) -> str:
    return "running speed Ω (r/min)" if sweep.parameter == "speed_rpm" else "misalignment Δ = δ/c (–)"


def plot_bifurcation(ax: Axes, sweep: SweepResult, *, colour: str = "black", label: str | None = None,
                     size: float = 1.5) -> None:
    """Poincaré points of the swept node/direction against the parameter; failed runs as grey ×."""
    ok = sweep.status == "ok"
    n_rec = sweep.poincare.shape[1]
    xs = np.repeat(sweep.values[ok], n_rec)
    ax.scatter(xs, sweep.poincare[ok].ravel(), s=size, c=colour, marker=".", linewidths=0, label=label,
               rasterized=True)
    if np.any(~ok):
        lo = np.nanmin(sweep.poincare[ok]) if np.any(ok) else 0.0
        ax.scatter(sweep.values[~ok], np.full((~ok).sum(), lo), marker="x", c="0.5", s=12,
                   label="journal contact / diverged")
    comp = sweep.inputs.get("direction", "x").upper()
    ax.set_xlabel(_label_param(sweep))
    ax.set_ylabel(f"{comp} = {comp.lower()}/c, node {sweep.inputs.get('node', 3)} (–)")
    ax.grid(alpha=0.3)


def plot_lle(ax: Axes, sweep: SweepResult, *, colour: str = "black", label: str | None = None,
             noise: float | None = None) -> None:
    """LLE per revolution against the parameter, with a ±3 standard-error band."""
    from .motion import LLE_NOISE_PER_INTERVAL

    x = sweep.values
    y = sweep.lle_per_rev
    e = 3 * np.nan_to_num(sweep.lle_stderr_per_rev)
    ax.plot(x, y, "-o", ms=2.5, lw=1, c=colour, label=label)
    ax.fill_between(x, y - e, y + e, color=colour, alpha=0.15, lw=0)
    ax.axhline(0.0, c="0.3", lw=0.8)
    n = LLE_NOISE_PER_INTERVAL if noise is None else noise
    ax.axhspan(-n, n, color="0.85", zorder=0, label="|LLE| ≤ noise level (quasi-periodic)")
    ax.set_xlabel(_label_param(sweep))
    ax.set_ylabel("largest Lyapunov exponent (1/rev)")
    ax.grid(alpha=0.3)


def plot_orbit(ax: Axes, point: PointResult, node: int = 3, title: str | None = None) -> None:
    """Orbit of a node (black) with its Poincaré points (red), in clearances."""
    w = point.waveform
    assert w is not None, "plot_orbit needs a point computed with keep_waveform=True"
    ax.plot(w[:, 0], w[:, 1], c="black", lw=0.5)
    sec = point.sections[:, node - 1]
    ax.plot(sec[:, 0], sec[:, 1], "o", c="red", ms=3)
    ax.set_xlabel(f"X = x/c, node {node} (–)")
    ax.set_ylabel(f"Y = y/c, node {node} (–)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)


def plot_spectrum(ax: Axes, point: PointResult, clearance_m: float, samples_per_rev: int, record_revs: int,
                  max_order: float = 4.0) -> None:
    """Amplitude spectrum (zero-to-peak, µm) of the horizontal displacement; 1X..3X marked."""
    assert point.waveform is not None, "plot_spectrum needs a point computed with keep_waveform=True"
    x = point.waveform[:, 0] * clearance_m * 1e6
    n = x.size
    spec = np.abs(np.fft.rfft(x - x.mean())) * 2.0 / n
    f_hz = np.fft.rfftfreq(n, d=60.0 / point.speed_rpm / samples_per_rev)
    f_run = point.speed_rpm / 60.0
    keep = f_hz <= max_order * f_run
    ax.semilogy(f_hz[keep], spec[keep] + 1e-4, c="black", lw=0.8)
    for k in (1, 2, 3):
        ax.axvline(k * f_run, c="tab:orange", lw=0.6, ls="--")
        ax.text(k * f_run, ax.get_ylim()[1], f"{k}X", ha="center", va="bottom", fontsize=7, color="tab:orange")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("amplitude x, node 3 (µm, 0-pk)")
    ax.grid(alpha=0.3, which="both")


def plot_amplitudes(axes: Sequence[Axes], curves: dict[float, SweepResult]) -> None:
    """Peak-to-peak, 1X and 2X (µm) against speed for several Δ (three axes)."""
    titles = ("peak-to-peak", "1X (0-pk)", "2X (0-pk)")
    for d, sw in curves.items():
        c_um = sw.clearance_m * 1e6
        vals = (sw.pkpk * c_um, sw.orders[:, 0] * c_um, sw.orders[:, 1] * c_um)
        for ax, v in zip(axes, vals):
            ax.plot(sw.values, v, "-o", ms=2, lw=1, c=_colour(d, "tab:purple"), label=f"Δ = {d:g}")
    for ax, t in zip(axes, titles):
        ax.set_xlabel("running speed Ω (r/min)")
        ax.set_ylabel(f"x node 3, {t} (µm)")
        ax.grid(alpha=0.3)
        ax.set_yscale("log")
    axes[0].legend(fontsize=7)


def plot_campbell(ax: Axes, data: Any, criticals: Sequence[Any] = (), *, title: str = "") -> Any:
    """Campbell diagram on ``ax``: damped natural frequencies of ``data`` (a ``simulator.campbell.CampbellData``)
    against speed, coloured by damping ratio (blue damped, red near or below zero), the 1X and 2X lines and
    the ``criticals`` (○, ``CriticalSpeed``); returns the scatter for a colour bar."""
    sp = data.speeds_rpm
    sc = None
    for m in range(data.frequencies_hz.shape[1]):
        ok = np.isfinite(data.frequencies_hz[:, m])
        sc = ax.scatter(sp[ok], data.frequencies_hz[ok, m], c=np.clip(data.damping_ratios[ok, m], -0.05, 0.3), s=10,
                        cmap="coolwarm_r", vmin=-0.05, vmax=0.3)
    for k, style in ((1, "k-"), (2, "k--")):
        ax.plot(sp, k * sp / 60.0, style, lw=0.8, label=f"{k}X")
    for c in criticals:
        ax.plot(c.speed_rpm, c.frequency_hz, "o", mfc="none", mec="k", ms=9)
    if criticals:
        ax.plot([], [], "o", mfc="none", mec="k", label="critical speed (AF ≥ 2.5)")
    finite = data.frequencies_hz[np.isfinite(data.frequencies_hz)]
    top = float(finite.max()) * 1.05 if finite.size else 2.6 * sp.max() / 60.0
    ax.set_ylim(0, min(top, 2.6 * sp.max() / 60.0))
    ax.set_xlim(0, sp.max())
    ax.set_xlabel("speed (r/min)")
    ax.set_ylabel("damped natural frequency (Hz)")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)
    return sc


def plot_train_sweep(axes: Sequence[Axes], sweep: Any, *, title: str = "") -> None:
    """A train's speed sweep (``analysis.train.TrainSweep``) on two axes: the Poincaré points (journal x
    relative to its bearing, once per revolution) of each bearing, and its 1X (solid) and 2X (dashed)
    amplitudes, µm pk-pk, against speed."""
    colours = ["#1f5fa8", "#d9480f", "#2b8a3e", "#862e9c", "#555555", "#b5a300"]
    ax0, ax1 = axes[0], axes[1]
    n_rev = sweep.poincare_um.shape[1]
    for b, name in enumerate(sweep.bearing_names):
        c = colours[b % len(colours)]
        ax0.plot(np.repeat(sweep.speeds_rpm, n_rev), sweep.poincare_um[:, :, b, 0].ravel(), ".", ms=2, c=c, label=name)
        ax1.plot(sweep.speeds_rpm, sweep.amp_1x_um_pp[:, b], "-o", ms=3, c=c, label=f"{name} 1X")
        ax1.plot(sweep.speeds_rpm, sweep.amp_2x_um_pp[:, b], "--", c=c, lw=1, label=f"{name} 2X")
    ax0.set_ylabel("journal x, once per rev (µm)")
    ax0.legend(fontsize=7, ncol=4, loc="best")
    ax0.grid(alpha=0.3)
    ax1.set_xlabel("speed (r/min)")
    ax1.set_ylabel("amplitude (µm pk-pk)")
    ax1.legend(fontsize=7, ncol=4, loc="best")
    ax1.grid(alpha=0.3)
    if title:
        ax0.set_title(title, fontsize=9)


def train_figures(out_dir: str | Path, train: Any, *, name: str, speed_rpm: float, speeds_rpm: Sequence[float] | np.ndarray,
                  transient_revs: int = 320, record_revs: int = 32, samples_per_rev: int = 64) -> dict:
    """A shaft train's figure set in ``out_dir``: ``train_orbits.png`` (each bearing's orbit at ``speed_rpm``
    in its clearance circle, DC included), ``train_spectra.png`` (x and y probe spectra at each bearing, in
    orders of running speed), ``train_centreline.png`` (each journal's mean position over ``speeds_rpm`` in
    its clearance circle) and ``train_amplitude_speed.png`` (Poincaré points, 1X and 2X over ``speeds_rpm``);
    returns a summary (files, the run's status, 1X/2X per bearing at ``speed_rpm``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..train.dynamics import simulate_train
    from .train import order_amplitude_pp, train_speed_sweep

    start = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    run = simulate_train(train, speed_rpm, transient_revs=transient_revs, record_revs=record_revs,
                         samples_per_rev=samples_per_rev)
    if not run.ok:
        raise ValueError(f"the run at {speed_rpm:g} r/min did not reach a steady state: {run.status} {run.message}")
    j = run.journal_m * 1e6
    clear = np.asarray(run.clearance_m, dtype=float) * 1e6
    names = list(run.bearing_names)
    nb = len(names)
    files = []
    circle = np.linspace(0, 2 * np.pi, 361)

    fig, axes = plt.subplots(1, nb, figsize=(3.2 * nb, 3.6), squeeze=False)
    for b in range(nb):
        ax = axes[0, b]
        ax.plot(clear[b] * np.cos(circle), clear[b] * np.sin(circle), c="0.6", lw=0.8)
        ax.plot(j[:, b, 0], j[:, b, 1], c="#1f5fa8", lw=0.8)
        ax.plot(j[::samples_per_rev, b, 0], j[::samples_per_rev, b, 1], "o", c="#d9480f", ms=3)
        _clearance_axes(ax, b, names, clear)
    fig.suptitle(f"{name}: journal orbits at {speed_rpm:g} r/min in the clearance circle (dot: once per rev)",
                 fontsize=10)
    fig.tight_layout()
    files.append(out / "train_orbits.png")
    fig.savefig(files[-1], dpi=100)
    plt.close(fig)

    n = j.shape[0]
    orders = np.fft.rfftfreq(n, d=1.0 / samples_per_rev)
    fig, axes = plt.subplots(nb, 1, figsize=(8, 2.0 * nb + 0.6), sharex=True, squeeze=False)
    for b in range(nb):
        ax = axes[b, 0]
        for k, (lab, c) in enumerate((("x", "#1f5fa8"), ("y", "#c2255c"))):
            sig = j[:, b, k] - j[:, b, k].mean()
            amp = 2 * 2 * np.abs(np.fft.rfft(sig)) / n
            ax.plot(orders, amp, c=c, lw=0.9, label=f"{lab} probe")
        ax.set_xlim(0, 4)
        ax.set_ylabel(f"{names[b]} (µm pk-pk)", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("frequency / running speed (order)")
    axes[0, 0].set_title(f"{name}: spectra at the bearings, {speed_rpm:g} r/min (DC removed)", fontsize=10)
    fig.tight_layout()
    files.append(out / "train_spectra.png")
    fig.savefig(files[-1], dpi=100)
    plt.close(fig)

    sw = train_speed_sweep(train, speeds_rpm, transient_revs=transient_revs, record_revs=max(8, record_revs // 2),
                           samples_per_rev=samples_per_rev)
    fig, axes = plt.subplots(1, nb, figsize=(3.2 * nb, 3.8), squeeze=False)
    for b in range(nb):
        ax = axes[0, b]
        ax.plot(clear[b] * np.cos(circle), clear[b] * np.sin(circle), c="0.6", lw=0.8)
        ok = np.isfinite(sw.centre_um[:, b, 0])
        ax.plot(sw.centre_um[ok, b, 0], sw.centre_um[ok, b, 1], "-o", ms=3, c="#2b8a3e")
        for s, (x, y) in zip(sw.speeds_rpm[ok][[0, -1]], sw.centre_um[ok, b][[0, -1]], strict=True):
            ax.annotate(f"{s:.0f}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
        _clearance_axes(ax, b, names, clear)
    fig.suptitle(f"{name}: shaft centreline in the clearance circle, {sw.speeds_rpm[0]:.0f}–{sw.speeds_rpm[-1]:.0f} "
                 "r/min (labels: r/min)", fontsize=10)
    fig.tight_layout()
    files.append(out / "train_centreline.png")
    fig.savefig(files[-1], dpi=100)
    plt.close(fig)

    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_train_sweep(axes, sw, title=f"{name}: amplitude against speed")
    fig.tight_layout()
    files.append(out / "train_amplitude_speed.png")
    fig.savefig(files[-1], dpi=100)
    plt.close(fig)

    summary = dict(name=name, speed_rpm=speed_rpm, status=run.status, message=run.message,
                   bearings=names, clearance_um=clear.tolist(),
                   amp_1x_um_pp=order_amplitude_pp(j, samples_per_rev, 1).max(axis=-1).tolist(),
                   amp_2x_um_pp=order_amplitude_pp(j, samples_per_rev, 2).max(axis=-1).tolist(),
                   sweep_speeds_rpm=sw.speeds_rpm.tolist(), sweep_status=sw.status,
                   files=[f.name for f in files], wall_time_s=time.perf_counter() - start)
    (out / "train_summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def motion_windows(sweep: SweepResult) -> list[dict]:
    """Contiguous parameter ranges with the same motion label (with LLE range where computed)."""
    out: list[dict] = []
    for k, label in enumerate(sweep.motion):
        v = float(sweep.values[k])
        lle = float(sweep.lle_per_rev[k])
        if out and out[-1]["motion"] == label:
            out[-1]["to"] = v
            out[-1]["n_points"] += 1
            if np.isfinite(lle):
                out[-1]["lle_min"] = min(out[-1]["lle_min"], lle)
                out[-1]["lle_max"] = max(out[-1]["lle_max"], lle)
        else:
            out.append(dict(motion=str(label), **{"from": v}, to=v, n_points=1,
                            lle_min=lle if np.isfinite(lle) else np.inf,
                            lle_max=lle if np.isfinite(lle) else -np.inf))
    for w in out:
        if not np.isfinite(w["lle_min"]):
            w["lle_min"] = w["lle_max"] = None
        else:
            w["lle_min"], w["lle_max"] = round(w["lle_min"], 4), round(w["lle_max"], 4)
    return out


# ------------------------------------------------------------------ the paper's set
@dataclass(frozen=True)
class FigureSettings:
    """Resolution of ``rotordiag figures`` (``QUICK`` and ``FULL`` presets)."""

    speed_step_rpm: float
    delta_step: float
    transient_revs: int
    record_revs: int
    lle_revs: int
    orbit_record_revs: int = 64
    unbalance: float = 0.05
    mechanism: str = "pin"
    speed_from_rpm: float = 1200.0
    speed_to_rpm: float = 3000.0
    delta_from: float = 0.02
    delta_to: float = 0.8


QUICK = FigureSettings(speed_step_rpm=100.0, delta_step=0.06, transient_revs=300, record_revs=64, lle_revs=60)
FULL = FigureSettings(speed_step_rpm=25.0, delta_step=0.01, transient_revs=400, record_revs=128, lle_revs=100,
                      orbit_record_revs=128)

SWEEP_DELTAS = (0.0, 0.02, 0.10)
AMPLITUDE_DELTAS = (0.0, 0.02, 0.10, 0.20)
ORBIT_SPEEDS = (1950.0, 2500.0, 2935.0)
DELTA_SWEEP_SPEEDS = (1843.0, 2140.0)


def _grid(a: float, b: float, step: float) -> np.ndarray:
    n = int(round((b - a) / step)) + 1
    return np.round(np.linspace(a, b, n), 10)


def paper_figures(out_dir: str | Path, settings: FigureSettings = QUICK, *, plant: Plant | None = None,
                  n_workers: int | None = None, scheduler_address: str | None = None,
                  progress: bool = True) -> dict:
    """Compute and write the paper's figure set into ``out_dir``; returns the summary dict.

    Files: ``fig04_bifurcation_speed_d0_d002.png``, ``fig05_lle_speed_d0_d002.png``,
    ``fig09_bifurcation_speed_d010.png``, ``fig10_lle_speed_d010.png``,
    ``fig06_orbits_1950rpm.png``, ``fig07_orbits_2500rpm.png``, ``fig08_orbits_2935rpm.png``
    (each with Δ = 0, 0.02, 0.10: Figs 6–8 and 11–13), ``fig14_bifurcation_misalignment.png``,
    ``fig15_amplitude_speed.png``, ``sweeps.h5`` and ``summary.json``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotordiag.simulator import Plant

    start = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    plant = Plant.default() if plant is None else plant
    s = settings
    speeds = _grid(s.speed_from_rpm, s.speed_to_rpm, s.speed_step_rpm)
    deltas = _grid(s.delta_from, s.delta_to, s.delta_step)
    common: dict[str, Any] = dict(mechanism=s.mechanism, transient_revs=s.transient_revs, samples_per_rev=64, rtol=1e-6,
                  atol=1e-8, node=3, direction="x", seed=0)

    groups: dict[str, list[PointTask]] = {}
    for d in AMPLITUDE_DELTAS:
        lle = s.lle_revs if d in SWEEP_DELTAS else 0
        groups[f"speed_d{d:g}"] = _tasks(plant, [(v, d) for v in speeds], s.unbalance, record_revs=s.record_revs,
                                         lle_revs=lle, **common)
    for v in DELTA_SWEEP_SPEEDS:
        groups[f"delta_{v:g}rpm"] = _tasks(plant, [(v, d) for d in deltas], s.unbalance,
                                           record_revs=s.record_revs, lle_revs=0, **common)
    orbit_common = {**common, "samples_per_rev": 128}
    groups["orbits"] = [replace(t, keep_waveform=True) for t in _tasks(
        plant, [(v, d) for v in ORBIT_SPEEDS for d in SWEEP_DELTAS], s.unbalance,
        record_revs=s.orbit_record_revs, lle_revs=0, **orbit_common)]

    flat = [t for ts in groups.values() for t in ts]
    results = run_points(flat, n_workers=n_workers, scheduler_address=scheduler_address, progress=progress,
                         desc="paper figures")
    by_group: dict[str, list[PointResult]] = {}
    k = 0
    for name, ts in groups.items():
        by_group[name] = results[k:k + len(ts)]
        k += len(ts)

    sweeps: dict[str, SweepResult] = {}
    for name, pts in by_group.items():
        if name == "orbits":
            continue
        if name.startswith("speed"):
            d = pts[0].misalignment
            lle = s.lle_revs if d in SWEEP_DELTAS else 0
            sweeps[name] = SweepResult.from_points("speed_rpm", pts, _inputs(
                plant, s.unbalance, misalignment=d, record_revs=s.record_revs, lle_revs=lle, **common))
        else:
            sweeps[name] = SweepResult.from_points("misalignment", pts, _inputs(
                plant, s.unbalance, speed_rpm=pts[0].speed_rpm, record_revs=s.record_revs, lle_revs=0, **common))
    for name, sw in sweeps.items():
        sw.to_hdf5(out / f"sweep_{name}.h5")

    files = []

    def save(fig: Any, name: str) -> None:
        fig.tight_layout()
        fig.savefig(out / name, dpi=110)
        plt.close(fig)
        files.append(name)

    cap = f"A = {s.unbalance:g}, ρ = {plant.asymmetry:g}, {s.mechanism}"
    # Fig 4: bifurcation vs speed, Δ = 0 (red) and 0.02 (black)
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    plot_bifurcation(ax, sweeps["speed_d0"], colour="tab:red", label="Δ = 0", size=3)
    plot_bifurcation(ax, sweeps["speed_d0.02"], colour="black", label="Δ = 0.02", size=1.5)
    ax.set_title(f"Fig 4: bifurcation vs speed, Δ = 0 and 0.02 ({cap})", fontsize=9)
    ax.legend(markerscale=4, fontsize=8)
    save(fig, "fig04_bifurcation_speed_d0_d002.png")
    # Fig 5: LLE vs speed
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    plot_lle(ax, sweeps["speed_d0"], colour="tab:red", label="Δ = 0")
    plot_lle(ax, sweeps["speed_d0.02"], colour="black", label="Δ = 0.02")
    ax.set_title(f"Fig 5: largest Lyapunov exponent vs speed ({cap})", fontsize=9)
    ax.legend(fontsize=8)
    save(fig, "fig05_lle_speed_d0_d002.png")
    # Fig 9, 10
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    plot_bifurcation(ax, sweeps["speed_d0.1"], colour="tab:blue", label="Δ = 0.10", size=2)
    ax.set_title(f"Fig 9: bifurcation vs speed, Δ = 0.10 ({cap})", fontsize=9)
    save(fig, "fig09_bifurcation_speed_d010.png")
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    plot_lle(ax, sweeps["speed_d0.1"], colour="tab:blue", label="Δ = 0.10")
    ax.set_title(f"Fig 10: largest Lyapunov exponent vs speed, Δ = 0.10 ({cap})", fontsize=9)
    ax.legend(fontsize=8)
    save(fig, "fig10_lle_speed_d010.png")
    # Figs 6-8 / 11-13: orbits + Poincaré + spectrum
    orbit_pts = by_group["orbits"]
    ratios: dict[str, dict[str, dict[str, Any]]] = {}
    for i, v in enumerate(ORBIT_SPEEDS):
        fig, axes = plt.subplots(2, 3, figsize=(11, 6.5))
        for j, d in enumerate(SWEEP_DELTAS):
            p = orbit_pts[i * len(SWEEP_DELTAS) + j]
            if p.status != "ok" or p.waveform is None or p.waveform.shape[0] == 0:
                axes[0, j].text(0.5, 0.5, f"run ended: {p.status}", ha="center", transform=axes[0, j].transAxes)
                continue
            plot_orbit(axes[0, j], p, title=f"Δ = {d:g}, {v:g} r/min: {p.motion}")
            plot_spectrum(axes[1, j], p, plant.clearance_m, 128, s.orbit_record_revs)
            spec = np.abs(np.fft.rfft(p.waveform[:, 0])) * 2 / p.waveform.shape[0]
            r = s.orbit_record_revs
            ratios.setdefault(f"{v:g}", {})[f"{d:g}"] = dict(
                motion=p.motion, one_x_um=float(spec[r] * plant.clearance_m * 1e6),
                two_x_um=float(spec[2 * r] * plant.clearance_m * 1e6),
                three_x_um=float(spec[3 * r] * plant.clearance_m * 1e6),
                two_x_over_one_x=float(spec[2 * r] / spec[r]), three_x_over_one_x=float(spec[3 * r] / spec[r]),
                pkpk_x=float(np.ptp(p.waveform[:, 0])))
        fig.suptitle(f"Figs {6 + i} / {11 + i}: node-3 orbit (black), Poincaré points (red) and spectrum, "
                     f"{v:g} r/min ({cap})", fontsize=10)
        save(fig, f"fig{6 + i:02d}_orbits_{v:g}rpm.png")
    # Fig 14
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, v in zip(axes, DELTA_SWEEP_SPEEDS):
        plot_bifurcation(ax, sweeps[f"delta_{v:g}rpm"], colour="black", size=2)
        ax.set_title(f"Fig 14: bifurcation vs Δ at {v:g} r/min ({cap})", fontsize=9)
    save(fig, "fig14_bifurcation_misalignment.png")
    # Fig 15
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    plot_amplitudes(axes, {d: sweeps[f"speed_d{d:g}"] for d in AMPLITUDE_DELTAS})
    fig.suptitle(f"Fig 15: amplitude vs speed, horizontal, node 3 ({cap})", fontsize=10)
    save(fig, "fig15_amplitude_speed.png")

    summary = dict(
        settings=s.__dict__, plant=plant.to_dict(), wall_time_s=round(time.perf_counter() - start, 1),
        windows={name: motion_windows(sw) for name, sw in sweeps.items()},
        orders_at_orbit_speeds=ratios,
        amplitude_jumps={name: _largest_jump(sw) for name, sw in sweeps.items() if name.startswith("speed")},
        failed_points={name: int(np.sum(sw.status != "ok")) for name, sw in sweeps.items()},
        files=files,
    )
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def _largest_jump(sweep: SweepResult) -> dict:
    """Largest rise of peak-to-peak between neighbouring speeds (µm)."""
    c_um = sweep.clearance_m * 1e6
    pk = sweep.pkpk * c_um
    if pk.size < 2 or not np.any(np.isfinite(np.diff(pk))):
        return {}
    dk = np.nan_to_num(np.diff(pk), nan=-np.inf)
    k = int(np.argmax(dk))
    return dict(from_rpm=float(sweep.values[k]), to_rpm=float(sweep.values[k + 1]),
                pkpk_before_um=round(float(pk[k]), 2), pkpk_after_um=round(float(pk[k + 1]), 2))
