"""What misalignment does to a shaft train (issue 42 item 6) → docs/train-misalignment.md and its figures.

    .venv/bin/python benchmarks/train_misalignment.py [--out-dir docs/figures/train_misalignment] [--quick]

For each preset (``simulator.shaftline.PRESETS``) at its first rated speed, the exciter's bearings are moved as a
rigid line (``simulator.train.misaligned``): a parallel offset δ of 0…0.5 c (c: the exciter coupling-end bearing's
clearance) downward (−90°) and sideways (0°), and an angular offset α. The static state (Newton) gives each
bearing's vertical load, the journals' eccentricities and the least-damped mode's logarithmic decrement (the whirl
margin). For ``gen200_2pole`` the steady response (reduced model, 232 revolutions) gives 1X and 2X at every
bearing, rigid and flexible couplings, beside the 2X/1X rule of thumb (0.5 / 1 / 2). Every figure is written as a
PNG; the tables are printed as Markdown. Deterministic (no random draws: noise-free probes).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rotordiag.simulator.shaftline import PRESETS, preset  # noqa: E402
from rotordiag.simulator.train import Coupling, TrainError, misaligned, static_state  # noqa: E402
from rotordiag.simulator.train.recording import train_recording  # noqa: E402
from rotordiag.simulator.train.shaftline import train_from_shaftline  # noqa: E402
from rotordiag.simulator.train.stability import stability  # noqa: E402

DIRECTIONS = {"down": -90.0, "sideways": 0.0}
FRACTIONS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)
#: flexible coupling of the dynamic study (illustrative, not sourced: the paper's k_c ≈ 1e8 N/m)
FLEX = dict(lateral_stiffness_n_m=1.0e8, angular_stiffness_n_m_rad=1.0e6, lateral_damping_n_s_m=1.0e4,
            angular_damping_n_m_s_rad=1.0e2)
RECORD_REVS = 32


def _orders_pp(wave_um: np.ndarray, record_revs: int) -> tuple[np.ndarray, np.ndarray]:
    """1X and 2X amplitude pk-pk of each probe (rows) over a record of whole revolutions."""
    spec = np.fft.rfft(wave_um - wave_um.mean(axis=1, keepdims=True), axis=1)
    n = wave_um.shape[1]
    amp = 2 * np.abs(spec) / n
    return 2 * amp[:, record_revs], 2 * amp[:, 2 * record_revs]


def static_sweep(name: str) -> list[dict]:
    tr = train_from_shaftline(preset(name))
    speed = float(PRESETS[name]["rated_speed_rpm"][0])
    c3 = float(tr.rotors[1].supports[0].bearing.clearance_m)
    rows = []
    for where, deg in DIRECTIONS.items():
        for f in FRACTIONS:
            t = misaligned(tr, offset_m=f * c3, direction_rad=math.radians(deg)) if f else tr
            try:
                st = static_state(t, speed)
                s = stability(t, speed)
            except TrainError as exc:
                rows.append({"preset": name, "dir": where, "frac": f, "error": str(exc)[:80]})
                continue
            rows.append({"preset": name, "dir": where, "frac": f, "speed": speed, "c_um": c3 * 1e6,
                         "load_y_kn": st.bearing_load_n[:, 1] / 1e3, "load_x_kn": st.bearing_load_n[:, 0] / 1e3,
                         "ecc": st.eccentricity.copy(), "journal_um": st.journal_m * 1e6,
                         "log_dec": s.log_decrement, "whirl_hz": s.frequency_hz})
    return rows


def angular_sweep(name: str, mrad=(0.0, 0.05, 0.1, 0.2)) -> list[dict]:
    tr = train_from_shaftline(preset(name))
    speed = float(PRESETS[name]["rated_speed_rpm"][0])
    out = []
    for a in mrad:
        t = misaligned(tr, angle_rad=a * 1e-3) if a else tr
        try:
            st = static_state(t, speed)
            out.append({"mrad": a, "load_y_kn": st.bearing_load_n[:, 1] / 1e3, "ecc": st.eccentricity.copy(),
                        "log_dec": stability(t, speed).log_decrement})
        except TrainError as exc:
            out.append({"mrad": a, "error": str(exc)[:80]})
    return out


def dynamic_sweep(name: str, coupling: str, fractions=FRACTIONS) -> list[dict]:
    base = train_from_shaftline(preset(name))
    speed = float(PRESETS[name]["rated_speed_rpm"][0])
    c3 = float(base.rotors[1].supports[0].bearing.clearance_m)
    rows = []
    for where, deg in DIRECTIONS.items():
        for f in fractions:
            tr = base
            if coupling == "flexible":
                tr = replace(base, couplings=(Coupling("flexible", kinematic_offset_m=f * c3,
                                                       kinematic_direction_rad=math.radians(deg), **FLEX),))
            t0 = time.perf_counter()
            try:
                rec = train_recording(tr, speed, offset_um=f * c3 * 1e6, direction_deg=deg, unbalance_kg_m=0.2,
                                      transient_revs=200, record_revs=RECORD_REVS, snr_db=math.inf)
            except TrainError as exc:
                rows.append({"coupling": coupling, "dir": where, "frac": f, "error": str(exc)[:80]})
                continue
            one, two = _orders_pp(rec.probes.waveforms_um, RECORD_REVS)
            rows.append({"coupling": coupling, "dir": where, "frac": f, "one_x": one, "two_x": two,
                         "channels": rec.probes.channels, "wave": rec.probes.waveforms_um, "s": time.perf_counter() - t0,
                         "log_dec": rec.inputs["log_decrement"]})
    return rows


def _plots(out_dir: Path, statics: dict[str, list[dict]], dyn: list[dict]) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    fig, axes = plt.subplots(2, len(statics), figsize=(4.2 * len(statics), 7.2), sharex=True, squeeze=False)
    for k, (name, rows) in enumerate(statics.items()):
        for where, style in (("down", "-"), ("sideways", "--")):
            ok = [r for r in rows if r["dir"] == where and "error" not in r]
            x = [r["frac"] for r in ok]
            for b in range(4):
                axes[0, k].plot(x, [-r["load_y_kn"][b] for r in ok], style, marker="o", ms=3, color=f"C{b}",
                                label=f"bearing {b + 1}" if where == "down" else None)
            axes[1, k].plot(x, [r["log_dec"] for r in ok], style, marker="o", ms=3, color="k",
                            label=f"offset {where}")
        axes[0, k].set_title(f"{name} at {ok[0]['speed']:g} r/min")
        axes[0, k].axhline(0, color="0.6", lw=0.8)
        axes[1, k].axhline(0, color="r", lw=0.8)
        axes[1, k].set_xlabel("parallel offset δ / c (exciter bearings moved)")
    axes[0, 0].set_ylabel("vertical bearing load, kN (down +)")
    axes[1, 0].set_ylabel("log decrement of the least-damped mode")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=7)
    fig.suptitle("Static load transfer and whirl margin under a parallel offset (solid: down, dashed: sideways)",
                 fontsize=10)
    fig.tight_layout()
    p = out_dir / "load_transfer.png"
    fig.savefig(p, dpi=90)
    plt.close(fig)
    paths.append(p)

    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for j, coupling in enumerate(("rigid", "flexible")):
        for where, style in (("down", "-"), ("sideways", "--")):
            ok = [r for r in dyn if r["coupling"] == coupling and r["dir"] == where and "error" not in r]
            x = [r["frac"] for r in ok]
            for b in range(4):
                two = [max(r["two_x"][2 * b], r["two_x"][2 * b + 1]) for r in ok]
                one = [max(r["one_x"][2 * b], r["one_x"][2 * b + 1]) for r in ok]
                axes[0, j].plot(x, two, style, marker="o", ms=3, color=f"C{b}",
                                label=f"bearing {b + 1}" if where == "down" else None)
                axes[1, j].plot(x, np.divide(two, one), style, marker="o", ms=3, color=f"C{b}")
        axes[0, j].set_title(f"gen200_2pole, {coupling} coupling")
        for level in (0.5, 1.0, 2.0):
            axes[1, j].axhline(level, color="r", lw=0.6, ls=":")
        axes[1, j].set_xlabel("parallel offset δ / c")
    axes[0, 0].set_ylabel("2X, µm pk-pk (larger probe)")
    axes[1, 0].set_ylabel("2X/1X (rule of thumb: 0.5 / 1 / 2)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    p = out_dir / "orders.png"
    fig.savefig(p, dpi=90)
    plt.close(fig)
    paths.append(p)

    fig, axes = plt.subplots(1, 4, figsize=(13, 3.6))
    for b in range(4):
        ax = axes[b]
        for r in [r for r in dyn if r["coupling"] == "rigid" and r["dir"] == "down" and "error" not in r
                  and r["frac"] in (0.0, 0.3, 0.5)]:
            p45, p135 = r["wave"][2 * b], r["wave"][2 * b + 1]
            x = (p45 - p135) / math.sqrt(2)
            y = (p45 + p135) / math.sqrt(2)
            ax.plot(x - x.mean(), y - y.mean(), lw=0.8, label=f"δ = {r['frac']:.1f} c")
        ax.set_aspect("equal")
        ax.set_title(f"bearing {b + 1}: orbit (mean removed)", fontsize=9)
        ax.set_xlabel("x, µm")
    axes[0].set_ylabel("y (up), µm")
    axes[0].legend(fontsize=7)
    fig.suptitle("gen200_2pole, rigid coupling, offset down: orbit shape", fontsize=10)
    fig.tight_layout()
    p = out_dir / "orbits.png"
    fig.savefig(p, dpi=90)
    plt.close(fig)
    paths.append(p)
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "figures" / "train_misalignment")
    ap.add_argument("--quick", action="store_true", help="fewer offsets in the dynamic study")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    statics = {name: static_sweep(name) for name in PRESETS}
    print("## Static state: vertical load per bearing (kN, down +), eccentricity, log decrement\n")
    print("| preset | offset | δ/c | load b1 | b2 | b3 | b4 | e/c b1 | b2 | b3 | b4 | log dec |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, rows in statics.items():
        for r in rows:
            if "error" in r:
                print(f"| {name} | {r['dir']} | {r['frac']:.1f} | {r['error']} |||||||||")
                continue
            ld, e = -r["load_y_kn"], r["ecc"]
            print(f"| {name} | {r['dir']} | {r['frac']:.1f} | " + " | ".join(f"{v:.1f}" for v in ld) + " | "
                  + " | ".join(f"{v:.2f}" for v in e) + f" | {r['log_dec']:.3f} |")
    print("\n## Angular offset (gen200_2pole, exciter line tilted about the coupling, in the vertical plane)\n")
    print("| α mrad | load b1 | b2 | b3 | b4 | e/c b3 | e/c b4 | log dec |")
    print("|---|---|---|---|---|---|---|---|")
    for r in angular_sweep("gen200_2pole"):
        if "error" in r:
            print(f"| {r['mrad']:g} | {r['error']} |||||||")
            continue
        print(f"| {r['mrad']:g} | " + " | ".join(f"{-v:.1f}" for v in r["load_y_kn"])
              + f" | {r['ecc'][2]:.2f} | {r['ecc'][3]:.2f} | {r['log_dec']:.3f} |")
    fractions = (0.0, 0.2, 0.4) if args.quick else FRACTIONS
    dyn = dynamic_sweep("gen200_2pole", "rigid", fractions) + dynamic_sweep("gen200_2pole", "flexible", fractions)
    print("\n## gen200_2pole at 3000 r/min: 1X and 2X (µm pk-pk, larger probe of each bearing) and 2X/1X\n")
    print("| coupling | offset | δ/c | 1X b1 | b2 | b3 | b4 | 2X b1 | b2 | b3 | b4 | 2X/1X b2 | b3 | rule (b2/b3) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in dyn:
        if "error" in r:
            print(f"| {r['coupling']} | {r['dir']} | {r['frac']:.1f} | {r['error']} |||||||||||")
            continue
        one = [max(r["one_x"][2 * b], r["one_x"][2 * b + 1]) for b in range(4)]
        two = [max(r["two_x"][2 * b], r["two_x"][2 * b + 1]) for b in range(4)]
        ratio = [two[b] / one[b] if one[b] > 0 else float("nan") for b in (1, 2)]
        rule = max(ratio)
        band = "aligned" if rule < 0.5 else "slight" if rule < 1 else "moderate" if rule < 2 else "severe"
        print(f"| {r['coupling']} | {r['dir']} | {r['frac']:.1f} | " + " | ".join(f"{v:.1f}" for v in one) + " | "
              + " | ".join(f"{v:.2f}" for v in two) + f" | {ratio[0]:.2f} | {ratio[1]:.2f} | {band} |")
    paths = _plots(args.out_dir, statics, dyn)
    print(f"\nwrote {', '.join(str(p.relative_to(ROOT)) for p in paths)} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
