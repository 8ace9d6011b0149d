"""How much a start-up adds beside the steady comparison on a simulated shaft train (issue 46 item 4, item 2 of
the follow-up): the gen200_2pole finite-element train (``simulator.train``), a baseline run-up aligned, then later
run-ups of the same train: a healthy re-run (another unbalance amount and phase, another noise seed) and runs with
the exciter's bearings moved down by a parallel offset at the coupling (``simulator.train.misaligned``). Each
run 300 → 1500 r/min in 6 s (200 r/min/s), 20 settling revolutions, 1024 Hz, 40 dB probe noise, order-tracked
(``features.transient``).

*With* the start-up: ``models.checks.startup`` on the coupling-end bearings 2 and 3 (the generator's rear and the
exciter's front bearing) — does it fire? *Without* it, what the service has is the steady comparison with the
asset's baseline at the running speed: here its proxy, the change of the coupling-end probes' 1X and 2X vectors
(pk-pk) and of the journals' mean position between the last 10 revolutions (~1450–1500 r/min) of the run and of the
baseline, against the shipped change thresholds per clearance (``models/default/change_thresholds.json``:
1X 0.234 c, 2X 0.041 c, DC 0.0135 c). A train run-up costs minutes here, so n is small; the table in
docs/transient.md says it. Usage::

    python benchmarks/startup_evidence_train.py --trains 1 --offsets-um 105
"""
from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from rotordiag.features import ProbeChannel, Recording
from rotordiag.features import transient as T
from rotordiag.models.checks.startup import StartupContext, startup_check
from rotordiag.models.startup import compare_startups, startup_evidence
from rotordiag.simulator import shaftline as sl
from rotordiag.simulator.train import misaligned
from rotordiag.simulator.train.shaftline import train_from_shaftline
from rotordiag.simulator.train.transient import TrainTransientModel, train_channels, unbalanced
from rotordiag.simulator.transient import SpeedProfile, simulate_transient

FS = 1024.0
COUPLING = (2, 3)
TOP_STEPS = 10


def run(offset_um: float, unbalance_kg_m: float, phase_rad: float, seed: int):
    tr = train_from_shaftline(sl.preset("gen200_2pole"))
    if offset_um:
        tr = misaligned(tr, offset_m=offset_um * 1e-6)
    model = TrainTransientModel(unbalanced(tr, unbalance_kg_m, angle_rad=phase_rad, replace_own=True))
    res = simulate_transient(model, SpeedProfile.linear(300, 1500, 6), sample_rate_hz=FS, settle_revs=20)
    if not res.ok:
        raise RuntimeError(res.message)
    chans_layout = train_channels(model.n_bearings)
    w = res.probe_waveforms_um(chans_layout, snr_db=40.0, seed=seed)
    chans = [ProbeChannel(b, a, "um", w[i]) for i, (b, a) in enumerate(chans_layout)]
    kp = res.keyphasor_times_s[res.keyphasor_times_s > 0]
    c_um = model.clearance_m * 1e6
    rec = Recording(sample_rate_hz=FS, channels=chans, keyphasor_times_s=kp, clearance_um=c_um)
    track = T.track_orders(rec)
    cl = T.centreline(rec, track)
    return startup_evidence(track, cl), track, cl, c_um


def steady_signature(track, cl) -> dict:
    """The coupling-end probes' 1X/2X vectors (0-pk complex) and journals' mean position over the last steps."""
    idx = np.argsort(track.speed_rpm)[-TOP_STEPS:]
    vec = {p: track.vectors_um[idx, j, :].mean(axis=0) for j, p in enumerate(track.probes) if p[0] in COUPLING}
    pos = {b: (float(cl.x_um[idx, j].mean()), float(cl.y_um[idx, j].mean()))
           for j, b in enumerate(cl.bearings) if b in COUPLING}
    return {"vec": vec, "pos": pos}


def steady_change(now: dict, base: dict, c_um: float) -> dict:
    o1 = max(2 * abs(now["vec"][p][0] - base["vec"][p][0]) for p in now["vec"]) / c_um
    o2 = max(2 * abs(now["vec"][p][1] - base["vec"][p][1]) for p in now["vec"]) / c_um
    dc = max(math.hypot(now["pos"][b][0] - base["pos"][b][0], now["pos"][b][1] - base["pos"][b][1])
             for b in now["pos"]) / c_um
    th = json.loads((Path(__file__).resolve().parents[1] / "models" / "default" /
                     "change_thresholds.json").read_text())["thresholds"]
    fires = o1 > th["1x_change_pp_per_c"] or o2 > th["2x_change_pp_per_c"] or dc > th["dc_shift_per_c"]
    return {"1x_per_c": o1, "2x_per_c": o2, "dc_per_c": dc, "fires": bool(fires)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trains", type=int, default=1)
    ap.add_argument("--seed", type=int, default=4646)
    ap.add_argument("--offsets-um", default="105")
    ap.add_argument("--skip-healthy", action="store_true",
                    help="Leave out the healthy re-run (its draws are still made, so the offset runs are the same)")
    args = ap.parse_args()
    offsets = [float(v) for v in args.offsets_um.split(",")]
    t0 = time.perf_counter()
    for i in range(args.trains):
        rng = np.random.default_rng(args.seed + i)
        base_ev, base_tr, base_cl, c_um = run(0.0, 0.2, 0.0, seed=100 * i)
        base_sig = steady_signature(base_tr, base_cl)
        print(f"train {i}: baseline half-rise {base_ev.half_rise_rpm}, top {base_ev.top_um}, "
              f"criticals {base_ev.criticals} ({time.perf_counter() - t0:.0f} s)", flush=True)
        for name, off in [("healthy re-run", 0.0)] + [(f"offset {o:g} µm ({o / c_um:.2f} c)", o) for o in offsets]:
            ub, ph = float(rng.uniform(0.1, 0.3)), float(rng.uniform(0, 2 * math.pi))
            if args.skip_healthy and off == 0.0:
                continue
            ev, tr, cl, _ = run(off, ub, ph, seed=100 * i + 1 + int(off))
            cmp_ = compare_startups(ev, base_ev, COUPLING)
            reasons = startup_check(StartupContext(ev, base_ev, misaligned_call=False, coupling_bearings=COUPLING))
            st = steady_change(steady_signature(tr, cl), base_sig, c_um)
            rise = max((abs(v[2]) for v in cmp_["half_rise_shift"].values()), default=math.nan)
            top = max(cmp_["top_change_per_clearance"].values(), default=math.nan)
            print(f"train {i} {name:26s} unbalance {ub:.2f} kg·m at {math.degrees(ph):5.0f}°: start-up check "
                  f"fires {bool(reasons)} (max |half-rise shift| {rise:.3f}, max top change {top:.3f} c; half-rise "
                  f"{ev.half_rise_rpm}); steady proxy fires {st['fires']} (1X {st['1x_per_c']:.3f} c, 2X "
                  f"{st['2x_per_c']:.4f} c, DC {st['dc_per_c']:.4f} c) ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
