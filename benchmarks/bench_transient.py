"""Start-up tracking and plotting speed (issue 46, item 6): a 60-s start-up of 8 probes at 25.6 kHz tracked and
plotted on one core, with the time per stage.

The recording: the paper's model (Δ = 0.3 pin, A = 0.05) run up 100 → 3000 r/min in 60 s by
``simulator.transient`` at 2560 Hz (not timed in the budget; printed), its journal displacements interpolated to
25.6 kHz (cubic spline in time), projected on 8 probes (bearings 1–4 at 45°/135°), 40 dB noise (seed 0), the
simulator's keyphasor marks. Stages timed: order tracking (1X/2X per revolution, keyphasor), the waterfall and
full-spectrum data of every bearing, the centreline and orbits, rendering the figures, writing the PNGs. Both the
wall time and the process CPU time are printed (on a shared machine the CPU time is the one that measures the code).

    python benchmarks/bench_transient.py [--out-dir DIR] [--no-keyphasor-too]
"""
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from rotordiag.features import ProbeChannel, Recording
from rotordiag.features import plots as P
from rotordiag.features import transient as T
from rotordiag.simulator import Plant
from rotordiag.simulator.transient import DEFAULT_CHANNELS, SpeedProfile, simulate_transient

FS = 25_600.0
BUDGET_S = 5.0


def startup_recording(seed: int = 0) -> tuple[Recording, float]:
    """The 60-s, 8-probe, 25.6-kHz start-up (see the module docstring); returns it and the simulation's wall time."""
    from scipy.interpolate import CubicSpline

    t0 = time.perf_counter()
    res = simulate_transient(Plant.default(), SpeedProfile.linear(100, 3000, 60), 0.3, 0.05, sample_rate_hz=2560,
                             settle_revs=100)
    sim_s = time.perf_counter() - t0
    if not res.ok:
        raise RuntimeError(res.message)
    t = np.arange(int(res.time_s[-1] * FS)) / FS
    d = CubicSpline(res.time_s, res.journal_displacements_m.reshape(-1, 8) * 1e6, axis=0)(t).reshape(-1, 4, 2)
    rng = np.random.default_rng(seed)
    chans = []
    for b, a in DEFAULT_CHANNELS:
        x = d[:, b - 1, 0] * np.cos(np.radians(a)) + d[:, b - 1, 1] * np.sin(np.radians(a))
        x = x + rng.standard_normal(x.size) * np.sqrt(x.var() / 1e4)
        chans.append(ProbeChannel(b, a, "um", x))
    kp = res.keyphasor_times_s[(res.keyphasor_times_s > 0) & (res.keyphasor_times_s <= t[-1])]
    return Recording(sample_rate_hz=FS, channels=chans, keyphasor_times_s=kp, clearance_um=res.clearance_m * 1e6), sim_s


class Stages:
    def __init__(self) -> None:
        self.rows: list[tuple[str, float, float]] = []

    def run(self, name: str, fn):
        w, c = time.perf_counter(), time.process_time()
        out = fn()
        self.rows.append((name, time.perf_counter() - w, time.process_time() - c))
        return out

    def report(self, title: str) -> tuple[float, float]:
        print(f"\n{title}")
        print(f"{'stage':<34}{'wall s':>9}{'cpu s':>9}")
        for name, w, c in self.rows:
            print(f"{name:<34}{w:9.3f}{c:9.3f}")
        tw, tc = sum(r[1] for r in self.rows), sum(r[2] for r in self.rows)
        print(f"{'total':<34}{tw:9.3f}{tc:9.3f}   (budget {BUDGET_S:g} s: {'met' if tc <= BUDGET_S else 'NOT met'} "
              f"on CPU time, {'met' if tw <= BUDGET_S else 'not met'} on wall time)")
        return tw, tc


def track_and_plot(rec: Recording, out_dir: Path, title: str) -> tuple[float, float]:
    st = Stages()
    track = st.run("track 1X/2X per revolution", lambda: T.track_orders(rec))
    wfs = st.run("waterfall + full spectrum data", lambda: (
        [T.waterfall(rec, track, next(i for i, c in enumerate(rec.channels) if c.bearing == b)) for b in rec.bearings],
        [T.full_spectrum(rec, track, b) for b in rec.bearings]))
    lo, hi = float(track.speed_rpm.min()), float(track.speed_rpm.max())
    cl, orb = st.run("centreline + orbits data", lambda: (
        T.centreline(rec, track), T.orbits_at(rec, track, [lo + f * (hi - lo) for f in (0.1, 0.5, 0.9)])))

    def render():
        figs = {"bode": P.bode_figure(track)}
        if track.phase_referenced:
            figs["polar"] = P.polar_figure(track)
        for b, w, f in zip(rec.bearings, *wfs):
            figs[f"waterfall_b{b}"] = P.waterfall_figure(w)
            figs[f"full_spectrum_b{b}"] = P.waterfall_figure(f)
        figs["centreline"] = P.centreline_figure(cl)
        figs["orbits"] = P.orbits_figure(orb)
        return figs

    figs = st.run("render figures", render)
    paths = st.run(f"write {len(figs)} PNGs", lambda: P.save_figures(figs, out_dir))
    tw, tc = st.report(f"{title}: {track.kind} {lo:.0f}–{hi:.0f} r/min, {track.speed_rpm.size} revolutions, "
                       f"{len(paths)} PNGs in {out_dir}")
    for n in track.notes:
        print(f"  note: {n}")
    return tw, tc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", type=Path, default=None)
    ap.add_argument("--no-keyphasor-too", action="store_true", help="also time the tracking without the keyphasor")
    args = ap.parse_args()
    rec, sim_s = startup_recording()
    print(f"recording: {len(rec.channels)} probes × {rec.n_points} samples at {FS:g} Hz "
          f"({rec.n_points / FS:.1f} s); simulated in {sim_s:.1f} s (not in the budget)")
    out = args.out_dir or Path(tempfile.mkdtemp(prefix="bench_transient_"))
    track_and_plot(rec, out, "with keyphasor")
    if args.no_keyphasor_too:
        from dataclasses import replace

        track_and_plot(replace(rec, keyphasor_times_s=None), out / "no_keyphasor", "speed from the signal")


if __name__ == "__main__":
    main()
