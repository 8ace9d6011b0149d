"""Benchmark of one steady-state run (issue 2's reference case).

400 transient + 128 recorded revolutions, rtol 1e-6, `pin`, Δ = 0.1, A = 0.05,
1950 r/min, on one core. Compares the numba Dormand–Prince integrator with
scipy.integrate.solve_ivp(RK45) on (a) a plain NumPy right-hand side (what a
user would write: tests/reference/rotor_numpy.py, timed over fewer revolutions
and scaled) and (b) the compiled right-hand side. Prints absolute figures,
ratios, steps and RHS evaluations per revolution, ns per RHS evaluation, and
the optional early end of the transient. Run: `python benchmarks/bench_simulator.py`.
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
from scipy.integrate import solve_ivp  # noqa: E402

from rotordiag.simulator import Plant, build_system, simulate  # noqa: E402
from rotordiag.simulator import _kernels as K  # noqa: E402
from tests.reference.rotor_numpy import ReferenceRotor  # noqa: E402

SPEED, DELTA, A = 1950.0, 0.1, 0.05
TRANSIENT, RECORD = 400, 128
REVS = TRANSIENT + RECORD


def best_of(fn, n=3):
    times = []
    for _ in range(n):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    plant = Plant.default()
    simulate(plant, SPEED, DELTA, A, transient_revs=2, record_revs=1)  # JIT warm-up / cache load
    t_numba, res = best_of(lambda: simulate(plant, SPEED, DELTA, A, transient_revs=TRANSIENT, record_revs=RECORD))
    print(f"numba DOPRI5 steady-state run ({TRANSIENT}+{RECORD} rev): {t_numba:.3f} s  status={res.status}")
    print(f"  accepted steps/rev {res.n_accepted / REVS:.1f}, rejected/rev {res.n_rejected / REVS:.2f}, "
          f"RHS evals/rev {res.nfev / REVS:.0f}")

    system = build_system(plant, SPEED, DELTA, A)
    y = system.initial_state()
    p = system.params
    dy = np.empty_like(y)
    n_eval = 500_000
    _rhs_loop(y, p, dy, 10)  # compile
    t0 = time.perf_counter()
    _rhs_loop(y, p, dy, n_eval)
    ns_rhs = (time.perf_counter() - t0) / n_eval * 1e9
    print(f"  compiled RHS: {ns_rhs:.0f} ns per evaluation (≈{ns_rhs * res.nfev / 1e9:.3f} s of the run)")

    # scipy solve_ivp(RK45) on the compiled RHS, τ units, same tolerances: full run
    y0 = system.initial_state()
    t_end = 2 * np.pi * REVS
    t_sc, sol = best_of(lambda: solve_ivp(lambda t, s: K.rhs_alloc(t, s, p), (0, t_end), y0, method="RK45",
                                          rtol=1e-6, atol=1e-8), n=1)
    print(f"solve_ivp RK45 + compiled RHS ({REVS} rev): {t_sc:.2f} s  (nfev {sol.nfev}, status {sol.status})")

    # scipy solve_ivp(RK45) on a plain NumPy RHS (SI units): fewer revolutions, scaled
    ref = ReferenceRotor(plant.to_dict(), SPEED, DELTA, A, "pin")
    n_ref = 20
    w = ref.w
    atol_si = np.concatenate([np.full(10, 1e-8 * ref.c), [1e-8], np.full(10, 1e-8 * ref.c * w), [1e-8 * w]])
    t_np, sol_np = best_of(lambda: solve_ivp(ref, (0, 2 * np.pi * n_ref / w), ref.to_si(y0), method="RK45",
                                             rtol=1e-6, atol=atol_si), n=1)
    t_np_scaled = t_np * REVS / n_ref
    print(f"solve_ivp RK45 + NumPy RHS: {t_np:.2f} s for {n_ref} rev -> scaled to {REVS} rev: {t_np_scaled:.1f} s"
          f"  (nfev/rev {sol_np.nfev / n_ref:.0f})")

    print(f"ratio vs solve_ivp + NumPy RHS:    {t_np_scaled / t_numba:7.0f}x   (target >= 100x)")
    print(f"ratio vs solve_ivp + compiled RHS: {t_sc / t_numba:7.1f}x   (target >= 15x)")
    print(f"per steady-state run: {t_numba:.3f} s (target <= 0.3 s)")
    t_early, early = best_of(lambda: simulate(plant, SPEED, DELTA, A, transient_revs=TRANSIENT, record_revs=RECORD,
                                              settle_tol=1e-6))
    used = early.inputs["transient_revs_used"]
    print(f"early transient end (settle_tol 1e-6): {t_early:.3f} s, transient {used} rev instead of {TRANSIENT}; "
          f"speed-up {t_numba / t_early:.1f}x")
    print("cost per steady-state run of every mechanism (same run, Δ = 0.1; offset downward, offset+α with an "
          "angular offset of 0.06 mrad; flexible k_c = "
          f"{plant.coupling_stiffness_n_m:.0e} N/m, ψ = 0):")
    t_pin = None
    angular = dict(offset_angle_rad=-0.5 * np.pi, angular_misalignment_mrad=0.06)
    for label, mech, kw in (("pin", "pin", {}), ("rigid", "rigid", {}),
                            ("offset", "offset", dict(offset_angle_rad=-0.5 * np.pi)),
                            ("offset+α", "offset", angular),  # Δ = 0.1 and α = 0.06 mrad, both downward
                            ("flexible", "flexible", {}), ("aligned", "aligned", {})):
        d = 0.0 if mech == "aligned" else DELTA
        t_m, r_m = best_of(lambda: simulate(plant, SPEED, d, A, mechanism=mech, transient_revs=TRANSIENT,
                                            record_revs=RECORD, **kw), n=5)
        t_pin = t_m if t_pin is None else t_pin
        print(f"  {label:9s} {t_m:.3f} s  ({t_m / t_pin:.2f}x pin, best of 5)  accepted steps/rev "
              f"{r_m.n_accepted / REVS:.1f}  RHS evals/rev {r_m.nfev / REVS:.0f}  status={r_m.status}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    from numba import njit

    @njit(cache=False)
    def _rhs_loop(y, p, dy, n):
        for i in range(n):
            K.rhs(0.001 * i, y, p, dy)

    main()
