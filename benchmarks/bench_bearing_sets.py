"""The shipped model per probe set: which instrumented bearings a verdict can be read from (models.checks.bearing_sets).

    .venv/bin/python benchmarks/bench_bearing_sets.py [--n 48] [--calibrate 816,817] [--seed 815] [--write]

Measures, on docs/robustness.md's clean base sets (held-out plants; ``bench_robustness.design``), the
model's class from each of its training probe sets alone (``train.toml`` ``[augment] bearing_sets``):
macro-F1 over the bands (all mechanisms) and the false-alarm rate on aligned machines, over the
``--calibrate`` seeds. ``--write`` stores them in ``models/default/bearing_sets.json``, the table
``models.checks.bearing_sets`` gates on (a set with more than ``MAX_FALSE_ALARM_ANY`` false alarms or a macro-F1 below
``MIN_MACRO_F1`` gives no severity; one with more than ``MAX_FALSE_ALARM`` no confident verdict).

Then, on the ``--seed`` set (not used for the table), every one of the 15 probe sets a four-bearing train can
have: the model's class from the bearings given (what the verdict read before models.checks.bearing_sets), the set the
verdict reads now, and what the user is shown — the status shares, and the aligned machines shown with a
misalignment severity (``uncertain`` or ``confident``), next to the classifier's own false-alarm rate.
"""
from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_robustness as br  # noqa: E402  (benchmarks/ on sys.path)


def clean_waveforms(n: int, seed: int, cache: Path) -> tuple[list[dict], list]:
    """The clean condition's recordings (µm, channels of bearings 1–4 at ``br.ANGLES_DEG``) of the base set."""
    cases, disps = br.simulate_set("base", n, seed, cache)
    clean = br.CONDITIONS[0]
    return cases, [None if d is None else br.measure(d, c["speed_rpm"], clean, br.measurement_rng(clean, seed, i))
                   for i, (c, d) in enumerate(zip(cases, disps))]


def run_set(bundle, cases: list[dict], waves: list, bearings: tuple[int, ...]) -> list:
    """Outcomes of every recording with the probes of ``bearings`` only (speed and clearance given)."""
    rows = [2 * (b - 1) + j for b in bearings for j in range(len(br.ANGLES_DEG))]
    outs = []
    for c, w in zip(cases, waves):
        o = br.Outcome(c["misalignment"], c["label_mechanism"], speed_rpm=float(c["speed_rpm"]))
        if w is None:
            o.status = "sim failed"
        else:
            br.diagnose_waveforms(bundle, w[rows], bearings, br.FS_HZ, c["speed_rpm"], c["plant"]["clearance_m"] * 1e6, o)
        outs.append(o)
    return outs


def figures(bundle, outs: list) -> dict:
    """Macro-F1 (all mechanisms) and false-alarm rate of the model's class, and what the user is shown."""
    s = br.summarize(bundle, outs)
    ran = [o for o in outs if o.status not in ("sim failed", "refused")]
    aligned = [o for o in ran if o.delta == 0]
    shown_fa = [o for o in aligned if o.status != "inconclusive" and o.severity not in ("aligned", "inconclusive")]
    return {"n": len(ran), "macro_f1": round(float(s["model"]["f1_all"]), 4),
            "false_alarm": round(float(s["model"]["false_alarm"]), 4),
            "status": {k: round(v, 4) for k, v in s["status"].items()},
            "shown_false_alarm": round(len(shown_fa) / len(aligned), 4) if aligned else None,
            "confident_off2": int(s["confident"]["off2"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=48)
    ap.add_argument("--calibrate", default="816,817", help="seeds of the base sets the table is measured on")
    ap.add_argument("--seed", type=int, default=815, help="seed of the base set the effect is shown on")
    ap.add_argument("--cache", type=Path, default=br.DEFAULT_CACHE)
    ap.add_argument("--write", action="store_true", help="write models/default/bearing_sets.json")
    args = ap.parse_args(argv)

    from rotordiag.models.checks import bearing_sets as bs
    from rotordiag.models.predict import ModelBundle, load_bundle

    t0 = time.perf_counter()
    registry = ROOT / "models" / "default_registry"
    bundle = load_bundle(registry)
    trained = bs.trained_sets(bundle.card)
    if trained is None:
        raise SystemExit("the shipped model's card lists no training probe sets")
    seeds = [int(s) for s in args.calibrate.split(",") if s.strip()]
    sets = [clean_waveforms(args.n, s, args.cache) for s in seeds]
    cases = [c for cs, _ in sets for c in cs]
    waves = [w for _, ws in sets for w in ws]
    table = {}
    print(f"held-out figures per training probe set (clean base sets, seeds {args.calibrate}, {len(cases)} plants):")
    print("| probe set | n | macro-F1 | false alarms | gate |")
    print("|---|---|---|---|---|")
    for s, _ in trained:
        f = figures(bundle, run_set(bundle, cases, waves, s))
        key = bs.set_key(s)
        table[key] = {"n": f["n"], "macro_f1": f["macro_f1"], "false_alarm": f["false_alarm"]}
        informative = f["false_alarm"] <= bs.MAX_FALSE_ALARM_ANY and f["macro_f1"] >= bs.MIN_MACRO_F1
        gate = ("no severity" if not informative else "never confident" if f["false_alarm"] > bs.MAX_FALSE_ALARM
                else "reads")
        print(f"| {key} | {f['n']} | {f['macro_f1']:.2f} | {f['false_alarm']:.1%} | {gate} |")
    if args.write:
        sha = hashlib.sha256((registry / str(bundle.version) / "model.skops").read_bytes()).hexdigest()
        out = {"model": {"version": bundle.card.get("version"), "created": bundle.card.get("created"), "sha256": sha},
               "gate": {"max_false_alarm": bs.MAX_FALSE_ALARM, "max_false_alarm_any": bs.MAX_FALSE_ALARM_ANY,
                        "min_macro_f1": bs.MIN_MACRO_F1},
               "figures": table,
               "source": {"command": f"benchmarks/bench_bearing_sets.py --n {args.n} --calibrate {args.calibrate} --write",
                          "what": "the model's class (before any status) from each training probe set alone, on the "
                                  "clean recordings of docs/robustness.md's base sets (held-out plants, all four "
                                  "mechanisms and aligned machines, speed and clearance given)"}}
        bs.CAPABILITY_PATH.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
        bs._read_capability.cache_clear()
        print(f"wrote {bs.CAPABILITY_PATH.relative_to(ROOT)}")

    cases, waves = clean_waveforms(args.n, args.seed, args.cache)
    # the verdict before models.checks.bearing_sets: the same model, read from every bearing given (a card without
    # training probe sets)
    before_bundle = ModelBundle(model=bundle.model, card={}, version=bundle.version)
    print(f"\nevery probe set on the base set of seed {args.seed} ({len(cases)} plants, clean), before (the model "
          "reads every bearing given) and now (it reads its answering set):")
    print("| probes at | before: macro-F1 / false alarms / aligned shown misaligned / confident two bands off | "
          "verdict reads | now: macro-F1 / false alarms (class) | now: confident / uncertain / inconclusive | "
          "now: aligned shown misaligned | now: confident two bands off |")
    print("|---|---|---|---|---|---|---|")
    for k in range(4, 0, -1):
        for s in itertools.combinations((1, 2, 3, 4), k):
            b = figures(before_bundle, run_set(before_bundle, cases, waves, s))
            f = figures(bundle, run_set(bundle, cases, waves, s))
            plan = bs.bearing_plan(bundle, s)
            reads = "none" if plan is None or plan.answering is None else bs.set_key(plan.answering)
            st = f["status"]
            print(f"| {bs.set_key(s)} | {b['macro_f1']:.2f} / {b['false_alarm']:.0%} / {b['shown_false_alarm']:.0%} / "
                  f"{b['confident_off2']} | {reads} | {f['macro_f1']:.2f} / {f['false_alarm']:.0%} | "
                  f"{st['confident']:.0%} / {st['uncertain']:.0%} / {st['inconclusive']:.0%} | "
                  f"{f['shown_false_alarm']:.0%} | {f['confident_off2']} |", flush=True)
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
