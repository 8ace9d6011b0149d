"""Figures and table of docs/bearings.md: static characteristics and linearised coefficients of the
bearing types of rotordiag.simulator.bearings against the Sommerfeld number.

    .venv/bin/python benchmarks/bearing_figures.py [--out docs/figures]

Same bearing for every type (D 0.45 m, L 0.35 m, c 0.35 mm, μ 0.018 Pa·s, 3000 r/min), the load
W (−y) swept; S = μ N L D (R/c)² / W with N in rev/s. The plain bearing is overlaid with Ocvirk's
closed forms (eccentricity and attitude angle from Capone's |f|, MODEL.md section 4).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotordiag.simulator.bearings import EllipticalBearing, PlainBearing, TiltingPadBearing

D, L, C, MU = 0.45, 0.35, 0.35e-3, 0.018
SPEED_RAD_S = 2.0 * math.pi * 3000 / 60
S_FACTOR = MU * (SPEED_RAD_S / (2 * math.pi)) * L * D * (D / 2 / C) ** 2   # S·W


def bearings():
    return [
        ("plain", PlainBearing(D, L, C, MU)),
        ("two-lobe m 0.5, 2×150°", EllipticalBearing(D, L, C, MU, preload=0.5, lobe_arc_deg=150.0)),
        ("tilting pad 4 LBP, m 0.3", TiltingPadBearing(D, L, C, MU, pads=4, pad_arc_deg=80.0, preload=0.3)),
        ("tilting pad 5 LOP, m 0.2, 0.6", TiltingPadBearing(D, L, C, MU, pads=5, pad_arc_deg=60.0, pivot_offset=0.6,
                                                            preload=0.2, load="on_pad")),
    ]


def sweep(b, loads):
    rows = []
    for w in loads:
        try:
            x, y = b.equilibrium(0.0, -w, SPEED_RAD_S)
        except ValueError:
            rows.append([np.nan] * 11)
            continue
        K, Cm = b.coefficients(x, y, SPEED_RAD_S)
        if isinstance(b, TiltingPadBearing):
            Kr, Cr = b.reduced_coefficients(x, y, SPEED_RAD_S)
        else:
            Kr, Cr = K, Cm
        k = K * C / w
        c = Cm * C * SPEED_RAD_S / w
        kr = Kr * C / w
        cr = Cr * C * SPEED_RAD_S / w
        rows.append([math.hypot(x, y) / C, math.degrees(math.atan2(x, -y)), k[0, 0], k[0, 1], k[1, 0], k[1, 1],
                     c[0, 0], c[1, 1], kr[1, 1], cr[1, 1], c[0, 1]])
    return np.array(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/figures")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    S = np.geomspace(0.03, 3.0, 36)
    loads = S_FACTOR / S
    res = {name: sweep(b, loads) for name, b in bearings()}

    eps = np.linspace(0.02, 0.97, 200)
    sb = MU * SPEED_RAD_S * (D / 2) * L**3 / (4 * C**2)
    w_oc = sb * eps / (1 - eps**2) ** 2 * np.sqrt(np.pi**2 * (1 - eps**2) + 16 * eps**2)
    att_oc = np.degrees(np.arctan(np.pi * np.sqrt(1 - eps**2) / (4 * eps)))

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].semilogx(S_FACTOR / w_oc, eps, "k-", lw=3, alpha=0.3, label="Ocvirk closed form")
    ax[1].semilogx(S_FACTOR / w_oc, att_oc, "k-", lw=3, alpha=0.3, label="Ocvirk closed form")
    for name, r in res.items():
        ax[0].semilogx(S, r[:, 0], "o-", ms=3, label=name)
        ax[1].semilogx(S, r[:, 1], "o-", ms=3, label=name)
    ax[0].set(xlabel="Sommerfeld number S = μNLD(R/c)²/W", ylabel="eccentricity |r|/c (c: assembled clearance)",
              xlim=(0.03, 3))
    ax[1].set(xlabel="Sommerfeld number S", ylabel="attitude angle from the load line (°)", xlim=(0.03, 3))
    ax[0].legend(fontsize=8)
    fig.suptitle("Static position under a vertical load, short-bearing films, L/D = 0.78, Ω > 0")
    fig.tight_layout()
    fig.savefig(out / "bearings_static.png", dpi=110)

    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
    for name, r in res.items():
        l, = ax[0].loglog(S, r[:, 5], "-", label=f"{name}: k̄yy")
        ax[0].loglog(S, r[:, 2], "--", color=l.get_color(), label=f"{name}: k̄xx")
        ax[1].semilogx(S, r[:, 4], "-", color=l.get_color(), label=f"{name}: k̄yx")
        ax[1].semilogx(S, r[:, 3], "--", color=l.get_color(), label=f"{name}: k̄xy")
        ax[2].loglog(S, r[:, 7], "-", color=l.get_color(), label=f"{name}: c̄yy")
        if name.startswith("tilting"):
            ax[0].loglog(S, r[:, 8], ":", color=l.get_color(), lw=2, label=f"{name}: k̄yy synchronous")
            ax[2].loglog(S, r[:, 9], ":", color=l.get_color(), lw=2, label=f"{name}: c̄yy synchronous")
    ax[0].set(xlabel="S", ylabel="k̄ = K c / W", title="direct stiffness")
    ax[1].set(xlabel="S", ylabel="k̄ = K c / W", title="cross-coupled stiffness", ylim=(-30, 10))
    ax[2].set(xlabel="S", ylabel="c̄ = C c Ω / W", title="direct damping (vertical)")
    for a in ax:
        a.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / "bearings_coefficients.png", dpi=110)

    print("| bearing | S | ε | attitude (°) | k̄xx | k̄xy | k̄yx | k̄yy | c̄xx | c̄yy | k̄yy sync | c̄yy sync |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, r in res.items():
        for i in (6, 17, 26):
            v = r[i]
            print(f"| {name} | {S[i]:.3f} | {v[0]:.3f} | {v[1]:.1f} | {v[2]:.2f} | {v[3]:.2f} | {v[4]:.2f} | {v[5]:.2f} "
                  f"| {v[6]:.2f} | {v[7]:.2f} | {v[8]:.2f} | {v[9]:.2f} |")


if __name__ == "__main__":
    main()
