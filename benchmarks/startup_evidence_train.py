"""How much a start-up adds beside the steady comparison on simulated shaft trains (issue 46 item 4, item 2 of
the follow-up), read from a generated transient dataset (a ``[transient]`` spec per held-out train,
docs/datasets.md "Run-ups and coast-downs").

Each held-out train is the gen200_2pole finite-element train (``[plant] model = "train"``) with its clearance drawn
±10 %, oil viscosity, coupling stiffness and bearing lengths ±15 % from the seed (written into the spec's
``plant.set``), one spec per train and coupling type (``--couplings rigid,flexible``). The spec is a grid:
misalignment [0, Δ…] (the exciter's bearings moved down, ``offset_angle_rad`` = −π/2; a flexible coupling also gets
the offset's kinematic 2X forcing, as every train sample) × unbalance phase [0°, ``--phase-deg``] at a balance
grade giving ≈ 0.2 kg·m at the top speed. Every run 300 → 1500 r/min in 6 s (200 r/min/s), 20 settling
revolutions, 1024 Hz, 40 dB probe noise, x/y probes at 45°/135° at all four bearings, order-tracked
(``features.transient``). The baseline start-up is the aligned run at 0°; the later runs are the healthy re-run
(aligned, the other phase, its own noise) and every offset run.

*With* the start-up: ``models.checks.startup`` on the coupling-end bearings 2 and 3 — does it fire? *Without* it,
what the service has is the steady comparison with the asset's baseline at the running speed: here its proxy,
the change of the coupling-end probes' 1X and 2X vectors (pk-pk) and of the journals' mean position between the
last 10 revolutions (~1450–1500 r/min) of the run and of the baseline, against the shipped change thresholds per
clearance (``models/default/change_thresholds.json``). Beside both, the slow-roll position alone: the coupling-end
journals' position over the slowest 5 % of the steps against the baseline start-up's, above
``RISE_CHANGED_FRACTION`` (0.10 c) — part of the check since it was measured here as what a train's offset moves
(before, the check compared only the rise from slow roll and its half-rise speed, and caught 0 of 3 offsets). A train run-up costs about a minute here, so n is small; rates are
printed with 95 % Wilson intervals. The datasets are kept in ``--out-dir`` and resumed (a rerun reads them).
Usage::

    python benchmarks/startup_evidence_train.py --trains 2 --misalignments 0.15,0.3 --workers 2
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
from rotordiag.simulator.dataset import DatasetReader, generate
from rotordiag.simulator.train.plant import TrainPlant

COUPLING = (2, 3)
TOP_STEPS = 10
#: ISO 21940 grade giving the generator ≈ 0.2 kg·m at 1500 r/min (the unbalance of the earlier runs' baseline)
BALANCE_GRADE_MM_S = 0.65

SPEC = """\
# {what}
[design]
method = "grid"
seed = {seed}

[plant]
model = "train"
preset = "gen200_2pole"
[plant.set]
clearance_m = {clearance_m!r}
viscosity_pa_s = {viscosity_pa_s!r}
coupling_stiffness_n_m = {coupling_stiffness_n_m!r}
bearing_length_m = {bearing_length_m!r}
balance_grade_mm_s = {grade!r}

[operating]
misalignment = {misalignments!r}
unbalance_phase_rad = [0.0, {phase_rad!r}]
offset_angle_rad = -1.5707963267948966
mechanism = "{coupling}"

[transient]
start_rpm = 300
end_rpm = 1500
duration_s = 6
settle_revs = 20

[measurement]
sample_rate_hz = 1024.0
snr_db = 40.0
"""


def held_out_values(seed: int) -> dict:
    """The preset's clearance ±10 %, viscosity, coupling stiffness and bearing lengths ±15 % (seeded)."""
    rng = np.random.default_rng(seed)
    p = TrainPlant.of(sl.preset("gen200_2pole"))

    def u(w: float) -> float:
        return float(rng.uniform(1 - w, 1 + w))

    return {"clearance_m": p.clearance_m * u(0.10), "viscosity_pa_s": p.viscosity_pa_s * u(0.15),
            "coupling_stiffness_n_m": p.coupling_stiffness_n_m * u(0.15),
            "bearing_length_m": [v * u(0.15) for v in p.bearing_length_m]}


def train_spec(i: int, coupling: str, args) -> str:
    return SPEC.format(what=f"held-out train {i} ({coupling}), benchmarks/startup_evidence_train.py",
                       seed=args.seed + i, coupling=coupling, grade=BALANCE_GRADE_MM_S,
                       misalignments=[0.0] + [float(v) for v in args.misalignments.split(",")],
                       phase_rad=math.radians(args.phase_deg), **held_out_values(args.seed + 7919 * i))


def evaluate(ds: DatasetReader, i: int):
    """The start-up evidence, order track and centreline of transient sample ``i``, and its clearance (µm)."""
    smp = ds.transient_sample(i)
    if smp.status != "ok":
        raise RuntimeError(f"sample {i}: {smp.status}")
    chans = [ProbeChannel(b, a, "um", smp.waveforms_um[k].astype(float)) for k, (b, a) in enumerate(smp.channels)]
    c_um = smp.clearance_m * 1e6
    kp = smp.keyphasor_times_s[smp.keyphasor_times_s > 0]
    rec = Recording(sample_rate_hz=smp.sample_rate_hz, channels=chans, keyphasor_times_s=kp, clearance_um=c_um)
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
    ap.add_argument("--misalignments", default="0.15,0.3", help="Δ = offset / clearance of the offset runs")
    ap.add_argument("--phase-deg", type=float, default=160.0, help="The later unbalance phase (the baseline: 0°)")
    ap.add_argument("--couplings", default="rigid", help="Coupling types: rigid,flexible")
    ap.add_argument("--workers", type=int, default=0, help="Dataset workers (0: serial)")
    ap.add_argument("--out-dir", type=Path, default=Path("build/startup_evidence_train"))
    ap.add_argument("--evaluate-only", action="store_true",
                    help="Generate nothing: evaluate the finished run-ups of the datasets already in --out-dir")
    args = ap.parse_args()
    args.out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    tally: dict[tuple[str, str], list[tuple[bool, bool, bool]]] = {}
    for i in range(args.trains):  # the coupling types interleaved: a run cut short still has both
        for coupling in args.couplings.split(","):
            spec = args.out_dir / f"train{i}_{coupling}.toml"
            spec.write_text(train_spec(i, coupling, args))
            out = args.out_dir / f"train{i}_{coupling}.h5"
            if args.evaluate_only:
                if not out.exists():
                    print(f"{out}: not generated", flush=True)
                    continue
            else:
                gs = generate(spec, out, n_workers=args.workers, progress=False)
                print(f"{out}: {gs.n_computed} run-ups generated, {gs.n_done_before} read back "
                      f"({time.perf_counter() - t0:.0f} s)", flush=True)
            with DatasetReader(out) as ds:
                lab = ds.labels()                     # the finished run-ups only
                phase = ds.parameters("parameters/unbalance_phase_rad")
                rows = [int(r) for r in ds.indices]
                print(f"{out}: {len(rows)} of {ds.done.size} run-ups finished", flush=True)
                base = next((r for r, d, ph in zip(rows, lab["misalignment"], phase) if d == 0.0 and ph == 0.0), None)
                if base is None:
                    print(f"{coupling} train {i}: its baseline run-up is not finished; skipped", flush=True)
                    continue
                base_ev, base_tr, base_cl, c_um = evaluate(ds, base)
                base_sig = steady_signature(base_tr, base_cl)
                unb = float(ds.parameters("labels/unbalance_kg_m")[0])
                print(f"{coupling} train {i}: c {c_um:.0f} µm, unbalance {unb:.2f} kg·m, "
                      f"baseline half-rise {base_ev.half_rise_rpm}, top {base_ev.top_um}, criticals "
                      f"{base_ev.criticals}", flush=True)
                for r, delta, ph in zip(rows, lab["misalignment"], phase):
                    if r == base:
                        continue
                    ev, tr, cl, _ = evaluate(ds, r)
                    cmp_ = compare_startups(ev, base_ev, COUPLING)
                    reasons = startup_check(StartupContext(ev, base_ev, misaligned_call=False,
                                                           coupling_bearings=COUPLING))
                    st = steady_change(steady_signature(tr, cl), base_sig, c_um)
                    sr = slow_roll_change(cl, base_cl, c_um)
                    rise = max((abs(v[2]) for v in cmp_["half_rise_shift"].values()), default=math.nan)
                    top = max(cmp_["top_change_per_clearance"].values(), default=math.nan)
                    kind = "healthy" if delta == 0.0 else "offset"
                    name = "healthy re-run" if delta == 0.0 else f"offset Δ {delta:g} ({delta * c_um:.0f} µm)"
                    tally.setdefault((coupling, kind), []).append((bool(reasons), sr > RISE_CHANGED_FRACTION,
                                                                   st["fires"]))
                    print(f"{coupling} train {i} {name:24s} unbalance at {math.degrees(ph):4.0f}°: start-up check "
                          f"fires {bool(reasons)} (max |half-rise shift| {rise:.3f}, max top change {top:.3f} c); "
                          f"slow-roll position change {sr:.3f} c (alone fires {sr > RISE_CHANGED_FRACTION}); "
                          f"steady proxy fires {st['fires']} (1X {st['1x_per_c']:.3f} c, 2X {st['2x_per_c']:.4f} c, "
                          f"DC {st['dc_per_c']:.4f} c)", flush=True)
    print(f"{time.perf_counter() - t0:.0f} s")
    for (coupling, kind), rows_ in sorted(tally.items()):
        n = len(rows_)
        cells = []
        for j, what in enumerate(("start-up check", "slow-roll alone", "steady proxy")):
            k = sum(r[j] for r in rows_)
            lo, hi = wilson(k, n)
            cells.append(f"{what} {k}/{n} ({lo:.2f}–{hi:.2f})")
        print(f"{coupling:8s} {kind:8s} fires: " + "; ".join(cells))


if __name__ == "__main__":
    main()
