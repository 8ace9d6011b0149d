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
1X 0.234 c, 2X 0.041 c, DC 0.0135 c). Beside both, a candidate the shipped check does not have: the coupling-end
journals' slow-roll position (the slowest 5 % of the steps) against the baseline start-up's, per clearance, fired
above ``RISE_CHANGED_FRACTION`` (0.10 c) — what a parallel offset moves on a train (docs/transient.md).

``--held-out``: each train is the preset with its clearance drawn ±10 %, oil viscosity, coupling stiffness and
bearing lengths ±15 % from the seed (``TrainPlant.replace``), per coupling type (``--couplings rigid,flexible``;
a flexible coupling also gets the offset's kinematic 2X forcing, ``with_kinematic_offset``). A train run-up
costs minutes here, so n is small; the table in docs/transient.md says it. Usage::

    python benchmarks/startup_evidence_train.py --trains 1 --offsets-um 105
    python benchmarks/startup_evidence_train.py --held-out --couplings rigid,flexible --trains 2 --offsets-um 50,105
"""
from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from startup_evidence import wilson  # (the sibling benchmark's 95 % Wilson interval)

from rotordiag.features import ProbeChannel, Recording
from rotordiag.features import transient as T
from rotordiag.models.checks.startup import RISE_CHANGED_FRACTION, StartupContext, startup_check
from rotordiag.models.startup import compare_startups, startup_evidence
from rotordiag.simulator import shaftline as sl
from rotordiag.simulator.train import misaligned
from rotordiag.simulator.train.plant import TrainPlant
from rotordiag.simulator.train.recording import with_kinematic_offset
from rotordiag.simulator.train.shaftline import train_from_shaftline
from rotordiag.simulator.train.transient import TrainTransientModel, train_channels, unbalanced
from rotordiag.simulator.transient import SpeedProfile, simulate_transient

FS = 1024.0
COUPLING = (2, 3)
TOP_STEPS = 10


def held_out_line(seed: int, coupling: str) -> sl.ShaftLine:
    """The preset with its clearance ±10 %, viscosity, coupling stiffness and bearing lengths ±15 % (seeded)."""
    rng = np.random.default_rng(seed)
    p = TrainPlant.of(sl.preset("gen200_2pole"))

    def u(w: float) -> float:
        return float(rng.uniform(1 - w, 1 + w))

    p = p.replace(clearance_m=p.clearance_m * u(0.10), viscosity_pa_s=p.viscosity_pa_s * u(0.15),
                  coupling_stiffness_n_m=p.coupling_stiffness_n_m * u(0.15),
                  bearing_length_m=[v * u(0.15) for v in p.bearing_length_m])
    return p.line(coupling=coupling)


def run(offset_um: float, unbalance_kg_m: float, phase_rad: float, seed: int, line: sl.ShaftLine | None = None):
    tr = train_from_shaftline(line if line is not None else sl.preset("gen200_2pole"))
    if offset_um:
        tr = with_kinematic_offset(misaligned(tr, offset_m=offset_um * 1e-6), offset_um, -90.0)
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


def slow_roll_change(now, base, c_um: float) -> float:
    """The largest coupling-end journal's move of its slow-roll position (slowest 5 % of the steps) / clearance."""
    def slow(cl) -> dict[int, np.ndarray]:
        order = np.argsort(cl.speed_rpm)
        n = max(1, order.size // 20)
        return {b: np.array([cl.x_um[order[:n], j].mean(), cl.y_um[order[:n], j].mean()])
                for j, b in enumerate(cl.bearings) if b in COUPLING}
    a, b = slow(now), slow(base)
    return max(float(np.hypot(*(a[k] - b[k]))) for k in a) / c_um


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
    ap.add_argument("--held-out", action="store_true", help="Draw each train's values from the seed (docstring)")
    ap.add_argument("--couplings", default="rigid", help="Coupling types with --held-out: rigid,flexible")
    ap.add_argument("--skip-healthy", action="store_true",
                    help="Leave out the healthy re-run (its draws are still made, so the offset runs are the same)")
    args = ap.parse_args()
    offsets = [float(v) for v in args.offsets_um.split(",")]
    couplings = args.couplings.split(",") if args.held_out else ["preset"]
    t0 = time.perf_counter()
    tally: dict[tuple[str, str], list[tuple[bool, bool, bool]]] = {}
    for i in range(args.trains):  # the coupling types interleaved: a run cut short still has both
        for coupling in couplings:
            rng = np.random.default_rng(args.seed + i)
            line = held_out_line(args.seed + 7919 * i, coupling) if args.held_out else None
            base_ev, base_tr, base_cl, c_um = run(0.0, 0.2, 0.0, seed=100 * i, line=line)
            base_sig = steady_signature(base_tr, base_cl)
            print(f"{coupling} train {i}: c {c_um:.0f} µm, baseline half-rise {base_ev.half_rise_rpm}, top "
                  f"{base_ev.top_um}, criticals {base_ev.criticals} ({time.perf_counter() - t0:.0f} s)", flush=True)
            for name, off in [("healthy re-run", 0.0)] + [(f"offset {o:g} µm ({o / c_um:.2f} c)", o) for o in offsets]:
                ub, ph = float(rng.uniform(0.1, 0.3)), float(rng.uniform(0, 2 * math.pi))
                if args.skip_healthy and off == 0.0:
                    continue
                ev, tr, cl, _ = run(off, ub, ph, seed=100 * i + 1 + int(off), line=line)
                cmp_ = compare_startups(ev, base_ev, COUPLING)
                reasons = startup_check(StartupContext(ev, base_ev, misaligned_call=False,
                                                       coupling_bearings=COUPLING))
                st = steady_change(steady_signature(tr, cl), base_sig, c_um)
                sr = slow_roll_change(cl, base_cl, c_um)
                rise = max((abs(v[2]) for v in cmp_["half_rise_shift"].values()), default=math.nan)
                top = max(cmp_["top_change_per_clearance"].values(), default=math.nan)
                kind = "healthy" if off == 0.0 else "offset"
                tally.setdefault((coupling, kind), []).append((bool(reasons), sr > RISE_CHANGED_FRACTION,
                                                               st["fires"]))
                print(f"{coupling} train {i} {name:26s} unbalance {ub:.2f} kg·m at {math.degrees(ph):5.0f}°: "
                      f"start-up check fires {bool(reasons)} (max |half-rise shift| {rise:.3f}, max top change "
                      f"{top:.3f} c; half-rise {ev.half_rise_rpm}); slow-roll position change {sr:.3f} c "
                      f"(candidate fires {sr > RISE_CHANGED_FRACTION}); steady proxy fires {st['fires']} (1X "
                      f"{st['1x_per_c']:.3f} c, 2X {st['2x_per_c']:.4f} c, DC {st['dc_per_c']:.4f} c) "
                      f"({time.perf_counter() - t0:.0f} s)", flush=True)
    print(f"{time.perf_counter() - t0:.0f} s")
    for (coupling, kind), rows in sorted(tally.items()):
        n = len(rows)
        cells = []
        for j, what in enumerate(("start-up check", "slow-roll candidate", "steady proxy")):
            k = sum(r[j] for r in rows)
            lo, hi = wilson(k, n)
            cells.append(f"{what} {k}/{n} ({lo:.2f}–{hi:.2f})")
        print(f"{coupling:8s} {kind:8s} fires: " + "; ".join(cells))


if __name__ == "__main__":
    main()
