"""Speed and reduction error of the shaft-train time response (docs/train.md), one core.

1. The 40-node generator–exciter train of ``train_ross_reference`` on four plain (Capone/Ocvirk)
   oil-film bearings, gravity, generator body asymmetry ρ = 0.05, at 3000 r/min: 448 revolutions
   (320 transient + 128 recorded, 32 samples per revolution) — wall time of the whole call (model
   assembly, Craig–Bampton reduction, Newton static state, exponential-integrator matrices, integration)
   against the target 0.5 s.
2. The same machine on linear bearings against ROSS 2.3.0's ``run_time_response`` (when ROSS is installed):
   ROSS is timed over a short record and scaled to 448 revolutions (its cost grows linearly with the
   samples); target ≥ 20×.
3. Reduction error against the full finite-element model: the first 6 undamped critical speeds and the
   steady 1X response at the four bearings (linear bearings, 3000 r/min).

``python benchmarks/bench_train.py [--modes 12]``
"""
from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import argparse
import importlib.util
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SPEED_RPM = 3000.0
TRANSIENT, RECORD, SPR = 320, 128, 32


def _ref():
    spec = importlib.util.spec_from_file_location("train_ross_reference", HERE / "train_ross_reference.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["train_ross_reference"] = mod
    spec.loader.exec_module(mod)
    return mod


def plain_train(ref):
    """The reference machine on plain bearings with gravity and a two-pole generator body."""
    from rotordiag.simulator.bearings import PlainBearing

    t = ref.reference_train(True)
    bg = PlainBearing(diameter_m=0.25, length_m=0.2, clearance_m=190e-6, viscosity_pa_s=0.02)
    be = PlainBearing(diameter_m=0.15, length_m=0.1, clearance_m=120e-6, viscosity_pa_s=0.02)
    rotors = []
    for r, b in zip(t.rotors, (bg, be), strict=True):
        el = r.elements
        if r.name == "generator":  # the 1 m body: the 15 elements of diameter 1.0
            el = tuple(replace(e, asymmetry=0.05) if e.outer_diameter_m == 1.0 else e for e in el)
        rotors.append(replace(r, elements=el, supports=tuple(replace(s, bearing=b) for s in r.supports)))
    return replace(t, rotors=tuple(rotors), gravity_m_s2=9.81)


def _run(train, n_modes):
    from rotordiag.simulator.train.dynamics import simulate_train

    t0 = time.perf_counter()
    run = simulate_train(train, SPEED_RPM, transient_revs=TRANSIENT, record_revs=RECORD, samples_per_rev=SPR,
                         n_modes=n_modes)
    return time.perf_counter() - t0, run


def _ross_seconds(ref, revs: int) -> float:
    rotor, off = ref._ross_rotor(True)
    w = SPEED_RPM * math.pi / 30
    t = np.arange(revs * SPR) * (2 * math.pi / w) / SPR
    F = np.zeros((len(t), rotor.ndof))
    nd = rotor.number_dof
    for r, s, me, a in ref.unbalances():
        n = off[r] + s
        F[:, nd * n] += me * w**2 * np.cos(w * t + a)
        F[:, nd * n + 1] += me * w**2 * np.sin(w * t + a)
    t0 = time.perf_counter()
    rotor.run_time_response(w, F, t)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--modes", type=int, default=12)
    ap.add_argument("--ross-revs", type=int, default=32, help="revolutions ROSS is timed over")
    args = ap.parse_args()
    ref = _ref()
    from rotordiag.simulator.train import assemble, critical_speeds, reduced_critical_speeds, unbalance_response
    from rotordiag.simulator.train.dynamics import simulate_train
    from rotordiag.simulator.train.reduced import reduce

    train = plain_train(ref)
    _run(train, args.modes)  # compile (numba caches to disk: later processes skip this)
    wall, run = min((_run(train, args.modes) for _ in range(3)), key=lambda x: x[0])
    n_nodes = assemble(train).n_nodes
    pp = 1e6 * np.ptp(run.journal_m, axis=0)
    print(f"[1] {n_nodes}-node train, plain bearings, {SPEED_RPM:.0f} r/min, {TRANSIENT}+{RECORD} revolutions: "
          f"{wall:.3f} s ({run.status}, {run.inputs['method']}); target 0.5 s → ratio {wall / 0.5:.2f}")
    print(f"    journal pk-pk x/y (µm): {np.round(pp.ravel(), 1).tolist()}")

    lin = ref.reference_train(True)
    wall_lin, run_lin = min((_run(lin, args.modes) for _ in range(3)), key=lambda x: x[0])
    try:
        import ross  # noqa: F401  # type: ignore[import-not-found]
    except ImportError:
        print("[2] ROSS not installed: pip install -e '.[validation]' to time it")
    else:
        short = _ross_seconds(ref, args.ross_revs)
        scaled = short * (TRANSIENT + RECORD) / args.ross_revs
        print(f"[2] linear bearings: ours {wall_lin:.3f} s for {TRANSIENT + RECORD} revolutions; ROSS 2.3.0 "
              f"run_time_response {short:.2f} s for {args.ross_revs} → {scaled:.1f} s scaled; "
              f"speed-up {scaled / wall_lin:.0f}× (target ≥ 20×)")

    asm = assemble(ref.reference_train(False))
    red = reduce(asm, args.modes)
    full = critical_speeds(asm, 6, 9000.0, n_grid=90)

    crit = reduced_critical_speeds(red, 6, 9000.0, n_grid=90)
    print(f"[3] reduction ({args.modes} fixed-interface modes + {len(red.boundary)} bearing DOFs = {red.n} of "
          f"{asm.n_dof}): first 6 critical speeds full {np.round(full, 1).tolist()} r/min, "
          f"max error {100 * np.abs(crit / full - 1).max():.4f} %")
    asm_d = assemble(lin)
    Rf = unbalance_response(asm_d, [SPEED_RPM])[0, asm_d.support_nodes, :]
    runr = simulate_train(asm_d, SPEED_RPM, transient_revs=TRANSIENT, record_revs=RECORD, samples_per_rev=SPR,
                          n_modes=args.modes)
    X = 2 * np.fft.fft(runr.journal_m, axis=0)[RECORD] / runr.journal_m.shape[0]
    print(f"    steady 1X at the bearings vs the full model's frequency response: amplitude "
          f"{100 * np.abs(np.abs(X / Rf) - 1).max():.3f} %, phase {np.degrees(np.abs(np.angle(X / Rf))).max():.3f}°")
    return 0


if __name__ == "__main__":
    sys.exit(main())
