"""Verdicts of a fixed set of recordings as JSON, and what each cost: a refactor of the verdict path must not change them.

The set: the shipped examples (``rotordiag.features.examples``) and ``--n`` simulated recordings (default plant,
seed ``--seed``, speed 1500–3600 r/min, Δ 0–0.6, unbalance 0.02–0.1, rigid / pin alternating, 48 revolutions at
4096 Hz, 8 probes at 45°/135°, 1 µm white noise; every third without a stated speed, every second with the
clearance 350 µm). Each recording is diagnosed with the shipped model through the verdict path
(``models.pipeline.diagnose_recording`` when it exists, else ``models.diagnosis.diagnose_recording``) and its
``Verdict.to_dict()`` written in µm and in mil (``models.output_units.verdict_in_units``), with the number of
feature extractions, model scorings (kNN OOD passes) and whole verdicts it took and its time (median of ``--repeat``).

Usage::

    .venv/bin/python benchmarks/compare_verdicts.py --out /tmp/before.json
    .venv/bin/python benchmarks/compare_verdicts.py --out /tmp/after.json
    .venv/bin/python benchmarks/compare_verdicts.py --compare /tmp/before.json /tmp/after.json
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

SAMPLE_RATE_HZ = 4096.0
REVS = 48
CLEARANCE_UM = 350.0


def simulated(n: int, seed: int, cache: Path) -> list[tuple[str, dict]]:
    """``n`` simulated recordings as (name, arrays and options), cached in ``cache`` (an .npz) so that the
    before and after runs read the same samples."""
    if cache.exists():
        z = np.load(cache, allow_pickle=False)
        meta = json.loads(str(z["meta"]))
        return [(m["name"], {**m, "data": z[m["name"]]}) for m in meta]
    from rotordiag.simulator import Plant, simulate

    rng = np.random.default_rng(seed)
    out, meta, arrays = [], [], {}
    for i in range(n):
        speed = float(rng.uniform(1500.0, 3600.0))
        delta = float(rng.uniform(0.0, 0.6))
        unb = float(rng.uniform(0.02, 0.1))
        mech = "rigid" if i % 2 == 0 else "pin"
        res = simulate(Plant.default(), speed, delta, unb, mechanism=mech, transient_revs=200,
                       record_revs=REVS + 1, sample_rate_hz=SAMPLE_RATE_HZ)
        n_pts = int(REVS * 60.0 / speed * SAMPLE_RATE_HZ)
        d = res.journal_displacements_m[:n_pts] * 1e6
        rows = [d[:, b - 1, 0] * np.cos(np.deg2rad(a)) + d[:, b - 1, 1] * np.sin(np.deg2rad(a))
                for b in range(1, 5) for a in (45.0, 135.0)]
        data = np.array(rows) + rng.normal(0.0, 1.0, size=(8, n_pts))
        name = f"sim{i:02d}"
        m = {"name": name, "speed_rpm": None if i % 3 == 2 else speed, "delta": delta, "mechanism": mech,
             "clearance_um": CLEARANCE_UM if i % 2 == 1 else None}
        meta.append(m)
        arrays[name] = data
        out.append((name, {**m, "data": data}))
    np.savez(cache, meta=json.dumps(meta), **arrays)
    return out


def recording_of(spec: dict):
    from rotordiag.features import ProbeChannel, Recording

    chans = [ProbeChannel(bearing=b, angle_deg=a, units="um", data=row)
             for (b, a), row in zip([(b, a) for b in range(1, 5) for a in (45.0, 135.0)], spec["data"])]
    return Recording(sample_rate_hz=SAMPLE_RATE_HZ, channels=chans, speed_rpm=spec["speed_rpm"],
                     clearance_um=spec["clearance_um"])


def examples() -> list[tuple[str, object]]:
    from rotordiag.features.examples import example_path
    from rotordiag.models.diagnose_files import load_options, read_recording

    out = []
    for name in ("aligned.csv", "aligned.h5", "whirl.csv", "whirl.h5", "whirl.uff", "whirl_2560hz.npy"):
        path = example_path(name)
        opts = load_options(path, None, {"sample_rate_hz": 2560} if path.suffix == ".npy" else {})
        out.append((name, read_recording(path, options=opts).recording))
    return out


class Counter:
    """Counts feature extractions and kNN OOD passes by wrapping the functions every module of the models
    package bound."""

    def __init__(self) -> None:
        import rotordiag.features as feat
        from rotordiag.models import compiled

        self.extractions = 0
        self.scorings = 0
        orig = feat.extract_features

        def counted(*a, **k):
            self.extractions += 1
            return orig(*a, **k)

        for name, mod in list(sys.modules.items()):
            if name.startswith("rotordiag.models") and getattr(mod, "extract_features", None) is orig:
                mod.extract_features = counted
        ood = compiled.CompiledModel.ood_ratio

        def counted_ood(model, X):
            self.scorings += 1
            return ood(model, X)

        compiled.CompiledModel.ood_ratio = counted_ood
        self.verdicts = 0                  # whole verdicts made: predict._diagnose before the pipeline, verdict_of after
        for modname, attr in (("rotordiag.models.predict", "_diagnose"), ("rotordiag.models.pipeline", "verdict_of")):
            mod = sys.modules.get(modname)
            if mod is not None and hasattr(mod, attr):
                setattr(mod, attr, self._counting(getattr(mod, attr)))

    def _counting(self, fn):
        def counted(*a, **k):
            self.verdicts += 1
            return fn(*a, **k)
        return counted

    def reset(self) -> tuple[int, int]:
        got = (self.extractions, self.scorings)
        self.extractions = self.scorings = self.verdicts = 0
        return got


def run(args) -> None:
    from rotordiag.models.output_units import verdict_in_units
    from rotordiag.models.predict import load_bundle
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR

    try:
        from rotordiag.models.pipeline import diagnose_recording
        path = "models.pipeline"
    except ImportError:
        from rotordiag.models.diagnosis import diagnose_recording
        path = "models.diagnosis"
    bundle = load_bundle(SHIPPED_REGISTRY_DIR)
    items = examples() + [(n, recording_of(s)) for n, s in simulated(args.n, args.seed, Path(args.cache))]
    counter = Counter()
    out: dict = {"path": path, "recordings": {}}
    for name, rec in items:
        clearance = rec.clearance_um if isinstance(rec.clearance_um, (int, float)) else None
        times = []
        for _ in range(args.repeat):
            counter.reset()
            t0 = time.perf_counter()
            verdict, fr = diagnose_recording(bundle, rec, clearance_um=clearance)
            times.append(time.perf_counter() - t0)
        n_ext, n_score, n_verdicts = counter.extractions, counter.scorings, counter.verdicts   # of the last repeat
        d = verdict.to_dict()
        out["recordings"][name] = {
            "um": json.loads(json.dumps(verdict_in_units(d, "um"), default=str, allow_nan=True)),
            "mil": json.loads(json.dumps(verdict_in_units(d, "mil"), default=str, allow_nan=True)),
            "extractions": n_ext, "scorings": n_score, "verdicts": n_verdicts, "ms": 1e3 * float(np.median(times)),
            "speed_source": fr.speed_source, "speed_rpm": fr.speed_rpm}
        print(f"{name:18s} {verdict.status:12s} {verdict.severity:12s} ood {verdict.ood_score:6.2f} "
              f"extractions {n_ext:2d} scorings {n_score:2d} verdicts {n_verdicts:2d} {1e3 * np.median(times):7.1f} ms")
    Path(args.out).write_text(json.dumps(out, indent=1, sort_keys=True, default=str))


def compare(a: str, b: str) -> int:
    A, B = json.loads(Path(a).read_text()), json.loads(Path(b).read_text())
    bad = 0
    for name, ra in A["recordings"].items():
        rb = B["recordings"].get(name)
        added = sorted(set(rb["um"]) - set(ra["um"])) if rb is not None else []
        same = rb is not None and all(ra[u] == {k: v for k, v in rb[u].items() if k not in added} for u in ("um", "mil"))
        if added:
            print(f"{name:18s} new fields (not compared): {', '.join(added)}")
        bad += not same
        print(f"{name:18s} {'identical' if same else 'DIFFERENT'}  extractions {ra['extractions']} → "
              f"{rb and rb['extractions']}, scorings {ra['scorings']} → {rb and rb['scorings']}, "
              f"verdicts {ra.get('verdicts')} → {rb and rb.get('verdicts')}, "
              f"{ra['ms']:.1f} → {rb and rb['ms']:.1f} ms")
    print(f"{A['path']} → {B['path']}: {len(A['recordings']) - bad} of {len(A['recordings'])} verdicts identical "
          "(to_dict JSON in µm and mil)")
    return 1 if bad else 0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out")
    p.add_argument("--compare", nargs=2)
    p.add_argument("--n", type=int, default=30)
    p.add_argument("--seed", type=int, default=4343)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--cache", default=str(Path(os.environ.get("TMPDIR", "/tmp")) / "compare_verdicts_sims.npz"))
    args = p.parse_args()
    if args.compare:
        raise SystemExit(compare(*args.compare))
    run(args)


if __name__ == "__main__":
    main()
