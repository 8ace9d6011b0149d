"""Cost of one oil-film force evaluation in the compiled kernel (issue 42), per bearing type.

    .venv/bin/python benchmarks/bench_bearings.py [--n 200000] [--repeats 7]

Each type is called through ``bearing_force(code, params, ...)`` from a compiled loop over a
small orbit about its static position under 60 kN at 3000 r/min (D 0.45 m, L 0.35 m, c 0.35 mm,
μ 0.018 Pa·s), with velocity, so every call solves a new film (and, for tilting pads, new pad
tilts; with the pad tilts as states, the tilt rates at fixed tilts). Prints µs of process CPU time per call (the minimum over the repeats: CPU time, not wall
time, because the machine is shared) and the ratio to
the plain bearing, whose Capone closed form is the simulator's film today.
"""
from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import argparse
import math
import time

import numpy as np
from numba import njit

from rotordiag.simulator.bearings import (
    EllipticalBearing,
    LinearBearing,
    PlainBearing,
    TiltingPadBearing,
    bearing_force,
    tilting_pad_force_states,
)

D, L, C, MU = 0.45, 0.35, 0.35e-3, 0.018
SPEED_RAD_S = 2.0 * math.pi * 3000 / 60
LOAD_N = 6.0e4


@njit(cache=False)
def _orbit(code, params, x0, y0, amp, omega, n):
    s = 0.0
    for i in range(n):
        ph = 2.0 * math.pi * i / 997.0
        c, sn = math.cos(ph), math.sin(ph)
        fx, fy = bearing_force(code, params, x0 + amp * c, y0 + amp * sn, -amp * omega * sn, amp * omega * c, omega)
        s += fx + fy
    return s


@njit(cache=False)
def _orbit_states(params, x0, y0, amp, omega, n, u):
    du = np.zeros(u.size)
    s = 0.0
    for i in range(n):
        ph = 2.0 * math.pi * i / 997.0
        c, sn = math.cos(ph), math.sin(ph)
        fx, fy = tilting_pad_force_states(params, x0 + amp * c, y0 + amp * sn, -amp * omega * sn, amp * omega * c,
                                          omega, u, du)
        s += fx + fy + du[0]
    return s


def _time(fn, repeats):
    best = math.inf
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200_000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    plain = PlainBearing(D, L, C, MU)
    cases = [
        ("plain (Capone closed form)", plain),
        ("two-lobe, m 0.5, 2 × 150°", EllipticalBearing(D, L, C, MU, preload=0.5, lobe_arc_deg=150.0)),
        ("tilting pad, 4 pads LBP, 80°, m 0.3", TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, preload=0.3)),
        ("tilting pad, 5 pads LOP, 60°, 0.6 offset", TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0,
                                                                        pivot_offset=0.6, preload=0.2, load="on_pad")),
    ]
    K, Cm = plain.coefficients(*plain.equilibrium(0.0, -LOAD_N, SPEED_RAD_S), SPEED_RAD_S)
    cases.append(("linear K/C", LinearBearing(D, L, C, stiffness_n_m=K, damping_n_s_m=Cm)))
    base = None
    print(f"{'bearing':44s} {'µs/call':>9s} {'× plain':>8s}")
    for name, b in cases:
        x0, y0 = b.equilibrium(0.0, -LOAD_N, SPEED_RAD_S)
        code, p = b.kernel()
        amp = 0.05 * C
        _orbit(code, p, x0, y0, amp, SPEED_RAD_S, 10)
        us = _time(lambda: _orbit(code, p, x0, y0, amp, SPEED_RAD_S, args.n), args.repeats) / args.n * 1e6
        base = base or us
        print(f"{name:44s} {us:9.3f} {us / base:8.1f}")
        if isinstance(b, TiltingPadBearing):
            u = b.pad_tilts(x0, y0, SPEED_RAD_S)
            _orbit_states(p, x0, y0, amp, SPEED_RAD_S, 10, u)
            us = _time(lambda: _orbit_states(p, x0, y0, amp, SPEED_RAD_S, args.n, u), args.repeats) / args.n * 1e6
            print(f"{'  same, pad tilts as states (rates)':44s} {us:9.3f} {us / base:8.1f}")

if __name__ == "__main__":
    main()
