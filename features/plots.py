"""Rendering of the transient plots (issue 46): Bode, polar, waterfall, full spectrum, shaft centreline, orbits,
Campbell — matplotlib figures from the data of :mod:`rotordiag.features.transient` (and
:mod:`rotordiag.simulator.campbell`). Nothing here computes a vibration quantity; every figure carries the
conventions (:func:`~rotordiag.features.transient.conventions`, lengths in µm or mil) in its footer.

:func:`transient_figures` builds them all; :func:`save_figures` writes PNGs (each to a temporary name first, then
renamed, so a failure leaves no half-written file).
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rotordiag.core.units import factor_to_um

from .transient import (
    Centreline,
    Orbit,
    OrderTrack,
    Waterfall,
    centreline,
    conventions,
    full_spectrum,
    orbits_at,
    waterfall,
)

__all__ = ["bode_figure", "polar_figure", "waterfall_figure", "centreline_figure", "orbits_figure",
           "campbell_figure", "transient_figures", "save_figures"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _footer(fig: Any, extra: str = "", units: str = "um") -> None:
    fig.text(0.01, 0.005, conventions(units) + (f"; {extra}" if extra else ""), fontsize=7, color="0.3", ha="left",
             va="bottom", wrap=True)


def _units(units: str) -> tuple[float, str]:
    """(factor from µm, label) of the plot's length unit: ``um`` or ``mil`` (1 mil = 25.4 µm)."""
    if units not in ("um", "mil"):
        raise ValueError(f"units must be 'um' or 'mil', got {units!r}")
    return (1.0, "µm") if units == "um" else (1.0 / factor_to_um("mil"), "mil")


def _probe_label(p: tuple[int, float]) -> str:
    return f"b{p[0]}@{p[1]:g}°"


def bode_figure(track: OrderTrack, probes: list[int] | None = None, title: str = "", units: str = "um") -> Any:
    """Amplitude (µm or mil pk-pk) and phase lag (°) against speed for each order (columns) and probe (lines)."""
    plt = _plt()
    f_u, u = _units(units)
    probes = list(range(len(track.probes))) if probes is None else probes
    n_o = len(track.orders)
    fig, axes = plt.subplots(2, n_o, figsize=(6.5 * n_o, 7.5), sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [1, 1.2]})
    # vectors that cannot be read (speed in doubt, non-synchronous vibration swamping the orders) are gaps, not bridged
    ok = track.readable()
    amp = np.where(ok, track.amp_um_pp, np.nan) * f_u
    ph = np.where(ok, track.phase_lag_deg, np.nan)
    for j, k in enumerate(track.orders):
        for p in probes:
            axes[1, j].plot(track.speed_rpm, amp[:, p, j], lw=1.0, label=_probe_label(track.probes[p]))
            if track.phase_referenced:
                lag = ph[:, p, j].copy()
                lag[1:][np.abs(np.diff(lag)) > 180.0] = np.nan  # no line across the 0/360° wrap
                axes[0, j].plot(track.speed_rpm, lag, lw=1.0)
        axes[1, j].set_ylabel(f"{k}X amplitude ({u} pk-pk)")
        axes[1, j].set_xlabel("speed (r/min)")
        axes[0, j].set_ylabel(f"{k}X phase lag (°)")
        axes[0, j].set_ylim(360, 0)   # lag grows downward, the vibration engineer's Bode
        axes[0, j].set_yticks(range(0, 361, 90))
        if not track.phase_referenced:
            axes[0, j].text(0.5, 0.5, "no keyphasor: phase not referenced", ha="center", va="center",
                            transform=axes[0, j].transAxes, color="0.4")
        axes[0, j].set_title(f"{k}X Bode")
        axes[0, j].grid(alpha=0.3)
        axes[1, j].grid(alpha=0.3)
    axes[1, 0].legend(fontsize=7, ncol=2)
    fig.suptitle(title or f"Bode plot ({track.kind}, speed from {track.speed_source})")
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.10, top=0.93, hspace=0.35, wspace=0.35)
    _footer(fig, "", units)
    return fig


def polar_figure(track: OrderTrack, probes: list[int] | None = None, order: int = 1, title: str = "",
                 units: str = "um") -> Any:
    """The kX vector (µm pk-pk, phase lag) of each probe as speed changes: phase lag measured from the top of
    the plot against the direction of rotation (clockwise on the page), speeds labelled along the path."""
    plt = _plt()
    f_u, u = _units(units)
    if not track.phase_referenced:
        raise ValueError("a polar plot needs phase lags: the recording has no keyphasor")
    probes = list(range(len(track.probes))) if probes is None else probes
    j = track.orders.index(order)
    n = len(probes)
    cols = min(4, n)
    rows = int(np.ceil(n / cols))
    fig = plt.figure(figsize=(3.6 * cols, 3.9 * rows + 0.6))
    keep = ~track.in_doubt
    sp = track.speed_rpm[keep]
    for i, p in enumerate(probes):
        ax = fig.add_subplot(rows, cols, i + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        ok = track.readable()[keep, p, j]
        lag = np.radians(np.where(ok, track.phase_lag_deg[keep, p, j], np.nan))
        a = np.where(ok, track.amp_um_pp[keep, p, j], np.nan) * f_u
        ax.plot(lag, a, lw=0.8)
        fin = np.flatnonzero(np.isfinite(a))
        for s in (np.linspace(sp[fin].min(), sp[fin].max(), 5) if fin.size else ()):
            q = int(fin[np.argmin(np.abs(sp[fin] - s))])
            ax.plot(lag[q], a[q], "o", ms=3, color="C3")
            ax.annotate(f"{sp[q]:.0f}", (lag[q], a[q]), fontsize=6)
        ax.set_title(f"{_probe_label(track.probes[p])} {order}X", fontsize=9)
        ax.tick_params(labelsize=6)
    fig.suptitle(title or f"Polar plot {order}X ({u} pk-pk at phase lag; points labelled r/min)")
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.11, top=0.90, hspace=0.35, wspace=0.35)
    _footer(fig, "phase lag clockwise from the top", units)
    return fig


CASCADE_SCALES = ("linear", "db", "row")
"""Trace heights of a cascade: ``linear`` (∝ amplitude, one scale for the plot), ``db`` (dB below the plot's largest
line, the bottom ``CASCADE_DB_RANGE`` dB shown), ``row`` (each trace scaled to its own largest line)."""
CASCADE_DB_RANGE = 60.0


def _cascade_heights(a: np.ndarray, scale: str) -> tuple[np.ndarray, str]:
    """Trace heights in [0, 1] (1 = six rows of height) for amplitudes ``a`` (rows × frequencies), and the words
    that say on the plot what the height means."""
    if scale not in CASCADE_SCALES:
        raise ValueError(f"cascade scale {scale!r} is not one of {', '.join(CASCADE_SCALES)}")
    top = max(float(a.max()), 1e-12)
    if scale == "linear":
        return a / top, "height ∝ amplitude"
    if scale == "db":
        db = 20.0 * np.log10(np.maximum(a, top * 1e-12) / top)
        return np.clip((db + CASCADE_DB_RANGE) / CASCADE_DB_RANGE, 0.0, 1.0), \
            f"height: dB below the largest line ({CASCADE_DB_RANGE:.0f} dB shown)"
    row_top = np.maximum(a.max(axis=1, keepdims=True), 1e-12)
    return a / row_top, "height: each trace to its own largest line"


def waterfall_figure(wf: Waterfall, max_order: float = 3.5, title: str = "", units: str = "um",
                     scale: str = "db") -> Any:
    """A cascade: each window's spectrum drawn at its speed, with the 1X and 2X (and −1X for a full spectrum)
    lines; amplitude µm (or mil) pk-pk. ``scale`` (:data:`CASCADE_SCALES`, stated on the plot): the default ``db``
    keeps the low-speed lines visible beside a whip line hundreds of times larger; ``row`` shows each speed's shape
    alone; ``linear`` the amplitudes on one scale."""
    plt = _plt()
    f_u, u = _units(units)
    fig, ax = plt.subplots(figsize=(9, 7))
    f_hi = max_order * wf.speed_rpm.max() / 60.0
    sel = (np.abs(wf.frequencies_hz) <= f_hi) if wf.full else (wf.frequencies_hz <= f_hi)
    f = wf.frequencies_hz[sel]
    a = wf.amp_um_pp[:, sel] * f_u
    heights, meaning = _cascade_heights(a, scale)
    step = np.median(np.diff(wf.speed_rpm)) if wf.speed_rpm.size > 1 else 1.0
    span = abs(step) * 6.0
    from matplotlib.collections import PolyCollection

    # the highest speed first, so each lower (nearer) trace hides what lies behind it
    order_idx = np.argsort(wf.speed_rpm)[::-1]
    verts = []
    for i in order_idx:
        top = wf.speed_rpm[i] + heights[i] * span
        verts.append(np.column_stack([np.r_[f, f[::-1]], np.r_[top, np.full(f.size, wf.speed_rpm[i])]]))
    ax.add_collection(PolyCollection(verts, facecolors="white", edgecolors="C0", linewidths=0.6))
    ax.set_xlim(f.min(), f.max())
    ax.set_ylim(wf.speed_rpm.min() - abs(step), wf.speed_rpm.max() + abs(step) * 7)
    sp = np.sort(wf.speed_rpm)
    for k, style in ((1, "C3--"), (2, "C2--")):
        ax.plot(k * sp / 60.0, sp, style, lw=0.8, label=f"{k}X", zorder=1000)
        if wf.full:
            ax.plot(-k * sp / 60.0, sp, style, lw=0.5, zorder=1000)
    if wf.full:
        ax.axvline(0, color="0.5", lw=0.5)
        ax.text(0.98, 0.98, "forward →", transform=ax.transAxes, ha="right", va="top")
        ax.text(0.02, 0.98, "← reverse", transform=ax.transAxes, ha="left", va="top")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"speed (r/min); trace {meaning}", fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    peak = float(a.max())
    what = {"linear": f" = {span:.0f} r/min of height", "db": f" = 0 dB = {span:.0f} r/min of height",
            "row": "; each trace to its own largest line"}[scale]
    ax.set_title(title or f"{'Full-spectrum cascade' if wf.full else 'Waterfall'} — {wf.label} "
                 f"(largest line {peak:.{2 if units == 'mil' else 1}f} {u} pk-pk{what})", fontsize=11)
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.10, top=0.93, hspace=0.35, wspace=0.35)
    base = "Hann window; x + jy: forward whirl (+x → +y) at positive frequencies" if wf.full else "Hann window"
    _footer(fig, base, units)
    return fig


def centreline_figure(cl: Centreline, title: str = "", units: str = "um") -> Any:
    """Each bearing's mean journal position per revolution, coloured by speed, inside its clearance circle."""
    plt = _plt()
    f_u, u = _units(units)
    n = len(cl.bearings)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 4.8), squeeze=False)
    for i, b in enumerate(cl.bearings):
        ax = axes[0, i]
        sc = ax.scatter(cl.x_um[:, i] * f_u, cl.y_um[:, i] * f_u, c=cl.speed_rpm, s=4, cmap="viridis")
        ax.plot(cl.x_um[0, i] * f_u, cl.y_um[0, i] * f_u, "k^", ms=6, label="start")
        c = cl.clearance_um.get(b)
        if c:
            c = c * f_u
            t = np.linspace(0, 2 * np.pi, 200)
            ax.plot(c * np.cos(t), c * np.sin(t), "k--", lw=0.7, label=f"clearance {c:.4g} {u}")
            ax.set_xlim(-1.1 * c, 1.1 * c)
            ax.set_ylim(-1.1 * c, 1.1 * c)
        ax.axhline(0, color="0.8", lw=0.5)
        ax.axvline(0, color="0.8", lw=0.5)
        ax.set_aspect("equal")
        ax.set_title(f"bearing {b}")
        ax.set_xlabel(f"x horizontal ({u})")
        ax.set_ylabel(f"y vertical ({u})")
        ax.legend(fontsize=7, loc="upper right")
    fig.colorbar(sc, ax=axes[0, -1], label="speed (r/min)", shrink=0.8)
    fig.suptitle(title or f"Shaft centreline (position {cl.reference})")
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.11, top=0.93, hspace=0.35, wspace=0.35)
    _footer(fig, "mean position per revolution", units)
    return fig


def orbits_figure(orbits: list[Orbit], title: str = "", units: str = "um") -> Any:
    """Orbits (raw, grey; 1X-filtered, blue; keyphasor dot) of each bearing (columns) at each speed (rows)."""
    plt = _plt()
    f_u, u = _units(units)
    bearings = sorted({o.bearing for o in orbits})
    speeds = sorted({round(o.speed_rpm, 3) for o in orbits})
    fig, axes = plt.subplots(len(speeds), len(bearings), figsize=(3.3 * len(bearings), 3.3 * len(speeds) + 0.5),
                             squeeze=False)
    for o in orbits:
        ax = axes[speeds.index(round(o.speed_rpm, 3)), bearings.index(o.bearing)]
        ax.plot(o.x_um * f_u, o.y_um * f_u, color="0.6", lw=0.7)
        ax.plot(o.x1_um * f_u, o.y1_um * f_u, color="C0", lw=1.0)
        if o.mark_um is not None:
            ax.plot(o.mark_um[0] * f_u, o.mark_um[1] * f_u, "ko", ms=4)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"bearing {o.bearing} at {o.speed_rpm:.0f} r/min", fontsize=8)
        ax.tick_params(labelsize=6)
        ax.set_xlabel(f"x ({u})", fontsize=7)
        ax.set_ylabel(f"y ({u})", fontsize=7)
    fig.suptitle(title or "Orbits over one revolution (grey raw, blue 1X, dot: keyphasor mark)")
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.11, top=0.90, hspace=0.35, wspace=0.35)
    _footer(fig, "rotation +x → +y (counter-clockwise on the page)", units)
    return fig


def campbell_figure(speeds_rpm: np.ndarray, frequencies_hz: np.ndarray, damping_ratios: np.ndarray,
                    criticals: Sequence[Any] = (), measured_peaks: Sequence[dict] = (), title: str = "") -> Any:
    """Damped natural frequencies of the plant model against speed (colour: damping ratio), the 1X and 2X
    lines, the model's critical speeds (○) and the measured 1X/2X peaks (×)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8.5, 6))
    zmax = 0.3
    for m in range(frequencies_hz.shape[1]):
        sc = ax.scatter(speeds_rpm, frequencies_hz[:, m], c=np.clip(damping_ratios[:, m], -0.05, zmax), s=8,
                        cmap="coolwarm_r", vmin=-0.05, vmax=zmax)
    for k, st in ((1, "k-"), (2, "k--")):
        ax.plot(speeds_rpm, k * speeds_rpm / 60.0, st, lw=0.8, label=f"{k}X")
    for c in criticals:
        ax.plot(c.speed_rpm, c.frequency_hz, "o", mfc="none", mec="k", ms=9)
    if criticals:
        ax.plot([], [], "o", mfc="none", mec="k", label="model critical (AF ≥ 2.5)")
    for p in measured_peaks:
        ax.plot(p["speed_rpm"], p["order"] * p["speed_rpm"] / 60.0, "x", color="C3", ms=8, mew=1.5)
    if measured_peaks:
        ax.plot([], [], "x", color="C3", label="measured peak")
    fig.colorbar(sc, ax=ax, label="damping ratio ζ (< 0: unstable)")
    ax.set_xlabel("speed (r/min)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_ylim(0, min(float(frequencies_hz.max()) * 1.05, 2.6 * speeds_rpm.max() / 60.0))
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title or "Campbell diagram of the plant model (linearised about the static equilibrium)")
    fig.subplots_adjust(left=0.08, right=0.95, bottom=0.15, top=0.93, hspace=0.35, wspace=0.35)
    _footer(fig)
    return fig


def transient_figures(rec: Any, track: OrderTrack, *, orbit_speeds_rpm: list[float] | None = None,
                      plant: Any = None, centreline_reference: str = "as recorded", units: str = "um",
                      cascade_scale: str = "db") -> dict[str, Any]:
    """Every plot of a start-up or coast-down as {name: Figure}: ``bode``, ``polar`` (keyphasor only),
    ``waterfall_b<bearing>`` (first probe of each bearing), ``full_spectrum_b<bearing>``, ``centreline`` (DC-coupled
    only), ``orbits``, ``campbell`` (with ``plant``: the plant model's Campbell over the run's speeds);
    ``cascade_scale`` is the cascades' trace height (:data:`CASCADE_SCALES`)."""
    _units(units)
    _cascade_heights(np.zeros((1, 1)), cascade_scale)
    figs: dict[str, Any] = {"bode": bode_figure(track, units=units)}
    if track.phase_referenced:
        figs["polar"] = polar_figure(track, units=units)
    for b in rec.bearings:
        first = next(i for i, c in enumerate(rec.channels) if c.bearing == b)
        figs[f"waterfall_b{b}"] = waterfall_figure(waterfall(rec, track, first), units=units, scale=cascade_scale)
        figs[f"full_spectrum_b{b}"] = waterfall_figure(full_spectrum(rec, track, b), units=units,
                                                           scale=cascade_scale)
    if not rec.dc_removed:
        figs["centreline"] = centreline_figure(centreline(rec, track, reference=centreline_reference), units=units)
    keep = ~track.in_doubt
    lo, hi = float(track.speed_rpm[keep].min()), float(track.speed_rpm[keep].max())
    speeds = orbit_speeds_rpm if orbit_speeds_rpm else [lo + f * (hi - lo) for f in (0.1, 0.5, 0.9)]
    figs["orbits"] = orbits_figure(orbits_at(rec, track, speeds), units=units)
    if plant is not None:
        from rotordiag.simulator.campbell import campbell, critical_speeds
        from rotordiag.simulator.params import SPEED_RANGE_RPM

        grid = np.linspace(max(SPEED_RANGE_RPM[0], lo * 0.8), min(SPEED_RANGE_RPM[1], hi * 1.1), 60)
        cd = campbell(plant, grid)
        figs["campbell"] = campbell_figure(cd.speeds_rpm, cd.frequencies_hz, cd.damping_ratios,
                                           critical_speeds(cd, (1, 2)), track.peaks(1) + track.peaks(2))
    return figs


def save_figures(figs: dict[str, Any], out_dir: str | Path, *, dpi: int = 100, close: bool = True) -> list[Path]:
    """Write each figure as ``<out_dir>/<name>.png`` (temporary name, then renamed); returns the paths."""
    plt = _plt()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    umask = os.umask(0)
    os.umask(umask)
    try:
        for name, fig in figs.items():
            fd, tmp = tempfile.mkstemp(suffix=".png", dir=out, prefix=f".{name}.")
            os.close(fd)
            try:
                fig.savefig(tmp, dpi=dpi)
                os.chmod(tmp, 0o666 & ~umask)  # mkstemp's 0600 → what a plain open() would give
                os.replace(tmp, out / f"{name}.png")
            finally:
                if os.path.exists(tmp):
                    os.unlink(tmp)
            paths.append(out / f"{name}.png")
    finally:
        if close:
            for fig in figs.values():
                plt.close(fig)
    return paths
