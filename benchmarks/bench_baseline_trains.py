"""Asset baselines on small shaft trains (issue 48, item 4): a coupling offset of a few µm against the asset's own
repeatability thresholds and against the fleet-wide (shipped) ones.

    .venv/bin/python benchmarks/bench_baseline_trains.py [--machines gen50_2pole:3000,gen200_2pole:3000]
                                                         [--draws 40] [--no-doc]

Per machine (a preset shaft line of ``simulator/shaftline.py`` as a finite-element train,
``simulator.train.recording.train_recording``, noise-free):

* ``N_HEALTHY`` healthy runs at speeds uniform within ±0.5 % of the rated speed (a grid-locked machine's
  day-to-day spread), unbalance 0.2 kg·m at the generator's middle;
* misaligned runs: parallel offsets of :data:`OFFSETS_UM` at the coupling, exciter low (−90°) and sideways (0°),
  each at the speed of a healthy run (so the journal movement it causes is read against that run noise-free).

Measurement (``simulator.dataset.measurement``): the machine's shaft runout (1X 0–3 µm, 2X 0–1 µm per bearing, fixed
to the shaft: the same in every recording of the machine) and white noise redrawn per recording at an SNR uniform
in 25–45 dB. ``--draws`` times per machine: a baseline of 3 recordings of 3 different healthy runs (averaged,
``features.average_signatures``, as the service's automatic baseline), its own thresholds
(``models.change.repeatability_thresholds``); later recordings: the other healthy runs (false alarms) and every
misaligned run (detection), each with new noise, judged by ``models.change.assess_change`` with the asset's own
thresholds and with the shipped ones. Intervals: Wilson 95 % over recordings — the recordings of one machine share
its few simulated runs, so they are not independent machines. Seeded (``--seed``); the simulations are cached in
``/tmp/rotordiag_baseline_trains_<key>.npz``.

The table goes into docs/models.md between ``<!-- baseline-trains:begin -->`` and ``<!-- baseline-trains:end -->``.
"""
from __future__ import annotations

import argparse
import hashlib
import math
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "models.md"
BEGIN, END = "<!-- baseline-trains:begin -->", "<!-- baseline-trains:end -->"
SEED = 4804
N_HEALTHY = 6
SPEED_SPREAD = 0.005
OFFSETS_UM = (2.0, 5.0, 10.0, 20.0, 40.0)
DIRECTIONS_DEG = (-90.0, 0.0)
RUNOUT_1X_UM = (0.0, 3.0)
RUNOUT_2X_UM = (0.0, 1.0)
SNR_DB = (25.0, 45.0)
N_BASE = 3
CACHE_VERSION = 1


def simulate_machine(name: str, rated_rpm: float, seed: int) -> dict:
    """The noise-free runs of one machine (cached)."""
    key = hashlib.sha1(repr((CACHE_VERSION, name, rated_rpm, seed, N_HEALTHY, SPEED_SPREAD, OFFSETS_UM,
                             DIRECTIONS_DEG)).encode()).hexdigest()[:12]
    cache = Path("/tmp") / f"rotordiag_baseline_trains_{key}.npz"
    if cache.exists():
        z = np.load(cache, allow_pickle=False)
        return {k: z[k] for k in z.files}
    from rotordiag.simulator.train.recording import train_recording
    from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline

    rng = np.random.default_rng(seed)
    line, _ = shaftline_of(name)
    train = train_from_shaftline(line)
    speeds = rated_rpm * (1 + rng.uniform(-SPEED_SPREAD, SPEED_SPREAD, N_HEALTHY))
    cases = [(float(s), 0.0, -90.0, i) for i, s in enumerate(speeds)]
    k = 0
    for off in OFFSETS_UM:
        for d in DIRECTIONS_DEG:
            cases.append((float(speeds[k % N_HEALTHY]), off, d, k % N_HEALTHY))
            k += 1
    waves, kps, t0 = [], [], time.perf_counter()
    for s, off, d, _ in cases:
        rec = train_recording(train, s, offset_um=off, direction_deg=d, unbalance_kg_m=0.2, snr_db=math.inf)
        waves.append(rec.probes.waveforms_um.astype(np.float64))
        kps.append(rec.probes.keyphasor_times_s)
        probes = rec.probes
    out = {"speed_rpm": np.array([c[0] for c in cases]), "offset_um": np.array([c[1] for c in cases]),
           "direction_deg": np.array([c[2] for c in cases]), "healthy_ref": np.array([c[3] for c in cases]),
           "waveforms_um": np.stack(waves), "n_kp": np.array([len(k_) for k_ in kps]),
           "keyphasor_s": np.concatenate(kps), "sample_rate_hz": np.array(probes.sample_rate_hz),
           "channels": np.array(probes.channels, dtype=float),
           "clearance_um": np.array([probes.clearance_um[b] for b in sorted(probes.clearance_um)]),
           "sim_s": np.array(time.perf_counter() - t0)}
    np.savez(cache, **out)
    return out


class Measured:
    """Recordings of one machine's runs as its probes read them: fixed runout, new noise per recording."""

    def __init__(self, sims: dict, rng: np.random.Generator) -> None:
        from rotordiag.simulator.dataset.measurement import MeasurementDraws

        self.sims = sims
        self.kp_at = np.concatenate([[0], np.cumsum(sims["n_kp"])])
        bearings = sorted({int(b) for b in sims["channels"][:, 0]})
        self.bearings = bearings
        n = len(bearings)
        self.runout = MeasurementDraws(0.0, 0.0, 0.0, rng.uniform(*RUNOUT_1X_UM, n), rng.uniform(0, 2 * np.pi, n),
                                       rng.uniform(*RUNOUT_2X_UM, n), rng.uniform(0, 2 * np.pi, n))

    def signature(self, i: int, rng: np.random.Generator | None) -> dict:
        """The signature of run ``i`` with the runout and, with ``rng``, noise at a drawn SNR."""
        from rotordiag.features import ProbeChannel, Recording, extract_features, signature
        from rotordiag.simulator.dataset.measurement import runout_um

        s = self.sims
        w = s["waveforms_um"][i].copy()
        fs = float(s["sample_rate_hz"])
        kp = s["keyphasor_s"][self.kp_at[i]:self.kp_at[i + 1]]
        t = np.arange(w.shape[1]) / fs
        theta = 2 * np.pi * float(s["speed_rpm"][i]) / 60.0 * (t - kp[0])
        chans = []
        for c, (b, a) in enumerate(s["channels"]):
            w[c] += runout_um(theta, float(a), self.runout, self.bearings.index(int(b)))
            if rng is not None:
                ac = w[c] - w[c].mean()
                w[c] += rng.standard_normal(len(ac)) * math.sqrt(float(np.mean(ac ** 2))) / 10 ** (
                    rng.uniform(*SNR_DB) / 20)
            chans.append(ProbeChannel(bearing=int(b), angle_deg=float(a), units="um", data=w[c]))
        clearance = {b: float(c) for b, c in zip(self.bearings, s["clearance_um"])}
        rec = Recording(sample_rate_hz=fs, channels=chans, keyphasor_times_s=kp, clearance_um=clearance)
        return signature(extract_features(rec))


def wilson(k: int, n: int) -> tuple[float, float]:
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    return float(ci.low), float(ci.high)


def _rate(flags: list[bool]) -> str:
    k, n = int(sum(flags)), len(flags)
    if n == 0:
        return "—"
    lo, hi = wilson(k, n)
    return f"{100 * k / n:.0f} % ({k}/{n}; {100 * lo:.0f}–{100 * hi:.0f})"


def evaluate(name: str, rated_rpm: float, draws: int, seed: int) -> dict:
    """Detection and false alarms of one machine, own vs shipped thresholds."""
    from rotordiag.features import average_signatures, change_features
    from rotordiag.models.change import assess_change, repeatability_thresholds, shipped_rule

    sims = simulate_machine(name, rated_rpm, seed)
    rng = np.random.default_rng(seed + 1)
    m = Measured(sims, rng)
    healthy = [i for i in range(len(sims["offset_um"])) if sims["offset_um"][i] == 0]
    misaligned = [i for i in range(len(sims["offset_um"])) if sims["offset_um"][i] > 0]
    clean = {i: m.signature(i, None) for i in range(len(sims["offset_um"]))}
    moved = {}
    for i in misaligned:   # journal movement and 2X change the offset causes, noise-free, against its healthy run
        res = change_features(clean[int(sims["healthy_ref"][i])], clean[i])
        moved[i] = (res.largest("dc_shift_um")[0], res.largest("2x_change_um_pp")[0])
    shipped = shipped_rule()
    fa: dict[str, list[bool]] = {"own": [], "shipped": []}
    fa_by: dict[str, dict[str, int]] = {"own": {}, "shipped": {}}
    det: dict[tuple[str, float], list[bool]] = {}
    own_th: list[dict] = []
    n_fleet = 0
    for _ in range(draws):
        base_runs = list(rng.choice(healthy, N_BASE, replace=False))
        sigs = [m.signature(i, rng) for i in base_runs]
        base = average_signatures(sigs)
        rep = repeatability_thresholds(sigs)
        n_fleet += rep is None
        rules = {"own": shipped.with_repeatability(rep), "shipped": shipped}
        if rep is not None:
            own_th.append(rep["thresholds"])
        for i in [h for h in healthy if h not in base_runs]:
            res = change_features(base, m.signature(i, rng))
            for k, rule in rules.items():
                verdict = assess_change(res, rule)
                fa[k].append(bool(verdict["changed"]))
                for q in verdict["exceeded"]:
                    fa_by[k][q] = fa_by[k].get(q, 0) + 1
        for i in misaligned:
            res = change_features(base, m.signature(i, rng))
            for k, rule in rules.items():
                det.setdefault((k, float(sims["offset_um"][i])), []).append(bool(assess_change(res, rule)["changed"]))
    return {"name": name, "rated_rpm": rated_rpm, "sims": sims, "moved": moved, "fa": fa, "fa_by": fa_by, "det": det,
            "own_th": own_th, "n_fleet": n_fleet, "draws": draws, "misaligned": misaligned}


def table(results: list[dict]) -> str:
    from rotordiag.models.change import shipped_rule

    sh = shipped_rule().thresholds
    lines = ["| machine | offset at the coupling | journal movement (largest, µm) | 2X change (µm pk-pk) | detected, own "
             "thresholds | detected, shipped thresholds |", "|---|---|---|---|---|---|"]
    for r in results:
        sims = r["sims"]
        for off in OFFSETS_UM:
            idx = [i for i in r["misaligned"] if sims["offset_um"][i] == off]
            mv = [r["moved"][i][0] for i in idx]
            x2 = [r["moved"][i][1] for i in idx]
            lines.append(f"| {r['name']} @ {r['rated_rpm']:.0f} r/min | {off:g} µm | {min(mv):.2f}–{max(mv):.2f} | "
                         f"{min(x2):.2f}–{max(x2):.2f} | {_rate(r['det'][('own', off)])} | "
                         f"{_rate(r['det'][('shipped', off)])} |")
        by = {k: ", ".join(f"{q} {n}" for q, n in sorted(v.items(), key=lambda kv: -kv[1])) for k, v in r["fa_by"].items()}
        lines.append(f"| {r['name']} @ {r['rated_rpm']:.0f} r/min | healthy re-recordings (false alarms) | – | – | "
                     f"{_rate(r['fa']['own'])}{' — ' + by['own'] if by['own'] else ''} | "
                     f"{_rate(r['fa']['shipped'])}{' — ' + by['shipped'] if by['shipped'] else ''} |")
    lines.append("")
    lines.append("Thresholds: shipped (fleet-wide) centreline shift > "
                 f"{sh['dc_shift_um']:.2g} µm and > {sh['dc_shift_per_c']:.2g} c, 2X vector change > "
                 f"{sh['2x_change_um_pp']:.3g} µm pk-pk, 1X > {sh['1x_change_um_pp']:.3g} µm pk-pk. Own (median over "
                 "the baselines drawn): " + "; ".join(
                     f"{r['name']} @ {r['rated_rpm']:.0f} r/min: centreline {np.median([t['dc_shift_um'] for t in r['own_th']]):.2g} µm, 2X "
                     f"{np.median([t['2x_change_um_pp'] for t in r['own_th']]):.2g} µm pk-pk, 1X "
                     f"{np.median([t['1x_change_um_pp'] for t in r['own_th']]):.2g} µm pk-pk "
                     f"({r['draws'] - r['n_fleet']}/{r['draws']} baselines with own thresholds)"
                     for r in results if r["own_th"]) + ".")
    return "\n".join(lines) + "\n"


def write_doc(text: str, path: Path = DOC) -> None:
    page = path.read_text()
    if BEGIN not in page or END not in page:
        raise SystemExit(f"{path}: markers {BEGIN} / {END} not found")
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    path.write_text(head + BEGIN + "\n" + text + END + tail)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--machines", default="gen50_2pole:3000,gen200_2pole:3000",
                    help="preset:rated_rpm, comma-separated (simulator/shaftline.py PRESETS)")
    ap.add_argument("--draws", type=int, default=40, help="baselines drawn per machine")
    ap.add_argument("--seed", type=int, default=SEED)
    ap.add_argument("--no-doc", action="store_true", help="print the table only")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    results = []
    for k, item in enumerate(args.machines.split(",")):
        name, rpm = item.split(":")
        results.append(evaluate(name, float(rpm), args.draws, args.seed + 100 * k))
        print(f"{name}: simulated in {float(results[-1]['sims']['sim_s']):.0f} s (cached afterwards)", flush=True)
    text = table(results)
    text += (f"\n`benchmarks/bench_baseline_trains.py --machines {args.machines} --draws {args.draws} --seed "
             f"{args.seed}`: {time.perf_counter() - t0:.0f} s on this machine (simulations cached).\n")
    print(text)
    if not args.no_doc:
        write_doc(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
