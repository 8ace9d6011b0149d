"""The presets as shipped, aligned on their catenary at their rated speeds: orbit size, 2X/1X, margin.

Each preset with its own residual unbalance (ISO 21940-11 G2.5 at its first rated speed) and rotor asymmetry,
its bearings moved onto the catenary (``aligned_offsets``: the coupling carries no shear and no moment), simulated
``TRANSIENT_REVS`` + ``RECORD_REVS`` revolutions from the static state. Per bearing: the vertical and horizontal
pk-pk journal motion relative to the bearing, 1X and 2X of the vertical motion, their ratio and the largest
subsynchronous line over 1X; per speed the least-damped mode's logarithmic decrement and ``speed_warning``.
Deterministic (no random draw). Usage: ``python benchmarks/train_presets_aligned.py [preset ...]``; results in
docs/train-misalignment.md ("Steady orbit, aligned").
"""
from __future__ import annotations

import json
import sys
import time

import numpy as np

from rotordiag.simulator import shaftline as sl
from rotordiag.simulator.train import aligned_offsets, with_moves
from rotordiag.simulator.train.dynamics import simulate_train
from rotordiag.simulator.train.shaftline import train_from_shaftline
from rotordiag.simulator.train.stability import speed_warning, stability

TRANSIENT_REVS, RECORD_REVS, SAMPLES_PER_REV = 200, 32, 64


def measure(name: str, speed_rpm: float) -> dict:
    t0 = time.perf_counter()
    line = sl.preset(name)
    train = train_from_shaftline(line)
    train = with_moves(train, aligned_offsets(train, speed_rpm))
    s = stability(train, speed_rpm)
    run = simulate_train(train, speed_rpm, transient_revs=TRANSIENT_REVS, record_revs=RECORD_REVS,
                         samples_per_rev=SAMPLES_PER_REV)
    rows = []
    k1, k2 = RECORD_REVS, 2 * RECORD_REVS
    for b in range(run.journal_m.shape[1]):
        x, y = run.journal_m[:, b, 0], run.journal_m[:, b, 1]
        spec = np.abs(np.fft.rfft(y - y.mean())) * 2 / len(y)
        rows.append(dict(bearing=b + 1, pp_vertical_um=float(np.ptp(y) * 1e6), pp_horizontal_um=float(np.ptp(x) * 1e6),
                         one_x_um=float(spec[k1] * 1e6), two_x_um=float(spec[k2] * 1e6),
                         two_x_over_one_x=float(spec[k2] / spec[k1]),
                         subsync_over_one_x=float(spec[1:k1].max() / spec[k1])))
    return dict(preset=name, speed_rpm=speed_rpm, clearance_um=line.clearance_m * 1e6,
                asymmetry=line.generator_asymmetry, unbalance_kg_m=line.generator_unbalance_kg_m,
                status=run.status, log_decrement=s.log_decrement, warning=speed_warning(train, speed_rpm),
                bearings=rows, wall_s=time.perf_counter() - t0)


if __name__ == "__main__":
    names = sys.argv[1:] or list(sl.PRESETS)
    for n in names:
        for rpm in sl.PRESETS[n]["rated_speed_rpm"]:
            print(json.dumps(measure(n, float(rpm))), flush=True)
