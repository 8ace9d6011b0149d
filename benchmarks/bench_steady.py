"""Benchmark: one period-1 steady state by brute force vs by shooting (issue 16).

Default plant, A = 0.05, 1950 r/min, rtol 1e-6, one core; `pin` Δ = 0.02 (the paper's
case), `rigid` Δ = 0.1 and `aligned`. Per point, best of 5:

* brute: ``simulate`` with 400 transient revolutions + 1 recorded (today's dataset/sweep path);
* brute+settle: the same with ``settle_tol=1e-8`` (the early transient end sweeps may use);
* newton: ``steady_state(method="newton")`` from MODEL.md's start (warm-up, then Newton with a
  monodromy matrix per iteration: the first implementation);
* shoot (cold): ``steady_state`` from MODEL.md's start (settling warm-up of at most 40
  revolutions, then chord iterations on one rtol-1e-3 monodromy matrix, then the exact
  monodromy matrix at the fixed point for the Floquet multipliers);
* start: ``steady_start`` (what dataset samples and sweep points run: the same without the
  exact final matrix; multipliers from the chord matrix);
* shoot (warm): ``steady_state`` from a neighbouring orbit's state (1 r/min away, no warm-up):
  what a continuation step pays.

Prints ms per point, the ratio to brute force, Newton iterations, the difference to the
brute-force state (non-dimensional) and peak RSS. Run: `python benchmarks/bench_steady.py`.
"""
from __future__ import annotations

import os
import resource
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from rotordiag.simulator import Plant, simulate  # noqa: E402
from rotordiag.simulator.steady import RotorMap, steady_state  # noqa: E402
from rotordiag.simulator.steady.start import steady_start  # noqa: E402
from rotordiag.simulator.system import RotorSystem  # noqa: E402

SPEED, A = 1950.0, 0.05
CASES = (("pin", 0.02), ("rigid", 0.1), ("aligned", 0.0))


def best_of(fn, n=5):
    times = []
    for _ in range(n):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    try:
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    except (AttributeError, OSError):
        pass
    plant = Plant.default()
    print(f"steady-state period-1 point, default plant, A = {A}, {SPEED:g} r/min, rtol 1e-6, one core (best of 5)")
    print(f"{'case':<14}{'brute ms':>10}{'settle ms':>11}{'newton ms':>10}{'cold ms':>9}{'x':>6}{'start ms':>9}"
          f"{'x':>6}{'warm ms':>9}{'x':>6}{'iters':>7}{'|diff|':>10}{'start|diff|':>12}{'max|mu|':>9}")
    for mech, delta in CASES:
        steady_state(plant, SPEED, delta, A, mechanism=mech)  # compile
        t_b, brute = best_of(lambda: simulate(plant, SPEED, delta, A, mechanism=mech, transient_revs=400,
                                              record_revs=1))
        t_s, _ = best_of(lambda: simulate(plant, SPEED, delta, A, mechanism=mech, transient_revs=400,
                                          record_revs=1, settle_tol=1e-8))
        t_n, _ = best_of(lambda: steady_state(plant, SPEED, delta, A, mechanism=mech, method="newton"))
        t_c, cold = best_of(lambda: steady_state(plant, SPEED, delta, A, mechanism=mech))
        system = RotorSystem(plant, SPEED, delta, A, mechanism=mech)
        t_st, st = best_of(lambda: steady_start(system, 400))
        near = steady_state(plant, SPEED - 1.0, delta, A, mechanism=mech)
        t_w, warm = best_of(lambda: steady_state(plant, SPEED, delta, A, mechanism=mech, initial_state=near.state,
                                                 warmup_revs=0, period=1))
        pmap = RotorMap(RotorSystem(plant, SPEED, delta, A, mechanism=mech))
        diff = float(np.max(np.abs(pmap.difference(pmap.reduce(cold.state), pmap.reduce(brute.final_state)))))
        sdiff = float(np.max(np.abs(pmap.difference(pmap.reduce(st.state), pmap.reduce(brute.final_state)))))
        assert st.path == "shooting", st.note
        print(f"{mech + f' Δ={delta:g}':<14}{t_b * 1e3:>10.1f}{t_s * 1e3:>11.1f}{t_n * 1e3:>10.1f}{t_c * 1e3:>9.1f}"
              f"{t_b / t_c:>6.1f}{t_st * 1e3:>9.1f}{t_b / t_st:>6.1f}"
              f"{t_w * 1e3:>9.1f}{t_b / t_w:>6.1f}{cold.iterations:>4}/{warm.iterations:<2}{diff:>10.1e}"
              f"{sdiff:>12.1e}{cold.max_multiplier:>9.4f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS {rss:.0f} MiB")


if __name__ == "__main__":
    main()
