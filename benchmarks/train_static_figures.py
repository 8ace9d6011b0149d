"""Static figures of docs/train.md: the 40-node plain-bearing train of bench_train at 3000 r/min — bearing
loads, eccentricities and attitude angles with the bearings on a straight line, at the aligned (catenary)
reference, and with the exciter's bearings moved from that reference (parallel δ and angular α, down and
horizontal); the coupling's shear and moment in each case; and the agreement with ROSS 2.3.0.

``python benchmarks/train_static_figures.py``
"""
from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _load(name):
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def _row(label, st):
    load = -st.bearing_load_n[:, 1] / 1e3
    cl = st.coupling_load[0]
    print(f"| {label} | " + " | ".join(f"{l:.1f} / {e:.2f} / {a:.0f}°" for l, e, a in
                                       zip(load, st.eccentricity, st.attitude_angle_deg, strict=True))
          + f" | {cl[1] / 1e3:.2f} kN, {cl[2] / 1e3:.2f} kN·m |")


def main() -> int:
    ref = _load("train_ross_reference")
    bench = _load("bench_train")
    from rotordiag.simulator.train import aligned_offsets, misaligned, static_state, with_moves

    t = bench.plain_train(ref)
    speed = 3000.0
    moves = aligned_offsets(t, speed)
    print("aligned (catenary) bearing moves from the straight line, µm (x, y):",
          np.round(1e6 * moves, 1).tolist())
    aligned = with_moves(t, moves)
    print("| case | B1 | B2 | B3 | B4 | coupling shear y, moment about x |")
    print("|---|---|---|---|---|---|")
    _row("bearings on a straight line", static_state(t, speed))
    _row("aligned (catenary)", static_state(aligned, speed))
    for label, kw in [("δ = 50 µm down", dict(offset_m=50e-6, direction_rad=-math.pi / 2)),
                      ("δ = 50 µm up", dict(offset_m=50e-6, direction_rad=math.pi / 2)),
                      ("δ = 50 µm horizontal (+x)", dict(offset_m=50e-6, direction_rad=0.0)),
                      ("α = 0.1 mrad down", dict(angle_rad=1e-4, direction_rad=-math.pi / 2))]:
        try:
            _row(label, static_state(misaligned(aligned, **kw), speed))
        except ValueError as exc:
            print(f"| {label} | refused: {exc} |")
    # ROSS agreement
    from rotordiag.simulator.train import assemble, critical_speeds, modes, unbalance_response

    fig = json.loads((HERE / "train_ross_reference.json").read_text())
    asm = assemble(ref.reference_train(True))
    camp = max(np.abs(modes(asm, s, n_modes=len(f), about_static=False).frequency_hz / np.array(f) - 1).max()
               for s, f in zip(fig["campbell_rpm"], fig["campbell_hz"], strict=True))
    lo, hi, n = ref.CRITICAL_GRID_RPM
    crit = critical_speeds(ref.reference_train(False), 6, hi, n_grid=n)
    r = unbalance_response(asm, fig["response_rpm"])[:, asm.support_nodes, :]
    R = np.array(fig["probe_response_m"])
    R = R[..., 0] + 1j * R[..., 1]
    print(f"ROSS {fig['ross_version']}: Campbell max rel. difference {camp:.1e}; critical speeds "
          f"{np.round(fig['critical_speeds_rpm'], 1).tolist()} r/min, ours max rel. difference "
          f"{np.abs(crit / np.array(fig['critical_speeds_rpm']) - 1).max():.1e}; unbalance response amplitude "
          f"{np.abs(np.abs(r / R) - 1).max():.1e}, phase {np.abs(np.angle(r / R)).max():.1e} rad")
    return 0


if __name__ == "__main__":
    sys.exit(main())
