"""How much a start-up adds beside the steady verdict (issue 46 item 4), on simulated held-out plants.

Each plant is the paper's model with its stiffnesses, damping, clearance and oil viscosity drawn ±15 % (±10 % for
the clearance) from a seed. Its baseline start-up is a run-up at Δ = 0; then three more run-ups of the same plant:
Δ = 0 with another unbalance phase and amount (a healthy later start-up), Δ = 0.15 and Δ = 0.3. Each run: 300 →
2000 r/min at 100 r/min/s, 2560 Hz, 40 dB probe noise, order-tracked (``features.transient``), then
``models.checks.startup``: does the run differ from the baseline (a critical moved > 5 %, a coupling-end
bearing's centreline half-rise speed moved > 10 % or its top-speed position > 10 % of the clearance)? The rate at
which it fires per Δ, with Wilson 95 % intervals, and the features' values; beside it the steady verdict of the
shipped model (``models/default_registry``) on a 1950 r/min recording of the same plant and Δ (40 dB noise), and
what the check does to it: an "aligned" call on a run that changed becomes uncertain. Usage::

    python benchmarks/startup_evidence.py --plants 6
"""
from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from rotordiag.core.conventions import project_on_probe
from rotordiag.features import ProbeChannel, Recording
from rotordiag.features import transient as T
from rotordiag.models.checks.startup import StartupContext, startup_check
from rotordiag.models.pipeline import diagnose_recording
from rotordiag.models.predict import load_bundle
from rotordiag.models.startup import compare_startups, startup_evidence
from rotordiag.simulator import Plant, simulate
from rotordiag.simulator.transient import DEFAULT_CHANNELS, SpeedProfile, simulate_transient

FS = 2560.0


def plant(seed: int) -> Plant:
    rng = np.random.default_rng(seed)
    p = Plant.default()
    f = lambda lo=0.85, hi=1.15: float(rng.uniform(lo, hi))  # noqa: E731
    return replace(p, generator_stiffness_n_m=p.generator_stiffness_n_m * f(),
                   exciter_stiffness_n_m=p.exciter_stiffness_n_m * f(),
                   generator_damping_n_s_m=p.generator_damping_n_s_m * f(),
                   exciter_damping_n_s_m=p.exciter_damping_n_s_m * f(), clearance_m=p.clearance_m * f(0.9, 1.1),
                   viscosity_pa_s=p.viscosity_pa_s * f())


def run(pl: Plant, delta: float, unbalance: float, phase_rad: float, seed: int, duration_s: float = 17.0):
    res = simulate_transient(pl, SpeedProfile.linear(300, 2000, duration_s), delta, unbalance, sample_rate_hz=FS,
                             settle_revs=100, unbalance_phase_rad=phase_rad)
    if not res.ok:
        raise RuntimeError(res.message)
    w = res.probe_waveforms_um(snr_db=40.0, seed=seed)
    chans = [ProbeChannel(b, a, "um", w[i]) for i, (b, a) in enumerate(DEFAULT_CHANNELS)]
    kp = res.keyphasor_times_s[res.keyphasor_times_s > 0]
    rec = Recording(sample_rate_hz=FS, channels=chans, keyphasor_times_s=kp, clearance_um=pl.clearance_m * 1e6)
    tr = T.track_orders(rec)
    return startup_evidence(tr, T.centreline(rec, tr))


def steady_call(bundle, pl: Plant, delta: float, unbalance: float, phase_rad: float, seed: int) -> tuple[str, str]:
    """The shipped model's (severity, status) on a steady 1950 r/min recording of the plant."""
    res = simulate(pl, 1950.0, delta, unbalance, transient_revs=300, record_revs=80, sample_rate_hz=FS,
                   unbalance_phase_rad=phase_rad)
    if res.status != "ok":
        raise RuntimeError(res.status)
    d = res.journal_displacements_m * 1e6
    rng = np.random.default_rng(seed)
    w = np.array([project_on_probe(d[:, b - 1, 0], d[:, b - 1, 1], a) for b, a in DEFAULT_CHANNELS])
    w += rng.standard_normal(w.shape) * np.sqrt(w.var(axis=1, keepdims=True) / 1e4)
    chans = [ProbeChannel(b, a, "um", w[i]) for i, (b, a) in enumerate(DEFAULT_CHANNELS)]
    rec = Recording(sample_rate_hz=FS, channels=chans, clearance_um=pl.clearance_m * 1e6, speed_rpm=1950.0)
    v, _ = diagnose_recording(bundle, rec, clearance_um=pl.clearance_m * 1e6)
    return v.severity, v.status


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--plants", type=int, default=6)
    ap.add_argument("--seed", type=int, default=4600)
    args = ap.parse_args()
    t0 = time.perf_counter()
    from pathlib import Path

    import rotordiag.models as M

    bundle = load_bundle(Path(M.__file__).parent / "default_registry")
    cases = [("Δ 0 (healthy re-run)", 0.0), ("Δ 0, 60 r/min/s ramp", 0.0), ("Δ 0.15", 0.15), ("Δ 0.3", 0.3)]
    fired: dict[str, list[bool]] = {c: [] for c, _ in cases}
    calls: dict[str, list[tuple[str, str, bool]]] = {c: [] for c, _ in cases}
    rows = []
    for i in range(args.plants):
        rng = np.random.default_rng(args.seed + 1000 + i)
        pl = plant(args.seed + i)
        base = run(pl, 0.0, 0.05, 0.0, seed=10 * i)
        for name, delta in cases:
            ub, ph = float(rng.uniform(0.03, 0.07)), float(rng.uniform(0, 2 * math.pi))
            ev = run(pl, delta, ub, ph, seed=10 * i + 1 + int(delta * 100),
                     duration_s=28.3 if "60 r/min/s" in name else 17.0)
            cmp_ = compare_startups(ev, base)
            reasons = startup_check(StartupContext(ev, base, misaligned_call=False))
            fired[name].append(bool(reasons))
            sev, status = steady_call(bundle, pl, delta, ub, ph, seed=10 * i + 5 + int(delta * 100))
            calls[name].append((sev, status, bool(reasons)))
            crit = max((abs(v[2]) for v in cmp_["critical_shift"].values()), default=math.nan)
            rise = max((abs(v[2]) for v in cmp_["half_rise_shift"].values()), default=math.nan)
            top = max(cmp_["top_change_per_clearance"].values(), default=math.nan)
            rows.append((i, name, crit, rise, top, bool(reasons)))
            print(f"plant {i} {name:22s} max |critical shift| {crit:6.3f}  max |half-rise shift| {rise:6.3f}  "
                  f"max top change/c {top:6.3f}  fires {bool(reasons)}; steady: {sev} ({status})", flush=True)
    print(f"\n{args.plants} plants, {time.perf_counter() - t0:.0f} s")
    for name, _ in cases:
        k, n = sum(fired[name]), len(fired[name])
        lo, hi = wilson(k, n)
        vals = np.array([r[2:5] for r in rows if r[1] == name], dtype=float)
        med = np.nanmedian(vals, axis=0)
        print(f"{name:22s} fires {k}/{n} (95 % {lo:.2f}–{hi:.2f}); medians: critical shift {med[0]:.3f}, "
              f"half-rise shift {med[1]:.3f}, top change/c {med[2]:.3f}")
        c = calls[name]
        aligned = [x for x in c if x[0] == "aligned"]
        conf_aligned = [x for x in aligned if x[1] == "confident"]
        print(f"{'':22s} steady calls: " + ", ".join(f"{k} {sum(x[0] == k for x in c)}" for k in sorted({x[0] for x in c}))
              + f"; 'aligned' {len(aligned)}/{n} (confident {len(conf_aligned)}); the check doubts "
              f"{sum(x[2] for x in aligned)} of the 'aligned' ({sum(x[2] for x in conf_aligned)} of the confident)")


if __name__ == "__main__":
    main()
