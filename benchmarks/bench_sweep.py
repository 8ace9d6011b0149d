"""Benchmark: wall time of a 50-point speed sweep, in-process vs Dask with 1 and 2 workers.

Baseline = what a user would write without rotordiag's sweep: a plain Python
loop over ``simulate`` in one process (``n_workers=0``). The sweep is the
paper's Fig 9 operating range (1200–3000 r/min, Δ = 0.10, A = 0.05, 400
transient + 128 recorded revolutions, rtol 1e-6), no Lyapunov exponent.

Run:  .venv/bin/python benchmarks/bench_sweep.py [--points 50] [--workers 1 2]
Prints wall time, points/s, speed-up vs the in-process loop, peak RSS, and
checks that every configuration produced bit-identical Poincaré points.

``--steady-start`` instead compares the two ways a point's record starts (issue 16 item 4),
in-process on one core: ``steady_start="integrate"`` with ``stiff_solver=False`` (400 transient
revolutions, Dormand–Prince throughout: the path before issue 16) vs the defaults (``"shooting"``
and the stiff hand-over to LSODA); it prints points/min of each and the ratio, overall
and over the points that took the shooting start, the largest Poincaré-point difference
there, and whether every point's motion label is equal. Add ``--misalignment-sweep`` for
the paper's Fig 14 Δ sweep at 1843 r/min as well.
"""
from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np


def main() -> None:
    from rotordiag.simulator import Plant
    from rotordiag.simulator.analysis import speed_sweep

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=50)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--steady-start", action="store_true", help="compare the shooting and integration starts")
    ap.add_argument("--misalignment-sweep", action="store_true", help="with --steady-start: also a Δ sweep")
    args = ap.parse_args()

    plant = Plant.default()
    if args.steady_start:
        compare_steady_start(plant, args.points, args.misalignment_sweep)
        return
    speeds = np.linspace(1200.0, 3000.0, args.points)
    kw = dict(transient_revs=400, record_revs=128, samples_per_rev=64, progress=False)
    print(f"{args.points}-point speed sweep 1200-3000 r/min, Δ=0.10, A=0.05, 400+128 rev, "
          f"{os.cpu_count()} CPUs visible, load avg {os.getloadavg()[0]:.2f}")

    # warm the numba cache in this process so the baseline is not charged compilation
    speed_sweep(plant, [1500.0], 0.1, 0.05, n_workers=0, **{**kw, "transient_revs": 1, "record_revs": 8})

    rows = []
    t0 = time.perf_counter()
    base = speed_sweep(plant, speeds, 0.1, 0.05, n_workers=0, **kw)
    t_base = time.perf_counter() - t0
    rows.append(("in-process loop (baseline)", t_base, base, 0))
    for w in args.workers:
        t0 = time.perf_counter()
        res = speed_sweep(plant, speeds, 0.1, 0.05, n_workers=w, **kw)
        rows.append((f"Dask LocalCluster, {w} worker(s)", time.perf_counter() - t0, res, w))

    print(f"{'configuration':34s} {'wall s':>8s} {'points/s':>9s} {'speed-up':>9s} {'identical':>9s} "
          f"{'sum point s':>11s} {'utilisation':>11s}")
    for name, t, res, n_workers in rows:
        same = np.array_equal(res.sections, base.sections, equal_nan=True)
        # sum of the per-point wall times: equal to the baseline's when every worker has a core
        # to itself; larger when the workers share cores with other load.  utilisation =
        # sum / (workers x wall): how busy the runner kept its workers
        print(f"{name:34s} {t:8.1f} {args.points / t:9.2f} {t_base / t:9.2f} {str(same):>9s} "
              f"{res.wall_time_s.sum():11.1f} {res.wall_time_s.sum() / (t * max(n_workers, 1)):11.2f}")
    print(f"load average after the runs: {os.getloadavg()[0]:.2f}")
    print(f"sum of per-point simulate times (baseline): {base.wall_time_s.sum():.1f} s; "
          f"slowest point {base.wall_time_s.max():.1f} s at {base.speed_rpm[base.wall_time_s.argmax()]:.0f} r/min")
    me = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"peak RSS: this process {me:.0f} MiB, largest worker process {kids:.0f} MiB")


def compare_steady_start(plant, n_points: int, with_delta: bool) -> None:
    from rotordiag.simulator.analysis import misalignment_sweep, speed_sweep

    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    kw = dict(transient_revs=400, record_revs=128, samples_per_rev=64, progress=False, n_workers=0)
    speed_sweep(plant, [1500.0], 0.1, 0.05, **{**kw, "transient_revs": 30, "record_revs": 8})  # compile
    cases = [(f"speed 1200-3000 r/min, pin Δ=0.10 ({n_points} pts)",
              lambda start, stiff: speed_sweep(plant, np.linspace(1200.0, 3000.0, n_points), 0.1, 0.05,
                                               steady_start=start, stiff_solver=stiff, **kw))]
    if with_delta:
        cases.append((f"Δ 0-0.6 at 1843 r/min, pin ({n_points} pts)",
                      lambda start, stiff: misalignment_sweep(plant, 1843.0, np.linspace(0.0, 0.6, n_points), 0.05,
                                                              steady_start=start, stiff_solver=stiff, **kw)))
    print(f"sweep steady start, in-process on one core, 400 transient + 128 recorded revs; "
          f"load {os.getloadavg()[0]:.2f}")
    print(f"{'sweep':<42}{'integrate /min':>15}{'shooting /min':>14}{'x':>6}{'shot':>7}{'x period-1':>11}"
          f"{'max |dpc|':>10}{'motion equal':>13}")
    for name, fn in cases:
        t0 = time.perf_counter()
        a = fn("integrate", False)  # before issue 16: 400 revolutions, Dormand–Prince throughout
        ta = time.perf_counter() - t0
        t0 = time.perf_counter()
        b = fn("shooting", True)  # the default now
        tb = time.perf_counter() - t0
        shot = b.steady_start == "shooting"
        dpc = float(np.nanmax(np.abs(a.poincare[shot] - b.poincare[shot]))) if shot.any() else float("nan")
        p1 = a.wall_time_s[shot].sum() / max(b.wall_time_s[shot].sum(), 1e-9)
        print(f"{name:<42}{60 * n_points / ta:>15.1f}{60 * n_points / tb:>14.1f}{ta / tb:>6.2f}"
              f"{f'{shot.sum()}/{n_points}':>7}{p1:>11.2f}{dpc:>10.1e}{str(bool(np.all(a.motion == b.motion))):>13}")
    print("(integrate: 400 transient revolutions, Dormand-Prince throughout: the path before issue 16; shooting: "
          "the default now, the shooting start where it converges and the stiff hand-over to LSODA; max |dpc|: "
          "largest difference of the Poincaré points X = x/c of the points that took the shooting start; x period-1: "
          "sum of their per-point times, integrate / shooting)")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS {rss:.0f} MiB")


if __name__ == "__main__":
    main()
