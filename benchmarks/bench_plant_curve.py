"""Learning curve of a retraining for one plant: its quality report against dataset size and wall time.

    .venv/bin/python benchmarks/bench_plant_curve.py [--preset gen600_4pole] [--sizes 32,96,256]
        [--report-cases 6] [--seed 0] [--workers 2] [--work /tmp/rotordiag_plant_curve]

Simulates the plant's dataset once at the largest size (``models.plant_retrain.plant_dataset_spec``; a Sobol
design, so the first n samples of it are the dataset of size n: same points, same per-sample seeds) and the
report's held-out recordings once; then for each size trains a model on the first n samples
(``models.train.train_and_register``, the shipped recipe), and scores it beside the shipped model on the same
held-out recordings under every measurement condition (``models.plant_retrain.quality_report``). Prints one
row per size: pooled band macro-F1, false-alarm rate, confident share, confident two-bands-off, 90 % interval
coverage, the decision, and the wall time a retrain of that size takes (the simulation and feature time per
sample measured here × n, plus the measured training and report times). docs/models.md, "Learning curve".
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import tomli_w


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--preset", default="gen600_4pole")
    ap.add_argument("--sizes", default="32,96,256")
    ap.add_argument("--train", default="", help="train and report only these of --sizes (default: all; separate "
                    "processes may share --work's simulated data and train different sizes)")
    ap.add_argument("--report-cases", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--work", type=Path, default=Path("/tmp/rotordiag_plant_curve"))
    a = ap.parse_args()
    # one OpenMP thread, as `rotordiag retrain --threads 1`: boosted trees spinning on oversubscribed shared
    # cores took minutes for a fit of seconds. Set before anything loads OpenMP: threadpoolctl limits only the
    # libraries already loaded, and scikit-learn's are loaded when training starts (a threadpool_limits(1)
    # called here left two threads spinning through the fits)
    os.environ["OMP_NUM_THREADS"] = "1"
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.models.plant_retrain import (
        describe_plant,
        drop_unmeasured,
        held_out_cases,
        pending_card,
        plant_dataset_spec,
        quality_report,
        simulate_held_out,
    )
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import Registry, shipped_registry_dir
    from rotordiag.models.train import train_and_register
    from rotordiag.simulator.dataset.generate import generate
    from rotordiag.simulator.dataset.spec import parse_spec
    sizes = sorted(int(s) for s in a.sizes.split(","))
    a.work.mkdir(parents=True, exist_ok=True)
    plant = describe_plant(preset=a.preset)
    spec = plant_dataset_spec(plant, n_samples=sizes[-1], seed=a.seed)
    data = a.work / f"{a.preset}_n{sizes[-1]}_s{a.seed}.h5"
    timing = data.with_suffix(".timing.json")    # the first run's times, kept for reruns that read the cache
    t0, c0 = time.perf_counter(), _cpu_s()
    generate(parse_spec(tomli_w.dumps(spec)), data, n_workers=a.workers, progress=False)
    sim_s, sim_cpu = time.perf_counter() - t0, _cpu_s() - c0
    cfg = TrainConfig.shipped({"seed": a.seed})
    t0, c0 = time.perf_counter(), _cpu_s()
    full = load_feature_table(data, augment=cfg.augment)
    feat_s, feat_cpu = time.perf_counter() - t0, _cpu_s() - c0
    if timing.is_file():
        t = json.loads(timing.read_text())
        sim_s, feat_s, sim_cpu, feat_cpu = t["sim_s"], t["feat_s"], t.get("sim_cpu_s", sim_cpu), t.get("feat_cpu_s", feat_cpu)
    else:
        timing.write_text(json.dumps({"sim_s": sim_s, "feat_s": feat_s, "sim_cpu_s": sim_cpu, "feat_cpu_s": feat_cpu,
                                      "workers": a.workers}))
    print(f"simulated {sizes[-1]} samples in {sim_s:.0f} s ({sim_cpu:.0f} CPU s), features in {feat_s:.0f} s "
          f"({feat_cpu:.0f} CPU s)", file=sys.stderr)
    t0, c0 = time.perf_counter(), _cpu_s()
    cases = held_out_cases(plant, a.report_cases, a.seed)
    disps = simulate_held_out(cases, cache=a.work / f"held_out_{a.preset}_k{a.report_cases}_s{a.seed}.npz")
    held_s, held_cpu = time.perf_counter() - t0, _cpu_s() - c0
    shipped = load_bundle(shipped_registry_dir())
    held_timing = a.work / f"held_out_{a.preset}_k{a.report_cases}_s{a.seed}.timing.json"
    if held_timing.is_file():                    # the first run's times (this one read the cache)
        held_s, held_cpu = json.loads(held_timing.read_text())["held_s"], json.loads(held_timing.read_text())["held_cpu_s"]
    else:
        held_timing.write_text(json.dumps({"held_s": held_s, "held_cpu_s": held_cpu, "n_cases": len(cases)}))
    shipped_outcomes: dict = {}                  # the shipped model's outcomes, scored once for every size
    rows = []
    for n in ([int(x) for x in a.train.split(",")] if a.train else sizes):
        table, _ = drop_unmeasured(full.subset(full.sample_index < n))
        reg = Registry(a.work / f"registry_n{n}")
        t0, c0 = time.perf_counter(), time.process_time()
        version, _ = train_and_register(table, cfg, reg, activate=False, card_extra=pending_card(plant))
        train_s, train_cpu = time.perf_counter() - t0, time.process_time() - c0
        t0, c0 = time.perf_counter(), time.process_time()
        first = not shipped_outcomes
        rep = quality_report(load_bundle(reg.root, version), shipped, plant, cases, disps, a.seed,
                             old_label=f"shipped {shipped.version}", old_outcomes=shipped_outcomes)
        report_s, report_cpu = time.perf_counter() - t0, time.process_time() - c0
        if first:          # a retrain scores the active model too: count that half in every size's time
            shipped_s, shipped_cpu = report_s / 2, report_cpu / 2
        else:
            report_s, report_cpu = report_s + shipped_s, report_cpu + shipped_cpu
        (a.work / f"report_n{n}.json").write_text(json.dumps(rep, indent=1, default=float))
        wall = (sim_s + feat_s) * n / sizes[-1] + train_s + held_s + report_s
        # idle 2-core wall time: the CPU seconds of every stage (worker processes included) over 2 cores
        idle2 = ((sim_cpu + feat_cpu) * n / sizes[-1] + train_cpu + held_cpu + report_cpu) / 2
        rows.append((n, len(table), rep, train_s, report_s, wall, idle2))
        print(f"n={n}: train {train_s:.0f} s wall, {train_cpu:.0f} s CPU; report {report_s:.0f} s wall, "
              f"{report_cpu:.0f} s CPU; held-out simulation {held_s:.0f} s", file=sys.stderr)

    def f(v, fmt="{:.2f}"):
        return "–" if v is None else fmt.format(v)

    print(f"{a.preset}: {len(cases)} held-out recordings × {len(rep['conditions'])} conditions "
          f"(seed {a.seed}); simulation {sim_s / sizes[-1]:.2f} s/sample, features {feat_s / sizes[-1]:.2f} s/sample "
          f"with {a.workers} worker(s)")
    print("| samples | rows | macro-F1 new (shipped) | F1 diff, 90 % interval | false alarms new (shipped) | "
          "confident new (shipped) | confident 2 bands off new (shipped) | 90 % coverage new (shipped) | "
          "Spearman Δ new (shipped) | better? | training s | retrain wall time here | idle 2-core (CPU s / 2) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n, nrows, rep, train_s, report_s, wall, idle2 in rows:
        p, b = rep["pooled"], rep["paired_bootstrap"]
        nw, sh = p["new"], p["active"]
        print(f"| {n} | {nrows} | {f(nw['macro_f1'])} ({f(sh['macro_f1'])}) | {b['macro_f1_diff_point']:+.3f} "
              f"({b['macro_f1_diff'][0]:+.3f}…{b['macro_f1_diff'][1]:+.3f}) | "
              f"{f(nw['false_alarm_rate'], '{:.1%}')} ({f(sh['false_alarm_rate'], '{:.1%}')}) | "
              f"{f(nw['confident_share'], '{:.0%}')} ({f(sh['confident_share'], '{:.0%}')}) | "
              f"{nw['confident_two_bands_off']} ({sh['confident_two_bands_off']}) | "
              f"{f(nw['interval_coverage'], '{:.0%}')} ({f(sh['interval_coverage'], '{:.0%}')}) | "
              f"{f(nw.get('spearman_delta'))} ({f(sh.get('spearman_delta'))}) | "
              f"{'yes' if rep['decision']['better'] else 'no'} | {train_s:.0f} | {wall / 60:.1f} min | "
              f"{idle2 / 60:.1f} min |")
    print(f"held-out simulation {held_s:.0f} s ({held_cpu:.0f} CPU s); numpy {np.__version__}", file=sys.stderr)


def _cpu_s() -> float:
    """CPU seconds of this process and its finished children (the dataset's worker processes)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


if __name__ == "__main__":
    main()
