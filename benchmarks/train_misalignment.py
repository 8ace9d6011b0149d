"""What misalignment does to a shaft train (issue 42 item 6) → docs/train-misalignment.md and its figures.

    .venv/bin/python benchmarks/train_misalignment.py [--out-dir docs/figures/train_misalignment] [--jobs 2]
                                                      [--presets gen200_2pole ...] [--no-onset]

Every preset (``simulator.shaftline.PRESETS``) as shipped — its asymmetry ρ and its G2.5 residual unbalance — at its
first rated speed, in two arrangements: **four bearings** (as shipped) and **three bearings** (the same shaft line with
bearing 4 ``none``: the exciter overhung on its coupling-end bearing 3, held by the rigid coupling; docs/train.md).
The exciter's bearings are moved as a rigid line (``simulator.train.misaligned``) from the straight bearing line:
a parallel offset δ of 0…0.5 c (c: the exciter coupling-end bearing's clearance) **down** (−90°) and **sideways**
(0°), and an angular offset α of 0.05…0.2 mrad in the vertical and the horizontal plane (four bearings only: with
one exciter bearing the exciter's line is the generator's, and moving bearing 3 is the parallel offset). Couplings:
the preset's rigid one and a flexible one (``FLEX``; four bearings only) whose parallel offset drives the
double-engagement kinematic 2X (``recording.with_kinematic_offset``).

Per case: the static state (Newton): each bearing's load, journal centreline and eccentricity; the least-damped
mode's logarithmic decrement with the nonlinear film's own coefficients (the force the time response integrates).
On a subset (``DYNAMIC_FRACTIONS``, ``DYNAMIC_ANGLES_MRAD``) the steady response (reduced model, ETDRK4,
``TRANSIENT_REVS`` + ``RECORD_REVS`` revolutions at ``SAMPLES_PER_REV``): 1X and 2X at the 45°/135° probes of every
bearing, the orbit's flattening and its tangent turning number (figure-8: 0, inner loop: 2). For the three-bearing
arrangement also the whirl onset speed (``threshold_speed_rpm`` on the film's coefficients). Tables as Markdown on
stdout, every row in ``misalignment.json`` beside the figures. Deterministic: no random draw (noise-free probes);
the worker pool changes only the order in which cases are computed.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rotordiag.simulator.shaftline import PRESETS, preset  # noqa: E402
from rotordiag.simulator.train import Coupling, Train, TrainError, misaligned, static_state  # noqa: E402
from rotordiag.simulator.train.dynamics import build_kernel, simulate_train  # noqa: E402
from rotordiag.simulator.train.recording import with_kinematic_offset  # noqa: E402
from rotordiag.simulator.train.shaftline import train_from_shaftline  # noqa: E402
from rotordiag.simulator.train.stability import stability, threshold_speed_rpm  # noqa: E402

DIRECTIONS = {"down": -90.0, "sideways": 0.0}
STATIC_FRACTIONS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)
DYNAMIC_FRACTIONS = (0.0, 0.1, 0.25, 0.5)
ANGLES_MRAD = (0.05, 0.1, 0.2)
DYNAMIC_ANGLES_MRAD = (0.1, 0.2)
#: flexible coupling of the study (illustrative, not sourced: the paper's k_c ≈ 1e8 N/m; docs/model.md)
FLEX = dict(lateral_stiffness_n_m=1.0e8, angular_stiffness_n_m_rad=1.0e6, lateral_damping_n_s_m=1.0e4,
            angular_damping_n_m_s_rad=1.0e2)
#: the steady run: 64 samples a revolution (one ETDRK4 step each) give the same 1X/2X as 128 within 1e-4
TRANSIENT_REVS, RECORD_REVS, SAMPLES_PER_REV = 200, 32, 64
#: whirl onset search of the three-bearing arrangement: speeds (× rated), grid, bisection tolerance
ONSET_RANGE, ONSET_GRID, ONSET_TOL_RPM = (0.5, 2.0), 7, 25.0
RULE_BANDS = ((0.5, "aligned"), (1.0, "slight"), (2.0, "moderate"), (math.inf, "severe"))


def base_train(name: str, arrangement: str, coupling: str) -> tuple[Train, float, float]:
    """The preset's train in ``arrangement`` (``four`` or ``three`` bearings) with its ``coupling`` (``rigid`` or
    ``flexible``), its first rated speed (r/min) and the exciter coupling-end bearing's clearance (m)."""
    line = preset(name)
    if arrangement == "three":
        line = dataclasses.replace(line, bearing_types=(*line.bearing_types[:3], "none"))
    tr = train_from_shaftline(line)
    if coupling == "flexible":
        tr = replace(tr, couplings=(Coupling("flexible", **FLEX),))
    c3 = float(tr.rotors[1].supports[0].bearing.clearance_m)
    return tr, float(PRESETS[name]["rated_speed_rpm"][0]), c3


def moved(tr: Train, kind: str, direction: str, value: float, c3: float) -> Train:
    """``tr`` misaligned: ``kind`` ``parallel`` (δ = value·c) or ``angular`` (α = value mrad) along ``direction``; a
    flexible coupling also gets the parallel offset's kinematic 2X."""
    deg = DIRECTIONS[direction]
    if value == 0:
        return tr
    if kind == "parallel":
        t = misaligned(tr, offset_m=value * c3, direction_rad=math.radians(deg))
        return with_kinematic_offset(t, value * c3 * 1e6, deg)
    return misaligned(tr, angle_rad=value * 1e-3, direction_rad=math.radians(deg))


def orbit_shape(x_um: np.ndarray, y_um: np.ndarray, revs: int, n_harmonics: int = 6) -> tuple[float, int]:
    """Flattening (minor/major principal axis of the AC orbit: 1 circular, 0 a line) and the tangent turning number
    of the revolution-averaged orbit (the winding of its velocity: +1 a forward ellipse, 2 an inner loop, 0 a
    figure-8, −1 backward), the averaged orbit rebuilt from its first ``n_harmonics`` orders on a fine grid."""
    xy = np.stack([x_um - x_um.mean(), y_um - y_um.mean()])
    lam = np.linalg.eigvalsh(np.cov(xy))
    flat = float(math.sqrt(max(lam[0], 0.0) / lam[1])) if lam[1] > 0 else float("nan")
    per = xy.reshape(2, revs, -1).mean(axis=1)
    spec = np.fft.rfft(per, axis=1) / per.shape[1]
    th = np.linspace(0.0, 2 * math.pi, 1024, endpoint=False)
    vel = np.zeros((2, th.size))
    for k in range(1, n_harmonics + 1):
        vel += 2 * (1j * k * spec[:, k, None] * np.exp(1j * k * th)).real
    ang = np.unwrap(np.arctan2(vel[1], vel[0]))
    step = (np.arctan2(vel[1, 0], vel[0, 0]) - ang[-1] + math.pi) % (2 * math.pi) - math.pi
    return flat, int(round((ang[-1] + step - ang[0]) / (2 * math.pi)))


def _orders(run, revs: int) -> dict:
    """1X and 2X (µm pk-pk) of the 45°/135° probes of each bearing, the larger of the pair, their ratio, the record's
    halves' largest relative difference (settled?), the largest line below 1X over 1X (subsynchronous), pk-pk and
    shape of each orbit."""
    one, two, settle, pp, flat, turn, sub = [], [], [], [], [], [], []
    for b in range(run.journal_m.shape[1]):
        o, t = [], []
        for a in (45.0, 135.0):
            w = run.probe_m(b, a) * 1e6
            amp = [2 * 2 * np.abs(np.fft.rfft(h - h.mean())) / len(h) for h in (w, *np.split(w, 2))]
            o.append(amp[0][revs])
            t.append(amp[0][2 * revs])
            sub.append(float(amp[0][1:revs].max() / amp[0][revs]))
            for k, n in ((1, revs // 2), (2, revs)):   # 1X and 2X over each half of the record
                settle.append(abs(amp[1][n] - amp[2][n]) / max(amp[0][k * revs], 1e-3))
        one.append(max(o))
        two.append(max(t))
        x, y = run.journal_m[:, b, 0] * 1e6, run.journal_m[:, b, 1] * 1e6
        pp.append([float(np.ptp(x)), float(np.ptp(y))])
        f, n = orbit_shape(x, y, revs)
        flat.append(f)
        turn.append(n)
    return {"one_x_um": one, "two_x_um": two, "ratio": [t / o for o, t in zip(one, two, strict=True)],
            "pp_um": pp, "flattening": flat, "turning": turn, "settled": float(max(settle)),
            "subsync": float(max(sub))}


def run_case(tr: Train, speed: float, dynamic: bool) -> dict:
    """Static state, film-coefficient stability and (``dynamic``) the steady response of one misaligned train."""
    t0 = time.perf_counter()
    try:
        st = static_state(tr, speed)
        s = stability(tr, speed, static=st, coefficients="film")
    except TrainError as exc:
        return {"error": str(exc)[:160]}
    row = {"load_y_kn": (-st.bearing_load_n[:, 1] / 1e3).tolist(), "load_x_kn": (st.bearing_load_n[:, 0] / 1e3).tolist(),
           "ecc": st.eccentricity.tolist(), "journal_um": (st.journal_m * 1e6).tolist(),
           "attitude_deg": st.attitude_angle_deg.tolist(), "log_dec": s.log_decrement, "whirl_hz": s.frequency_hz,
           "forward": s.forward, "coupling_shear_y_kn": float(st.coupling_load[0][1] / 1e3),
           "coupling_moment_x_knm": float(st.coupling_load[0][2] / 1e3)}
    if dynamic:
        kern = build_kernel(tr, speed)
        kern.static_q, kern.journal_m = st.q, st.journal_m      # the Newton solution just found
        run = simulate_train(kern, speed, transient_revs=TRANSIENT_REVS, record_revs=RECORD_REVS,
                             samples_per_rev=SAMPLES_PER_REV)
        if run.status != "ok":
            row["error"] = f"steady run ended {run.status}: {run.message}"[:160]
        else:
            row.update(_orders(run, RECORD_REVS), method=run.inputs["method"],
                       wave_um=(run.journal_m * 1e6).tolist())
    row["wall_s"] = time.perf_counter() - t0
    return row


def job(name: str, arrangement: str, coupling: str, onset: bool) -> list[dict]:
    """Every case of one preset, arrangement and coupling."""
    t0 = time.perf_counter()
    tr0, speed, c3 = base_train(name, arrangement, coupling)
    cases = [("parallel", d, f) for d in DIRECTIONS for f in STATIC_FRACTIONS if f or d == "down"]
    if arrangement == "four":
        cases += [("angular", d, a) for d in DIRECTIONS for a in ANGLES_MRAD]
    rows = []
    for kind, direction, value in cases:
        dyn = value in (DYNAMIC_FRACTIONS if kind == "parallel" else DYNAMIC_ANGLES_MRAD)
        tr = moved(tr0, kind, direction, value, c3)
        row = {"preset": name, "arrangement": arrangement, "coupling": coupling, "kind": kind, "dir": direction,
               "value": value, "speed_rpm": speed, "c_um": c3 * 1e6, **run_case(tr, speed, dyn)}
        if onset and arrangement == "three" and kind == "parallel" and value in (0.0, 0.5) and "error" not in row:
            try:
                row["onset_rpm"] = threshold_speed_rpm(tr, ONSET_RANGE[1] * speed, min_rpm=ONSET_RANGE[0] * speed,
                                                       n_grid=ONSET_GRID, tol_rpm=ONSET_TOL_RPM, coefficients="film")
            except TrainError as exc:
                row["onset_error"] = str(exc)[:160]
        rows.append(row)
    print(f"{name}, {arrangement} bearings, {coupling}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return rows


# ----------------------------------------------------------------------------------------------------- tables
def _sel(rows, **kw):
    return [r for r in rows if all(r.get(k) == v for k, v in kw.items())]


def _case(r: dict) -> str:
    if r["value"] == 0:
        return "aligned (straight line)"
    unit = "c" if r["kind"] == "parallel" else "mrad"
    sym = "δ" if r["kind"] == "parallel" else "α"
    return f"{sym} {r['value']:g} {unit} {r['dir']}"


def print_tables(rows: list[dict]) -> None:
    print("## Static state: vertical load per bearing (kN, down +), e/c, journal centre (µm), film log decrement\n")
    print("| preset | bearings | coupling | case | load b1 | b2 | b3 | b4 | e/c b1 | b2 | b3 | b4 | b3 journal x, y µm "
          "| coupling shear kN, moment kN·m | log dec (Hz) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        head = f"| {r['preset']} | {r['arrangement']} | {r['coupling']} | {_case(r)} |"
        if "load_y_kn" not in r:
            print(head + f" {r['error']} |||||||||||")
            continue
        ld = r["load_y_kn"] + [math.nan] * (4 - len(r["load_y_kn"]))
        ec = r["ecc"] + [math.nan] * (4 - len(r["ecc"]))
        j3 = r["journal_um"][2]
        print(head + " | ".join(f" {v:.1f}" for v in ld) + " |" + " | ".join(f" {v:.2f}" for v in ec)
              + f" | {j3[0]:.0f}, {j3[1]:.0f} | {r['coupling_shear_y_kn']:.1f}, {r['coupling_moment_x_knm']:.1f} "
              f"| {r['log_dec']:.3f} ({r['whirl_hz']:.1f}) |")
    print("\n## Steady response: 1X, 2X (µm pk-pk, larger of the 45°/135° probes), 2X/1X, orbit flattening and "
          "turning number per bearing\n")
    print("| preset | bearings | coupling | case | 1X b1..b4 | 2X b1..b4 | 2X/1X b1..b4 | rule (max b2, b3) "
          "| flattening b1..b4 | turning b1..b4 | pk-pk x, y µm (largest bearing) | sub/1X | settled |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "one_x_um" not in r:
            if "error" in r and "load_y_kn" in r:
                print(f"| {r['preset']} | {r['arrangement']} | {r['coupling']} | {_case(r)} | {r['error']} |"
                      "|||||||||")
            continue
        rule = max(r["ratio"][1:3])
        band = next(b for lim, b in RULE_BANDS if rule < lim)
        big = max(r["pp_um"], key=max)
        print(f"| {r['preset']} | {r['arrangement']} | {r['coupling']} | {_case(r)} | "
              + " / ".join(f"{v:.1f}" for v in r["one_x_um"]) + " | " + " / ".join(f"{v:.1f}" for v in r["two_x_um"])
              + " | " + " / ".join(f"{v:.2f}" for v in r["ratio"]) + f" | {band} | "
              + " / ".join(f"{v:.2f}" for v in r["flattening"]) + " | "
              + " / ".join(f"{v:d}" for v in r["turning"]) + " | "
              + "{:.0f}, {:.0f} (b{})".format(*big, 1 + r["pp_um"].index(big))
              + f" | {r['subsync']:.0e} | {r['settled']:.0e} |")
    onsets = [r for r in rows if "onset_rpm" in r]
    if onsets:
        print("\n## Whirl onset speed, three-bearing arrangement (film coefficients; inf: none in "
              f"{ONSET_RANGE[0]:g}–{ONSET_RANGE[1]:g} × rated)\n")
        print("| preset | coupling | case | onset r/min | × rated |")
        print("|---|---|---|---|---|")
        for r in onsets:
            print(f"| {r['preset']} | {r['coupling']} | {_case(r)} | {r['onset_rpm']:.0f} | "
                  f"{r['onset_rpm'] / r['speed_rpm']:.2f} |")


# ----------------------------------------------------------------------------------------------------- figures
def _plots(out_dir: Path, rows: list[dict]) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    names = list(dict.fromkeys(r["preset"] for r in rows))
    paths = []

    def parallel(name, arrangement, coupling, direction):
        ok = [r for r in _sel(rows, preset=name, arrangement=arrangement, coupling=coupling, kind="parallel")
              if (r["dir"] == direction or r["value"] == 0) and "load_y_kn" in r]
        return sorted(ok, key=lambda r: r["value"])

    def save(fig, fname):
        fig.tight_layout(rect=(0, 0, 1, 0.97))
        p = out_dir / fname
        fig.savefig(p, dpi=90)
        plt.close(fig)
        paths.append(p)

    # 1. static load transfer, e/c and margin against δ, rigid coupling, four and three bearings
    fig, axes = plt.subplots(3, len(names), figsize=(4.3 * len(names), 9.5), sharex=True, squeeze=False)
    for k, name in enumerate(names):
        for arrangement, marker in (("four", "o"), ("three", "s")):
            for direction, style in (("down", "-"), ("sideways", "--")):
                ok = parallel(name, arrangement, "rigid", direction)
                if not ok:
                    continue
                x = [r["value"] for r in ok]
                nb = len(ok[0]["load_y_kn"])
                lab = arrangement == "four" and direction == "down"
                for b in range(nb):
                    axes[0, k].plot(x, [r["load_y_kn"][b] for r in ok], style, marker=marker, ms=3, color=f"C{b}",
                                    alpha=1.0 if arrangement == "four" else 0.55,
                                    label=f"bearing {b + 1}" if lab else None)
                axes[1, k].plot(x, [r["ecc"][2] for r in ok], style, marker=marker, ms=3,
                                color="C2" if arrangement == "four" else "C5",
                                label=f"bearing 3, {arrangement} bearings, {direction}")
                axes[2, k].plot(x, [r["log_dec"] for r in ok], style, marker=marker, ms=3,
                                color="k" if arrangement == "four" else "C3",
                                label=f"{arrangement} bearings, offset {direction}")
        speed = _sel(rows, preset=name)[0]["speed_rpm"]
        axes[0, k].set_title(f"{name} at {speed:g} r/min, rigid coupling", fontsize=9)
        axes[0, k].axhline(0, color="0.6", lw=0.8)
        axes[2, k].axhline(0, color="r", lw=0.8)
        axes[2, k].set_xlabel("parallel offset δ / c (exciter bearings moved)")
    axes[0, 0].set_ylabel("vertical bearing load, kN (down +)")
    axes[1, 0].set_ylabel("bearing 3 eccentricity e/c")
    axes[2, 0].set_ylabel("log decrement, least-damped mode\n(film coefficients)")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=6)
    axes[2, 0].legend(fontsize=6)
    fig.suptitle("Static load transfer, bearing 3 and whirl margin under a parallel offset (solid: down, dashed: "
                 "sideways; circles: four bearings, squares, paler: three bearings)", fontsize=10)
    save(fig, "load_transfer.png")

    # 2. angular offset: loads and margin against α, rigid and flexible, vertical and horizontal
    fig, axes = plt.subplots(2, len(names), figsize=(4.3 * len(names), 6.8), sharex=True, squeeze=False)
    for k, name in enumerate(names):
        for coupling, alpha in (("rigid", 1.0), ("flexible", 0.5)):
            for direction, style in (("down", "-"), ("sideways", "--")):
                ok = sorted([r for r in _sel(rows, preset=name, arrangement="four", coupling=coupling)
                             if "load_y_kn" in r and (r["value"] == 0 and r["kind"] == "parallel"
                                                      or r["kind"] == "angular" and r["dir"] == direction)],
                            key=lambda r: r["value"] if r["kind"] == "angular" else 0.0)
                x = [r["value"] if r["kind"] == "angular" else 0.0 for r in ok]
                for b in range(4):
                    axes[0, k].plot(x, [r["load_y_kn"][b] for r in ok], style, marker="o", ms=3, color=f"C{b}",
                                    alpha=alpha, label=f"bearing {b + 1}" if coupling == "rigid" and
                                    direction == "down" else None)
                axes[1, k].plot(x, [r["log_dec"] for r in ok], style, marker="o", ms=3,
                                color="k" if coupling == "rigid" else "C7", label=f"{coupling}, {direction}")
        axes[0, k].set_title(f"{name}: angular offset", fontsize=9)
        axes[1, k].set_xlabel("α, mrad (exciter line tilted about the coupling)")
        axes[0, k].axhline(0, color="0.6", lw=0.8)
    axes[0, 0].set_ylabel("vertical bearing load, kN (down +)")
    axes[1, 0].set_ylabel("log decrement (film coefficients)")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=7)
    fig.suptitle("Angular offset, four bearings (solid: vertical, far end down; dashed: horizontal; pale: flexible "
                 "coupling)", fontsize=10)
    save(fig, "angular.png")

    # 3. 2X and 2X/1X against δ per preset, rigid and flexible (four bearings) and rigid three bearings
    groups = (("four", "rigid"), ("four", "flexible"), ("three", "rigid"))
    fig, axes = plt.subplots(2 * len(groups), len(names), figsize=(4.3 * len(names), 3.0 * 2 * len(groups)),
                             sharex=True, squeeze=False)
    for k, name in enumerate(names):
        for g, (arrangement, coupling) in enumerate(groups):
            a2, ar = axes[2 * g, k], axes[2 * g + 1, k]
            for direction, style in (("down", "-"), ("sideways", "--")):
                ok = [r for r in parallel(name, arrangement, coupling, direction) if "two_x_um" in r]
                x = [r["value"] for r in ok]
                for b in range(len(ok[0]["two_x_um"]) if ok else 0):
                    a2.plot(x, [r["two_x_um"][b] for r in ok], style, marker="o", ms=3, color=f"C{b}",
                            label=f"bearing {b + 1}" if direction == "down" else None)
                    ar.plot(x, [r["ratio"][b] for r in ok], style, marker="o", ms=3, color=f"C{b}")
            a2.set_title(f"{name}, {coupling} coupling, {arrangement} bearings", fontsize=9)
            a2.set_ylabel("2X, µm pk-pk")
            ar.set_ylabel("2X/1X")
            for level in (0.5, 1.0, 2.0):
                ar.axhline(level, color="r", lw=0.6, ls=":")
            ar.set_yscale("log")
            lo, hi = ar.get_ylim()
            ar.set_ylim(min(lo, 0.3), max(hi, 3.0))   # the rule's three levels always in view
        axes[-1, k].set_xlabel("parallel offset δ / c")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("2X (larger of the 45°/135° probes) and 2X/1X against a parallel offset (solid: down, dashed: "
                 "sideways; red dotted: the rule of thumb's 0.5 / 1 / 2)", fontsize=10)
    save(fig, "orders.png")

    # 4. orbits at the bearings, gen200_2pole (or the first preset), rigid and flexible, offset down
    name = "gen200_2pole" if "gen200_2pole" in names else names[0]
    fig, axes = plt.subplots(3, 4, figsize=(13, 10))
    for g, (arrangement, coupling) in enumerate(groups):
        ok = [r for r in parallel(name, arrangement, coupling, "down") if "wave_um" in r and r["value"] in (0.0, 0.5)]
        for b in range(4):
            ax = axes[g, b]
            if b >= len(ok[0]["wave_um"][0]) if ok else True:
                ax.set_axis_off()
                continue
            for r in ok:
                w = np.asarray(r["wave_um"])[:, b]
                x, y = w[:, 0] - w[:, 0].mean(), w[:, 1] - w[:, 1].mean()
                shape = (f"flat {r['flattening'][b]:.2f}, turn {r['turning'][b]:d}" if r["subsync"] < 0.05 else
                         f"not period-1: sub/1X {r['subsync']:.1f}")
                ax.plot(x, y, lw=0.8, label=f"δ = {r['value']:.1f} c: {shape}")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f"bearing {b + 1}, {coupling}, {arrangement} bearings", fontsize=8)
            ax.set_xlabel("x, µm")
            ax.set_ylabel("y (up), µm")
            ax.legend(fontsize=6)
    fig.suptitle(f"{name}: orbits relative to the bearing, mean removed, offset down (turn: tangent turning number, "
                 "1 simple orbit, 2 inner loop, 0 figure-8)", fontsize=10)
    save(fig, "orbits.png")

    # 5. centreline: journal centres of bearings 2 and 3 in their clearance as δ grows (rigid, four and three)
    fig, axes = plt.subplots(2, len(names), figsize=(4.3 * len(names), 8.4), squeeze=False)
    for k, name in enumerate(names):
        for i, b in enumerate((1, 2)):
            ax = axes[i, k]
            c = _sel(rows, preset=name)[0]["c_um"]
            ax.add_patch(__import__("matplotlib.patches", fromlist=["Circle"]).Circle((0, 0), c, fill=False,
                                                                                       color="0.6", lw=0.8))
            for arrangement, marker in (("four", "o"), ("three", "s")):
                for direction, style in (("down", "-"), ("sideways", "--")):
                    ok = parallel(name, arrangement, "rigid", direction)
                    if not ok or b >= len(ok[0]["journal_um"]):
                        continue
                    j = np.array([r["journal_um"][b] for r in ok])
                    ax.plot(j[:, 0], j[:, 1], style, marker=marker, ms=3,
                            color="C0" if arrangement == "four" else "C3", label=f"{arrangement}, {direction}")
                    ax.plot(j[0, 0], j[0, 1], "k" + marker, ms=5)
            ax.set_aspect("equal")
            ax.set_xlim(-1.1 * c, 1.1 * c)
            ax.set_ylim(-1.1 * c, 1.1 * c)
            ax.set_title(f"{name}: bearing {b + 1} journal centre", fontsize=9)
            ax.set_xlabel("x, µm (from the bearing centre)")
            ax.set_ylabel("y (up), µm")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Shaft centreline under a parallel offset 0 → 0.5 c, rigid coupling (black: aligned; circle: the "
                 "clearance c)", fontsize=10)
    save(fig, "centreline.png")
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "figures" / "train_misalignment")
    ap.add_argument("--presets", nargs="*", default=list(PRESETS), choices=list(PRESETS))
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (results do not depend on it)")
    ap.add_argument("--no-onset", action="store_true", help="skip the three-bearing whirl onset search")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    jobs = [(n, a, c, not args.no_onset) for n in args.presets for a, c in
            (("four", "rigid"), ("four", "flexible"), ("three", "rigid"))]
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            parts = list(pool.map(job, *zip(*jobs, strict=True)))
    else:
        parts = [job(*j) for j in jobs]
    rows = [r for p in parts for r in p]
    print_tables(rows)
    paths = _plots(args.out_dir, rows)
    keep = [{k: v for k, v in r.items() if k not in ("wave_um", "wall_s")} for r in rows]
    (args.out_dir / "misalignment.json").write_text(json.dumps(keep, indent=1, allow_nan=True) + "\n")
    wall = time.perf_counter() - t0
    print(f"\nwrote {', '.join(p.name for p in paths)} in {args.out_dir} and misalignment.json in {wall:.0f} s "
          f"({args.jobs} worker(s); {sum(r.get('wall_s', 0) for r in rows):.0f} s of cases)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
