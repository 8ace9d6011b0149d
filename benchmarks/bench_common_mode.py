"""How common a 1X / 2X is to every probe on held-out machines, and on the same machines with mains pickup.

    .venv/bin/python benchmarks/bench_common_mode.py [--n 48] [--seeds 815,816,817]

The thresholds of ``features._sanity.COMMON_MODE_MIN_SHARE`` (the sanity checks ``common_mode_1x`` /
``common_mode_2x``) and ``models.checks.common_mode.COMMON_MODE_REMOVE_SHARE`` (the common signal removed before the
verdict) are set from this. In family: docs/robustness.md's simulated sets (held-out plants; base sets of
``--seeds``, the far and presets sets of the first seed) under the clean, runout, SNR 15 dB and gain-mismatch
conditions; for each recording ``features.common_mode`` over every probe set of 6 or 8 probes that spans the
coupling (1-2-3-4, 1-2-3, 2-3-4, 1-2-4, 1-3-4), at 1X and 2X: the largest shares and their quantiles, per number
of probes. With pickup: the clean base set of the first seed with a signal of ``A`` µm (0-pk) at 1X or 2X added
to every channel in one random phase (a ground loop on a grid-synchronous generator): how often the share
reaches the sanity threshold and the doubt threshold.
"""
from __future__ import annotations

import argparse
import sys
import time
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_robustness as br  # noqa: E402  (benchmarks/ on sys.path)

PROBE_SETS = ((1, 2, 3, 4), (1, 2, 3), (2, 3, 4), (1, 2, 4), (1, 3, 4))
CONDITION_NAMES = ("clean", "runout", "SNR 15 dB", "gain mismatch ±10 %")
PICKUP_UM = (2.0, 5.0, 10.0, 20.0)


def _features(w: np.ndarray, case: dict):
    from rotordiag.features import ProbeChannel, Recording, extract_features

    chans = [ProbeChannel(b, a, "um", w[2 * k + j]) for k, b in enumerate((1, 2, 3, 4))
             for j, a in enumerate(br.ANGLES_DEG)]
    return extract_features(Recording(br.FS_HZ, chans, speed_rpm=case["speed_rpm"],
                                      clearance_um=case["plant"]["clearance_m"] * 1e6))


def _shares(fr, order: int) -> dict[int, list[float]]:
    """The common share at ``order`` over each probe set of :data:`PROBE_SETS`, by the number of probes judged."""
    from rotordiag.features import common_mode

    out: dict[int, list[float]] = {}
    for bearings in PROBE_SETS:
        if not set(bearings) <= set(fr.bearings):
            continue
        cm = common_mode(types.SimpleNamespace(bearings={b: fr.bearings[b] for b in bearings}), order)
        if cm is not None:
            out.setdefault(cm.n_probes, []).append(cm.share)
    return out


def in_family(n: int, seeds: list[int]) -> dict[tuple[int, int], list[float]]:
    """(order, probes) → every share measured on the held-out sets."""
    found: dict[tuple[int, int], list[float]] = {}
    sets = [("base", s) for s in seeds] + [("far", seeds[0]), ("presets", seeds[0])]
    for sim_set, seed in sets:
        cases, disps = br.simulate_set(sim_set, n, seed, br.DEFAULT_CACHE)
        for name in CONDITION_NAMES:
            cond = next(c for c in br.CONDITIONS if c.name == name)
            for i, (c, d) in enumerate(zip(cases, disps)):
                if d is None:
                    continue
                w = br.measure(d, c["speed_rpm"], cond, br.measurement_rng(cond, seed, i))
                try:
                    fr = _features(w, c)
                except ValueError:
                    continue
                for order in (1, 2):
                    for probes, v in _shares(fr, order).items():
                        found.setdefault((order, probes), []).extend(v)
    return found


def with_pickup(n: int, seed: int) -> dict[tuple[int, float], list[float]]:
    """(order, A µm) → the 8-probe share of each clean base-set recording with that pickup."""
    from rotordiag.features import common_mode

    cases, disps = br.simulate_set("base", n, seed, br.DEFAULT_CACHE)
    clean = br.CONDITIONS[0]
    out: dict[tuple[int, float], list[float]] = {}
    for i, (c, d) in enumerate(zip(cases, disps)):
        if d is None:
            continue
        w0 = br.measure(d, c["speed_rpm"], clean, br.measurement_rng(clean, seed, i))
        t_s = np.arange(w0.shape[1]) / br.FS_HZ
        phase = np.random.default_rng([seed, 4242, i]).uniform(0.0, 2.0 * np.pi)
        for order in (1, 2):
            for amp in PICKUP_UM:
                w = w0 + amp * np.cos(2.0 * np.pi * order * c["speed_rpm"] / 60.0 * t_s + phase)
                cm = common_mode(_features(w, c), order)
                out.setdefault((order, amp), []).append(np.nan if cm is None else cm.share)
    return out


def main(argv: list[str] | None = None) -> int:
    from rotordiag.features._sanity import COMMON_MODE_MIN_SHARE
    from rotordiag.models.checks.common_mode import COMMON_MODE_REMOVE_SHARE

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=48)
    ap.add_argument("--seeds", default="815,816,817")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    t0 = time.perf_counter()
    fam = in_family(args.n, seeds)
    print(f"in family (held-out sets: base {seeds}, far and presets {seeds[0]}; conditions {', '.join(CONDITION_NAMES)})")
    print("| order | probes | n | median | 99 % | 99.9 % | max | sanity threshold | removal threshold |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (order, probes), v in sorted(fam.items()):
        a = np.asarray(v)
        need = COMMON_MODE_MIN_SHARE[max(m for m in COMMON_MODE_MIN_SHARE if m <= probes)]
        q = np.percentile(a, [50, 99, 99.9])
        print(f"| {order}X | {probes} | {a.size} | {q[0]:.3f} | {q[1]:.3f} | {q[2]:.3f} | {a.max():.3f} | {need:g} "
              f"| {COMMON_MODE_REMOVE_SHARE:g} |")
    pick = with_pickup(args.n, seeds[0])
    print(f"\nwith pickup on every channel (clean base set, seed {seeds[0]}; 8 probes judged where both probes of each "
          "bearing stand out of the noise)")
    print("| order | pickup µm 0-pk | n | median share | ≥ sanity threshold (8 probes) | ≥ removal threshold |")
    print("|---|---|---|---|---|---|")
    for (order, amp), v in sorted(pick.items()):
        a = np.asarray(v)
        ok = a[np.isfinite(a)]
        print(f"| {order}X | {amp:g} | {a.size} | {np.median(ok):.3f} | {np.mean(ok >= COMMON_MODE_MIN_SHARE[8]):.0%} "
              f"| {np.mean(ok >= COMMON_MODE_REMOVE_SHARE):.0%} |")
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
