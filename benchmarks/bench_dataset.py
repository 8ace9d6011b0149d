"""Dataset generation throughput: samples/min on 1 and 2 Dask workers, scaling, bytes/sample, peak RSS.

A fixed 40-sample spec (Sobol over Δ, A, Ω, phases, pin/rigid mix, ±10 % plant
perturbations; MODEL.md's 400 transient revolutions; 8 channels × 1 s at
2560 Hz) is generated

* serially in one process (``--workers 0``: the baseline a user would write as a
  plain loop over ``simulate``),
* on a LocalCluster with 1 and with 2 worker processes,

each into a fresh file, each in its own subprocess so peak RSS is per run.
The same 40 samples (same spec, same values) are computed in every run.
Reported per run:

* ``total s`` / ``e2e /min``: the whole ``generate`` call (spec, design, file,
  cluster start-up, samples), the figure a user sees;
* ``start s``: the part of it before the first task is submitted (spec and
  design, output file, LocalCluster with its worker processes started);
* ``gen /min``: samples/min from the first task submitted to the last sample
  written, i.e. without the start-up (includes the workers' first-task warm-up:
  imports and loading the numba cache);
* ``steady /min``: after the first sample written (the older figure);
* bytes per sample on disk, peak RSS of the parent and of its worker processes;
* CPU: the parent's CPU per sample while samples are coming in (between the
  first and the last sample written: writing, the Dask scheduler, nannies and
  client, which all live in the parent), and the CPU of all processes per
  sample over the whole run;
* the 1-minute load average before and after the run (scaling needs two
  otherwise idle cores).

Then the 2-vs-1-worker scaling ratio on each figure (target ≥ 1.8× on two free
cores), the parent's write cost per sample (the ceiling on any cluster's
throughput into one file), and the parent's peak RSS for 20 vs 160 samples
(serial, short simulations), which shows memory does not grow with the sample
count.

Run: ``.venv/bin/python benchmarks/bench_dataset.py`` (about 1–2 minutes on two free cores).

``--steady-start N`` instead compares the two ways a record starts (issue 16 item 4) on the
shipped default-model specs (models/default/dataset_*.toml, each cut to its first N Sobol
samples: ``n_samples = N``): each is generated serially in one process (one core) with
``simulation.steady_start = "integrate"`` (400 transient revolutions: the old path) and
``"shooting"``; it prints samples/min of each, the ratio, how many samples took the shooting
start, the ratio over just those samples (sum of their per-sample times), the largest
waveform difference between the two files and whether every label is equal.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import traceback
from pathlib import Path

SPEC = """
[design]
method = "sobol"
n_samples = {n}
seed = 2024
[operating]
speed_rpm = {{min = 1200, max = 3000}}
misalignment = {{min = 0.0, max = 0.6}}
unbalance = {{min = 0.02, max = 0.1}}
unbalance_phase_rad = {{min = 0.0, max = 6.283185307179586}}
offset_angle_rad = {{min = 0.0, max = 6.283185307179586}}
mechanism = {{pin = 1, rigid = 1}}
[plant.perturb]
generator_mass_kg = 0.1
exciter_mass_kg = 0.1
generator_stiffness_n_m = 0.1
asymmetry = 0.3
viscosity_pa_s = 0.1
[measurement]
sample_rate_hz = 2560.0
duration_s = 1.0
snr_db = {{min = 25, max = 45}}
runout_1x_um = {{min = 0, max = 3}}
runout_2x_um = {{min = 0, max = 1}}
speed_fluctuation = 0.002
[simulation]
transient_revs = {transient}
record_revs_min = 64
"""

CHILD = r"""
import json, os, resource, sys, time
from rotordiag.simulator.dataset.generate import generate
spec, out, workers = sys.argv[1], sys.argv[2], int(sys.argv[3])
cpu = []   # the parent's CPU time (all its threads) at each sample written
load0 = os.getloadavg()[0]
s = generate(spec, out, n_workers=workers, progress=False,
             on_progress=lambda k, n: cpu.append(time.process_time()))
load1 = os.getloadavg()[0]
me, ch = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
ru_self, ru_children = me.ru_maxrss / 1024, ch.ru_maxrss / 1024
print(json.dumps({"n": s.n_computed, "elapsed_s": s.elapsed_s, "first_s": s.first_sample_s,
                  "startup_s": s.startup_s, "gen_rate": s.generation_rate_per_s,
                  "steady_rate": s.steady_rate_per_s, "bytes": os.path.getsize(out),
                  "rss_parent_mb": ru_self, "rss_children_mb": ru_children, "status": s.status_counts,
                  "cpu_parent_s": me.ru_utime + me.ru_stime, "cpu_children_s": ch.ru_utime + ch.ru_stime,
                  "cpu_parent_steady_s": (cpu[-1] - cpu[1]) / max(1, len(cpu) - 2), "load": [load0, load1]}))
"""


def run(spec: Path, out: Path, workers: int) -> dict:
    res = subprocess.run([sys.executable, "-c", CHILD, str(spec), str(out), str(workers)],
                         capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def writer_cost_ms(tmp: Path, n: int = 64) -> tuple[float, float]:
    """Parent-side cost of writing one sample (rows, the worker-compressed waveform chunk, two SWMR flushes):
    the ceiling on cluster throughput; and the worker-side cost of compressing the chunk."""
    import time

    import numpy as np

    from rotordiag.simulator.dataset.design import build_design
    from rotordiag.simulator.dataset.generate import _dataset_attrs, _file_attrs, _rows
    from rotordiag.simulator.dataset.measurement import MeasurementSettings, draw_measurement
    from rotordiag.simulator.dataset.spec import load_spec
    from rotordiag.simulator.dataset.store import DatasetWriter, encode_waveform_chunk, layout
    from rotordiag.simulator.dataset.worker import SampleOutput

    spec = tmp / "writer.toml"
    spec.write_text(SPEC.format(n=n, transient=400))
    r = load_spec(spec)
    d, m = build_design(r), MeasurementSettings.from_spec(r.spec)
    L = layout(len(m.channels), m.n_points, len(m.bearings), r.base_plant.to_dict())
    w = DatasetWriter.open(tmp / "writer.h5", n_samples=n, spec_hash=r.spec_hash, L=L, channels=m.channels,
                           attrs=_file_attrs(r, d, m), dataset_attrs=_dataset_attrs(), code_version="bench")
    rng = np.random.default_rng(0)
    t = np.arange(m.n_points) / m.sample_rate_hz
    total = encode = 0.0
    try:
        for i in range(n):
            wave = (50 * np.sin(2 * np.pi * 30 * t)[None, :] + rng.normal(size=(len(m.channels), m.n_points)))
            t0 = time.process_time()
            chunk = encode_waveform_chunk(wave.astype(np.float32))  # done by the worker (run_sample_encoded)
            encode += time.process_time() - t0
            out = SampleOutput(i, chunk, draw_measurement(m, rng), "ok", "pin", 64)
            t0 = time.process_time()
            w.write_sample(i, {k: v for k, v in _rows(d[i], out).items() if k in L})  # as generate() writes
            total += time.process_time() - t0
    finally:
        w.close()
    return 1e3 * total / n, 1e3 * encode / n


SHIPPED = sorted((Path(__file__).resolve().parent.parent / "models" / "default").glob("dataset_*.toml"))


#: the ways a record may start, in the order each sample runs them (back to back, so they share the load)
#: (steady_start, transient_stop, integrator): the path before issue 16 first (the baseline), then the
#: default now (shooting start, explicit integration handing stiff runs to LSODA), then the opt-in stop.
MODES = (("integrate", "fixed", "explicit"), ("shooting", "fixed", "auto"), ("shooting", "stationary", "auto"))
KEYS = ["/".join(m) for m in MODES]
BASE = KEYS[0]
STEADY_CHILD = r"""
import json, resource, sys
sys.path.insert(0, sys.argv[3])
from bench_dataset import steady_start_rows
rows = steady_start_rows(int(sys.argv[1]), sys.argv[2] == "1", int(sys.argv[4]))
print(json.dumps({"rows": rows, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def _sample_kind(out) -> str:
    """period-1 (shot), or the fallback's kind from its note: handed to the stiff solver, stopped once
    stationary, or neither."""
    if out.steady_start == "shooting":
        return "period-1"
    if "stiff from rev" in out.steady_note:
        return "fallback stiff"
    return "fallback stationary" if "(stationary)" in out.steady_note else "fallback full"


def steady_start_rows(n: int, floor: bool, offset: int = 0) -> list[dict]:
    """Samples ``offset`` … ``offset + n − 1`` of every shipped spec (Sobol: the same as in the full design), run with every start in MODES back to back
    (plus, with ``floor``, 800 transient revolutions for the samples that fall back)."""
    import dataclasses
    import fnmatch
    import re

    from rotordiag.features import FEATURE_NAMES, ProbeChannel, Recording, extract_features
    from rotordiag.simulator.dataset.design import build_design
    from rotordiag.simulator.dataset.measurement import MeasurementSettings
    from rotordiag.simulator.dataset.spec import parse_spec
    from rotordiag.simulator.dataset.worker import SampleTask, SimulationSettings, run_sample

    used = [not fnmatch.fnmatch(f, "b?_[xy]_[123]x_phase_deg") for f in FEATURE_NAMES]  # train.toml's exclude

    def features(out, meas, p) -> list[float]:
        try:  # a sample that ended in contact has NaN after it: no features (as in the feature table)
            rec = Recording(sample_rate_hz=meas.sample_rate_hz, speed_rpm=p.speed_rpm,
                            clearance_um=p.plant["clearance_m"] * 1e6,
                            channels=[ProbeChannel(bearing=b, angle_deg=a, units="um", data=out.waveforms_um[c])
                                      for c, (b, a) in enumerate(meas.channels)])
            return [float(v) for v, u in zip(extract_features(rec).values, used) if u]
        except ValueError:
            return [float("nan")] * sum(used)

    rows = []
    for path in SHIPPED:
        text = re.sub(r"(?m)^n_samples = \d+", f"n_samples = {n + offset}", path.read_text())
        resolved = parse_spec(text, base_dir=path.parent)
        design, meas = build_design(resolved), MeasurementSettings.from_spec(resolved.spec)
        sim = SimulationSettings.from_spec(resolved.spec)
        if not rows:  # load the compiled kernels' cache before anything is timed
            run_sample(SampleTask(design[0], dataclasses.replace(sim, transient_revs=4), meas))
        for i in range(offset, len(design)):
            try:
                rows.append(_steady_start_row(path.stem, i, design[i], sim, meas, floor, features))
            except Exception as exc:  # noqa: BLE001 - a benchmark reports and goes on
                traceback.print_exc()
                print(f"{path.stem} sample {i}: {type(exc).__name__}: {exc}", file=sys.stderr)
    return rows


def _steady_start_row(stem: str, i: int, p, sim, meas, floor: bool, features) -> dict:
    import dataclasses
    import time

    import numpy as np

    from rotordiag.simulator.dataset.worker import SampleTask, run_sample

    row: dict = {"spec": stem, "index": i}
    for start, stop, integrator in MODES:
        t0 = time.perf_counter()
        task = SampleTask(p, dataclasses.replace(sim, steady_start=start, transient_stop=stop, integrator=integrator),
                          meas)
        out = run_sample(task)
        key = f"{start}/{stop}/{integrator}"
        row[key] = {"s": time.perf_counter() - t0, "kind": _sample_kind(out), "note": out.steady_note,
                    "labels": [out.status, out.simulated_mechanism, out.motion_kind, out.motion_period],
                    "features": features(out, meas, p),
                    "wave": out.waveforms_um.astype(float).tolist() if start == "integrate" else None}
        if start != "integrate":
            ref = np.array(row[BASE]["wave"])
            diff = np.abs(out.waveforms_um - ref)
            row[key]["dwave_um"] = float(np.nanmax(diff)) if np.isfinite(diff).any() else float("nan")
    row[BASE]["wave"] = None
    if floor and row[KEYS[2]]["kind"] != "period-1":
        out = run_sample(SampleTask(p, dataclasses.replace(sim, steady_start="integrate", integrator="explicit",
                                                           transient_revs=2 * sim.transient_revs), meas))
        row["floor"] = {"features": features(out, meas, p)}
    return row


def compare_steady_start(n: int, floor: bool, offset: int = 0) -> None:
    """Samples/min of the three starts on the shipped specs, by sample kind, and the features' deviation."""
    import numpy as np

    load0 = os.getloadavg()[0]
    res = subprocess.run([sys.executable, "-c", STEADY_CHILD, str(n), "1" if floor else "0",
                          str(Path(__file__).resolve().parent), str(offset)], stdout=subprocess.PIPE, text=True,
                         check=True)
    data = json.loads(res.stdout.strip().splitlines()[-1])
    rows = data["rows"]
    print(f"steady start: shipped default-model specs, samples {offset}-{offset + n - 1} of each ({len(rows)}), each sample run with "
          f"every start back to back, in one process (one core); load {load0:.2f} -> {os.getloadavg()[0]:.2f}; "
          f"peak RSS {data['rss_mb']:.0f} MiB")
    keys = KEYS
    print(f"{'spec':<26}" + "".join(f"{k + ' /min':>28}" for k in keys) + f"{'x default':>10}{'x stationary':>13}")
    groups = {stem.stem: [r for r in rows if r["spec"] == stem.stem] for stem in SHIPPED}
    groups["all"] = rows
    for name, rs in groups.items():
        if not rs:
            continue
        rate = [60 * len(rs) / sum(r[k]["s"] for r in rs) for k in keys]
        print(f"{name:<26}" + "".join(f"{v:>28.1f}" for v in rate) + f"{rate[1] / rate[0]:>10.2f}{rate[2] / rate[0]:>13.2f}")
    print("by sample kind (as the default run them; seconds summed over the samples):")
    print(f"{'kind':<22}{'n':>4}" + "".join(f"{k + ' s':>28}" for k in keys) + f"{'share':>7}{'x default':>10}"
          f"{'x stationary':>13}{'transient revs (stationary)':>29}")
    total0 = sum(r[keys[0]]["s"] for r in rows)
    kinds = ("period-1", "fallback stiff", "fallback full")
    for kind in kinds:
        rs = [r for r in rows if r[keys[1]]["kind"] == kind]
        if not rs:
            continue
        t = [sum(r[k]["s"] for r in rs) for k in keys]
        revs = [int(m.group(1)) if (m := re.search(r"transient (\d+)/", r[keys[2]]["note"]))
                else 0 if kind == "period-1" else 400 for r in rs]
        print(f"{kind:<22}{len(rs):>4}" + "".join(f"{v:>28.1f}" for v in t) + f"{t[0] / total0:>7.0%}"
              f"{t[0] / t[1]:>10.2f}{t[0] / t[2]:>13.2f}{f'{min(revs)}-{max(revs)}':>29}")
    for k in keys[1:]:
        differ = [r for r in rows if r[k]["labels"] != r[keys[0]]["labels"]]
        print(f"labels (status, simulated mechanism, motion) of {k} equal to {keys[0]}'s: "
              f"{len(rows) - len(differ)}/{len(rows)}" + "".join(
                  f"; {r['spec']}[{r['index']}] {r[keys[0]]['labels'][0]} -> {r[k]['labels'][0]} ({r[k]['kind']})"
                  for r in differ))
    shot = [r for r in rows if r[keys[1]]["kind"] == "period-1"]
    print(f"largest waveform difference of the period-1 samples: "
          f"{max((r[keys[1]]['dwave_um'] for r in shot), default=float('nan')):.1e} um")
    X0 = np.array([r[keys[0]]["features"] for r in rows])
    scale = np.nanstd(X0, axis=0)
    scale[~(scale > 0)] = np.nan

    def dev(rs, k) -> np.ndarray:
        a = np.array([r[k]["features"] for r in rs])
        b = np.array([r[keys[0]]["features"] for r in rs])
        return np.nanmax(np.abs(a - b) / scale, axis=1)  # per sample: the worst feature

    for k in keys[1:]:
        for kind in kinds[1:]:
            rs = [r for r in rows if r[keys[1]]["kind"] == kind
                  and r[k]["labels"][0] == "ok" and r[keys[0]]["labels"][0] == "ok"]
            if not rs:
                continue
            d = dev(rs, k)
            line = f"{k}, {kind} ({len(rs)} ok in both): worst standardised feature deviation from the 400-rev " \
                   f"record, per sample: median {np.nanmedian(d):.3f}, max {np.nanmax(d):.3f}"
            fl = [r for r in rs if "floor" in r]
            if fl:
                f = dev(fl, "floor")
                line += f"; the 400-rev record's own (400 vs 800 revs): median {np.nanmedian(f):.3f}, " \
                        f"max {np.nanmax(f):.3f}"
            print(line)
    print(f"(x: samples/min ratio against {keys[0]}, the path before issue 16 (400 transient revolutions, "
          f"Dormand-Prince throughout); {keys[1]}: the default now (shooting start; fallbacks integrate the full "
          f"transient, handed to LSODA where they become stiff); {keys[2]}: the opt-in stop, fallbacks end their "
          "transient once stationary; standardised deviation: |feature - 400-rev feature| / the feature's standard "
          "deviation over these samples, largest over the model's features (phases excluded), per sample)")


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steady-start", type=int, default=0, metavar="N",
                    help="compare the shooting and integration starts on the first N samples of each shipped spec")
    ap.add_argument("--floor", action="store_true",
                    help="with --steady-start: also run 800 transient revolutions for the fallback samples (the "
                         "400-revolution reference's own spread)")
    ap.add_argument("--offset", type=int, default=0, metavar="K",
                    help="with --steady-start: samples K..K+N-1 of each spec instead of the first N")
    args = ap.parse_args()
    if args.steady_start > 0:
        compare_steady_start(args.steady_start, args.floor, args.offset)
        return
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        spec = tmp / "bench.toml"
        spec.write_text(SPEC.format(n=40, transient=400))
        # warm the numba cache once so no run pays for compilation
        warm = tmp / "warm.toml"
        warm.write_text(SPEC.format(n=1, transient=10))
        run(warm, tmp / "warm.h5", 0)

        print(f"dataset benchmark: 40 samples, 400 transient revs + ≥64 recorded, 8 ch × 2560 points; "
              f"cpus available {len(os.sched_getaffinity(0))}, load {os.getloadavg()[0]:.2f}")
        print(f"{'mode':<11}{'total s':>8}{'start s':>8}{'e2e /min':>9}{'gen /min':>9}{'steady /min':>12}"
              f"{'B/sample':>9}{'RSS MB parent/worker':>21}{'parent CPU ms/sample':>21}"
              f"{'all CPU s/sample':>17}{'load before/after':>18}")
        results = {}
        for label, workers in (("serial", 0), ("1 worker", 1), ("2 workers", 2)):
            r = run(spec, tmp / f"{workers}.h5", workers)
            results[label] = r
            rss = f"{r['rss_parent_mb']:.0f}/{r['rss_children_mb']:.0f}" if workers else f"{r['rss_parent_mb']:.0f}/-"
            print(f"{label:<11}{r['elapsed_s']:>8.1f}{r['startup_s']:>8.1f}{60 * r['n'] / r['elapsed_s']:>9.1f}"
                  f"{60 * r['gen_rate']:>9.1f}{60 * r['steady_rate']:>12.1f}{r['bytes'] / r['n']:>9.0f}"
                  f"{rss:>21}{1e3 * r['cpu_parent_steady_s']:>21.1f}"
                  f"{(r['cpu_parent_s'] + r['cpu_children_s']) / r['n']:>17.3f}"
                  f"{r['load'][0]:>11.2f}/{r['load'][1]:.2f}")
        one, two, ser = results["1 worker"], results["2 workers"], results["serial"]
        print(f"scaling 2 vs 1 worker: end-to-end {one['elapsed_s'] / two['elapsed_s']:.2f}x, "
              f"generation (without start-up) {two['gen_rate'] / one['gen_rate']:.2f}x, "
              f"steady-state {two['steady_rate'] / one['steady_rate']:.2f}x (target >= 1.8x)")
        print(f"2 workers vs serial loop (baseline): end-to-end {ser['elapsed_s'] / two['elapsed_s']:.2f}x, "
              f"generation {two['gen_rate'] / ser['gen_rate']:.2f}x, "
              f"steady-state {two['steady_rate'] / ser['steady_rate']:.2f}x")
        print(f"status counts: {two['status']}")
        print("(scaling needs two otherwise idle cores: compare the load above with the worker count; "
              "CPU s/sample shows the work itself, independent of load)")

        ms, enc = writer_cost_ms(tmp)
        print(f"parent write cost: {ms:.1f} CPU ms/sample (rows + compressed chunk + 2 SWMR flushes) -> at most "
              f"{1000 / ms:.0f} samples/s into one file, whatever the cluster size; compressing the chunk "
              f"(in the worker): {enc:.1f} CPU ms/sample")
        print("memory vs sample count (serial, 50 transient revs):")
        for n in (20, 160):
            s = tmp / f"mem{n}.toml"
            s.write_text(SPEC.format(n=n, transient=50))
            r = run(s, tmp / f"mem{n}.h5", 0)
            print(f"  {n:>4} samples: peak RSS {r['rss_parent_mb']:.0f} MB, file {r['bytes'] / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
