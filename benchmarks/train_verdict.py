"""The verdict on finite-element shaft trains: the shipped model, and models trained on trains with each machine
family held out, on the same held-out recordings, with the 2X/1X rule of thumb beside them.

The recordings are the shaft-train datasets of ``models/trains/`` (``[plant] model = "train"``: each rotor on its
own bearings, the coupling overhung, misaligned by moving the exciter's bearings; runout, noise and speed
fluctuation in every sample). Build them first (about 0.5–2 s per sample per core)::

    for p in trains_2pole trains_2pole_aligned trains_4pole trains_4pole_aligned; do
        rotordiag dataset generate models/trains/dataset_$p.toml --out data/trains/$p.h5
    done
    for p in trains_2pole trains_2pole_aligned trains_4pole trains_4pole_aligned; do   # training machines
        rotordiag dataset generate models/default/dataset_$p.toml --out data/trains_more/$p.h5
    done
    python benchmarks/train_verdict.py --data data/trains --train-data data/trains_more --out docs/train-verdict.md

Held out (default; ``--no-holdout`` skips it): for each family (preset) a model is trained, with
``models/default/train.toml``'s configuration, on the other families' recordings only (``--train-data``'s when
given, else ``--data``'s), and judged on the held-out family's — machines of a design it never saw. With
``--train-data`` a model trained on every family of those sets is judged too: machines of known designs that it
never saw. The shipped model is judged whatever its training. Each recording is judged four ways:
speed and clearance stated; clearance not stated; speed not stated; clearance not stated with the machine's plant
model declared (``train:PRESET``, as an asset's plant model: ``models.checks.family``). Figures per family, per coupling and per
condition; ``robustness.summarize``'s definitions (false alarm: a healthy train given any misalignment class).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

PARTS = ("trains_2pole", "trains_2pole_aligned", "trains_4pole", "trains_4pole_aligned")
CONDITIONS = ("speed and clearance stated", "clearance not stated", "speed not stated",
              "clearance not stated, plant model declared")


def read_samples(data: Path) -> list[dict]:
    """Every finished, ok sample of the shaft-train sets: waveforms and what the verdict is judged against."""
    out = []
    for part in PARTS:
        path = data / f"{part}.h5"
        if not path.is_file():
            raise SystemExit(f"{path} is missing: generate models/trains/dataset_{part}.toml first (module docstring)")
        with h5py.File(path, "r") as f:
            codes = {v: k for k, v in json.loads(f["labels/status"].attrs["codes_json"]).items()}
            mcodes = {v: k for k, v in json.loads(f["parameters/simulated_mechanism"].attrs["codes_json"]).items()}
            chans = [(int(b), float(a)) for b, a in f["channels"][...]]
            bearings = tuple(dict.fromkeys(b for b, _ in chans))
            ok = f["done"][...].astype(bool) & np.array([codes[int(s)] == "ok" for s in f["labels/status"][...]])
            for i in np.flatnonzero(ok):
                out.append({
                    "part": part, "index": int(i), "waveforms_um": f["waveforms"][i].astype(float),
                    "bearings": bearings, "fs_hz": float(f.attrs["sample_rate_hz"]),
                    "speed_rpm": float(f["parameters/speed_rpm"][i]),
                    "clearance_um": float(f["parameters/plant/clearance_m"][i]) * 1e6,
                    "delta": float(f["labels/misalignment"][i]),
                    "mechanism": mcodes[int(f["parameters/simulated_mechanism"][i])],
                    "family": f["parameters/plant_source"][i].decode().removeprefix("preset:"),
                    "offset_angle_rad": float(f["parameters/offset_angle_rad"][i]),
                    "log_decrement": float(f["diagnostics/log_decrement"][i]),
                })
    return out


def judge(bundle, samples: list[dict], condition: str) -> list:
    """One :class:`~rotordiag.models.robustness.Outcome` per sample under ``condition``."""
    from rotordiag.models.robustness import Outcome, diagnose_waveforms

    outs = []
    for s in samples:
        o = Outcome(s["delta"], s["mechanism"], machine=s["family"], speed_rpm=s["speed_rpm"])
        diagnose_waveforms(bundle, s["waveforms_um"], s["bearings"], s["fs_hz"],
                           None if condition == "speed not stated" else s["speed_rpm"],
                           None if condition.startswith("clearance not stated") else s["clearance_um"], o,
                           plant_model=f"train:{s['family']}" if condition.endswith("plant model declared") else None)
        outs.append(o)
    return outs


def family_tables(data: Path, config_path: Path | None) -> tuple[object, np.ndarray]:
    """The feature table of every set (with the configuration's augmentation; ``config_path`` None: the rows as
    stored) and each row's family."""
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.models.table import FeatureTable

    augment = None if config_path is None else TrainConfig.from_file(config_path).augment
    tables, fams = [], []
    for part in PARTS:
        path = data / f"{part}.h5"
        t = load_feature_table(path, augment=augment)
        with h5py.File(path, "r") as f:
            src = np.array([s.decode().removeprefix("preset:") for s in f["parameters/plant_source"][...]], dtype=object)
        tables.append(t)
        fams.append(src[t.sample_index])
    return FeatureTable.concat(tables), np.concatenate(fams)


def train_without(table, families: np.ndarray, held_out: str, config_path: Path, root: Path,
                  n_splits: int | None = None):
    """A model trained, as ``rotordiag train`` does, on every family but ``held_out`` ("": every family); its
    bundle."""
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import Registry
    from rotordiag.models.train import train_and_register

    config = TrainConfig.from_file(config_path)
    if n_splits is not None:      # the held-out family is the evaluation that matters here: fewer inner folds
        config = dataclasses.replace(config, n_splits=n_splits)
    from rotordiag.models.families import families_of_specs, specs_of_meta

    sub = table.subset(np.flatnonzero(families != held_out))
    registry = Registry(root / (held_out or "every_family"))
    # the card's families are its specs' less the family whose rows were left out (the specs name every preset)
    trained = [f for f in families_of_specs(specs_of_meta(sub.meta))
               if not (held_out and f.endswith(f"preset:{held_out}"))]
    train_and_register(sub, config, registry, card_extra={"training_families": trained})
    return load_bundle(registry.root)


def rows_by(outs: list, key) -> dict[str, list]:
    groups: dict[str, list] = {}
    for o in outs:
        groups.setdefault(key(o), []).append(o)
    return dict(sorted(groups.items()))


def _by_family(md: str) -> str:
    """robustness' tables name their first column "condition"; here the rows are machine families."""
    return md.replace("| condition |", "| family |", 1)


def report(results: dict[str, dict[str, list]], bundles: dict[str, object], n_samples: int, elapsed_s: float) -> str:
    from rotordiag.models.robustness import confident_table, summarize, table

    lines = ["# The verdict on shaft trains", "",
             "Generated by `benchmarks/train_verdict.py` (its docstring says how to rebuild the recordings); "
             f"{n_samples} recordings of finite-element shaft trains, {elapsed_s / 60:.0f} min.", ""]
    for who, by_condition in results.items():
        if who not in bundles or not any(by_condition.values()):   # a held-out model still training
            continue
        bundle = bundles[who]
        lines += [f"## {who}", ""]
        for cond, outs in by_condition.items():
            rows = {f"{fam}": summarize(bundle, o) for fam, o in rows_by(outs, lambda o: o.machine).items()}
            rows["all families"] = summarize(bundle, outs)
            lines += [f"### {cond}", "", "Model:", "", _by_family(table(rows, "model")), "",
                      "2X/1X rule of thumb (cuts 0.5, 1, 2):",
                      "", _by_family(table(rows, "rule")), "", "Confident answers:", "", _by_family(confident_table(rows)), ""]
    return "\n".join(lines)


def judged_name(bundle, shipped: bool) -> str:
    """The judged model's heading: its version and the families its card says it was trained on."""
    from rotordiag.models.families import describe_family, training_families

    families = training_families(bundle.card)
    trains = [describe_family(f).removesuffix(" (finite-element train)") for f in families if f.startswith("train:")]
    lumped = ["the paper's lumped model"] if any(f.startswith("lumped:") for f in families) else []
    seen = ("trained on the trains " + ", ".join(trains) if trains else "never saw a train")
    seen += (" and " if trains and lumped else "; trained on " if lumped else "") + "".join(lumped)
    return f"{'shipped' if shipped else 'judged'} model {bundle.version} ({seen})"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("data/trains"))
    ap.add_argument("--registry", type=Path, default=None, help="the model to judge (default: the shipped one)")
    ap.add_argument("--config", type=Path, default=Path("models/default/train.toml"))
    ap.add_argument("--no-holdout", action="store_true", help="judge the shipped model only")
    ap.add_argument("--out", type=Path, default=None, help="write the report (markdown) here (rewritten as parts finish)")
    ap.add_argument("--train-data", type=Path, default=None,
                    help="train the held-out models on these sets (the same four parts, other machines: another "
                         "seed) instead of --data's, and add a model trained on every family of them, judged on "
                         "--data's machines (plants of known families it never saw)")
    ap.add_argument("--inner-splits", type=int, default=2,
                    help="group folds of the training report of each held-out model (train.toml's n_splits: None)")
    args = ap.parse_args(argv)
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir

    t0 = time.perf_counter()
    samples = read_samples(args.data)
    shipped = load_bundle(args.registry or shipped_registry_dir())
    name = judged_name(shipped, args.registry is None)
    results: dict[str, dict[str, list]] = {name: {c: judge(shipped, samples, c) for c in CONDITIONS}}
    bundles: dict[str, object] = {name: shipped}

    def write() -> str:
        text = report(results, bundles, len(samples), time.perf_counter() - t0)
        if args.out:
            args.out.write_text(text + "\n")
        return text

    write()
    if not args.no_holdout:
        table_, fams = family_tables(args.train_data or args.data, args.config)
        with tempfile.TemporaryDirectory() as td:
            if args.train_data is not None:
                name = "trained on every family's other machines (the judged machines never seen)"
                t1 = time.perf_counter()
                bundle = train_without(table_, fams, "", args.config, Path(td), args.inner_splits)
                bundles[name] = bundle
                results[name] = {c: judge(bundle, samples, c) for c in CONDITIONS}
                print(f"every family: {len(samples)} recordings, {time.perf_counter() - t1:.0f} s", file=sys.stderr)
                write()
            name = "trained on shaft trains, the judged family held out"
            results[name] = {c: [] for c in CONDITIONS}
            for fam in sorted(set(s["family"] for s in samples)):
                t1 = time.perf_counter()
                bundle = train_without(table_, fams, fam, args.config, Path(td), args.inner_splits)
                bundles[name] = bundle        # the bands and policy are the configuration's, the same for every fold
                held = [s for s in samples if s["family"] == fam]
                for c in CONDITIONS:
                    results[name][c] += judge(bundle, held, c)
                print(f"held out {fam}: {len(held)} recordings, {time.perf_counter() - t1:.0f} s", file=sys.stderr)
                write()
    print(write())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
