"""Whirl onset speed against misalignment (issue 42 item 6) → docs/train-misalignment.md and its figure.

    .venv/bin/python benchmarks/train_whirl_onset.py [--out-dir docs/figures/train_misalignment] [--quick]

For each preset (``simulator.shaftline.PRESETS``), rigid coupling, aligned on its catenary at the first rated
speed (``simulator.train.aligned_offsets``), the exciter's bearings are then moved as a rigid line by a parallel
offset δ (a fraction of c, the exciter coupling-end bearing's clearance) down (−90°), up (+90°) and sideways (0°).
The threshold speed of instability is where the least-damped mode's logarithmic decrement crosses zero, linearised
with the **nonlinear film's own coefficients** at the static state solved at each speed
(``simulator.train.stability.threshold_speed_rpm(..., coefficients="film")``; the pads' reduced synchronous
coefficients give a larger margin, printed at δ = 0 for comparison). Beside it: each coupling-end bearing's vertical
load and film eccentricity at rated speed, the field's "radial preload" reading. Prints Markdown tables and writes
``whirl_onset.png``. Deterministic (no random draws).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rotordiag.simulator.shaftline import PRESETS, preset  # noqa: E402
from rotordiag.simulator.train import TrainError, aligned_offsets, misaligned, static_state, with_moves  # noqa: E402
from rotordiag.simulator.train.shaftline import train_from_shaftline  # noqa: E402
from rotordiag.simulator.train.stability import threshold_speed_rpm  # noqa: E402
from rotordiag.simulator.train.static import film_eccentricity  # noqa: E402

DIRECTIONS = {"down": -90.0, "up": 90.0, "sideways": 0.0}
FRACTIONS = (0.0, 0.5, 1.0, 1.5)
#: speeds searched: from half the rated speed to three times it
SPAN = (0.5, 3.0)


def _film_ecc(st) -> list[float]:
    asm = st.assembly
    return [film_eccentricity(b, *st.journal_m[k]) for k, b in enumerate(asm.bearings)]


def sweep(name: str, fractions, directions) -> dict:
    rated = float(PRESETS[name]["rated_speed_rpm"][0])
    tr = train_from_shaftline(preset(name))
    al = with_moves(tr, aligned_offsets(tr, rated))
    c3 = float(tr.rotors[1].supports[0].bearing.clearance_m)
    lo, hi = SPAN[0] * rated, SPAN[1] * rated
    out = {"preset": name, "rated_rpm": rated, "c3_um": c3 * 1e6, "rows": [],
           "reduced_onset_rpm_aligned": threshold_speed_rpm(al, hi, min_rpm=lo, n_grid=8, tol_rpm=25.0)}
    for where, deg in directions.items():
        for f in fractions:
            if f == 0 and where != next(iter(directions)):
                continue
            t = misaligned(al, offset_m=f * c3, direction_rad=math.radians(deg)) if f else al
            row = {"direction": where if f else "aligned", "fraction_c": f}
            t0 = time.perf_counter()
            try:
                st = static_state(t, rated)
                row["load_kn"] = [round(float(v) / 1e3, 1) for v in -st.bearing_load_n[:, 1]]
                row["film_ecc"] = [round(v, 3) for v in _film_ecc(st)]
                row["onset_rpm"] = threshold_speed_rpm(t, hi, min_rpm=lo, n_grid=8, tol_rpm=25.0,
                                                       coefficients="film")
            except TrainError as exc:
                row["refused"] = str(exc)
            row["wall_s"] = round(time.perf_counter() - t0, 1)
            out["rows"].append(row)
            print(name, row, flush=True)
    return out


def figure(results: list[dict], path: Path) -> None:
    """Top: onset speed / rated speed against δ/c per direction (a triangle at 3: none below 3× rated). Bottom: the
    coupling-end bearings' vertical loads at rated speed (B2 solid, B3 dashed), the radial preload."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(results), figsize=(4.3 * len(results), 7.5), squeeze=False, sharex="col")
    for col, res in enumerate(results):
        ax, axl = axes[0, col], axes[1, col]
        base = [r for r in res["rows"] if r["direction"] == "aligned"]
        for k, where in enumerate(DIRECTIONS):
            rows = [r for r in base + [r for r in res["rows"] if r["direction"] == where] if "onset_rpm" in r]
            xs = [r["fraction_c"] for r in rows]
            ys = [min(r["onset_rpm"], SPAN[1] * res["rated_rpm"]) / res["rated_rpm"] for r in rows]
            ax.plot(xs, ys, "-", color=f"C{k}", label=f"offset {where}")
            for x, y, r in zip(xs, ys, rows, strict=True):
                ax.plot([x], [y], "^" if not math.isfinite(r["onset_rpm"]) else "o", color=f"C{k}")
            axl.plot(xs, [r["load_kn"][1] for r in rows], "-o", color=f"C{k}", ms=4, label=f"B2, {where}")
            axl.plot(xs, [r["load_kn"][2] for r in rows], "--s", color=f"C{k}", ms=4, label=f"B3, {where}")
        ax.axhline(1.0, color="k", lw=0.8, ls=":", label="rated speed")
        if math.isfinite(res["reduced_onset_rpm_aligned"]):
            ax.plot([0], [res["reduced_onset_rpm_aligned"] / res["rated_rpm"]], "k*", ms=9,
                    label="aligned, pads' reduced coeff.")
        ax.set_title(f"{res['preset']} (rated {res['rated_rpm']:g} r/min)", fontsize=9)
        ax.set_ylabel("whirl onset speed / rated speed")
        ax.set_ylim(0, SPAN[1] + 0.15)
        ax.grid(alpha=0.3)
        axl.axhline(0.0, color="k", lw=0.6)
        axl.set_xlabel(f"parallel offset δ / c  (c = {res['c3_um']:.0f} µm)")
        axl.set_ylabel("vertical load at rated speed, kN (+ down)")
        axl.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="lower left")
    axes[1, 0].legend(fontsize=6, loc="upper left", ncol=2)
    fig.suptitle("Threshold speed of instability (nonlinear film coefficients at the static state) against the "
                 "exciter's offset from the catenary, rigid coupling\n▲ at 3: no onset below 3× rated speed; "
                 "bottom: the coupling-end bearings' loads (B2 generator, B3 exciter)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "figures" / "train_misalignment")
    ap.add_argument("--quick", action="store_true", help="gen200_2pole only, δ 0 and 0.5 c down")
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--directions", default=",".join(DIRECTIONS), help="a subset of down,up,sideways")
    ap.add_argument("--fractions", default=",".join(f"{f:g}" for f in FRACTIONS), help="δ/c values (0: aligned)")
    args = ap.parse_args()
    directions = {d: DIRECTIONS[d] for d in args.directions.split(",")}
    fractions = tuple(float(f) for f in args.fractions.split(","))
    args.out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if args.quick:
        results = [sweep("gen200_2pole", (0.0, 0.5), {"down": -90.0})]
    else:
        results = [sweep(n, fractions, directions) for n in args.presets.split(",")]
    (args.out_dir / "whirl_onset.json").write_text(json.dumps(results, indent=1))
    figure(results, args.out_dir / "whirl_onset.png")
    for res in results:
        print(f"\n{res['preset']} (rated {res['rated_rpm']:g} r/min; aligned onset with the pads' reduced "
              f"coefficients: {res['reduced_onset_rpm_aligned']:.0f} r/min)")
        print("| offset | δ/c | onset r/min (film) | onset / rated | B2 load kN | B3 load kN | B2 film ε | B3 film ε |")
        print("|---|---|---|---|---|---|---|---|")
        for r in res["rows"]:
            if "refused" in r:
                print(f"| {r['direction']} | {r['fraction_c']:g} | refused: {r['refused'][:80]} | | | | | |")
                continue
            on = r["onset_rpm"]
            ons = f"{on:.0f}" if math.isfinite(on) else f"> {SPAN[1] * res['rated_rpm']:.0f}"
            rat = f"{on / res['rated_rpm']:.2f}" if math.isfinite(on) else f"> {SPAN[1]:g}"
            print(f"| {r['direction']} | {r['fraction_c']:g} | {ons} | {rat} | {r['load_kn'][1]} | {r['load_kn'][2]} "
                  f"| {r['film_ecc'][1]} | {r['film_ecc'][2]} |")
    print(f"\n{time.perf_counter() - t0:.0f} s", file=sys.stderr)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
