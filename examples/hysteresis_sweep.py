"""Up-sweep / down-sweep in Δ or speed overlaid on the continuation branch (issue 16 item 3).

Brute-force sweeps in increasing and in decreasing Δ at a fixed speed (or speed at a fixed Δ: the
branches file says which), each point started from the previous point's end state (``simulate(initial_state=...)``; the library's sweeps start
every point from the same state), overlaid on a branches file of ``rotordiag continue``.

Run (default plant, 1843 r/min; ≈ 1–2 min on one core)::

    rotordiag continue --over misalignment --from 0.02 --to 0.6 --speed-rpm 1843 \\
        --out /tmp/d1843.h5 --max-points 120 --brute-points 0
    python examples/hysteresis_sweep.py /tmp/d1843.h5 docs/figures/continuation_hysteresis_1843.png

Light-exciter plant, 1843 r/min, with the period-3 and period-5 windows (isolas) overlaid::

    P=docs/figures/light-exciter-plant.toml
    rotordiag continue --over misalignment --from 0.02 --to 0.16 --speed-rpm 1843 --plant $P \\
        --out /tmp/l1.h5 --brute-points 0 --max-points 100
    rotordiag continue --over misalignment --from 0.08 --to 0.16 --lo 0.02 --speed-rpm 1843 --plant $P \\
        --start-revs 400 --out /tmp/l3.h5 --brute-points 0
    rotordiag continue --over misalignment --from 0.14 --to 0.16 --lo 0.02 --speed-rpm 1843 --plant $P \\
        --start-revs 400 --out /tmp/l5.h5 --brute-points 0
    python examples/hysteresis_sweep.py /tmp/l1.h5 docs/figures/light-exciter/continuation_hysteresis_1843.png \\
        --extra /tmp/l3.h5 --extra /tmp/l5.h5 --from 0.02 --to 0.16 --step 0.001 --record-revs 16

Speed, through the oil-whirl onset (the Neimark–Sacker point of the period-1 branch)::

    rotordiag continue --over speed --from 1500 --to 2500 --misalignment 0.02 --out /tmp/s002.h5 --brute-points 0
    python examples/hysteresis_sweep.py /tmp/s002.h5 /tmp/s002.png --from 2250 --to 2400 --step 5

Prints the Δ (or speed) of each jump (the largest change of the section coordinate between
neighbours) and where the whirl starts/ends in each direction.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from rotordiag.simulator import Plant, simulate  # noqa: E402
from rotordiag.simulator.steady.report import read_branches  # noqa: E402


def sweep(plant: Plant, values: np.ndarray, over: str, fixed: float, unbalance: float, mechanism: str, node: int,
          transient_revs: int, record_revs: int) -> np.ndarray:
    """Section x/c of ``node`` (record_revs per value of Δ or speed), each started from the previous end state."""
    state = None
    out = np.full((values.size, record_revs), np.nan)
    for i, v in enumerate(values):
        speed, delta = (float(v), fixed) if over == "speed_rpm" else (fixed, float(v))
        res = simulate(plant, speed, delta, unbalance, mechanism=mechanism, transient_revs=transient_revs,
                       record_revs=record_revs, samples_per_rev=8, initial_state=state, settle_tol=1e-9)
        if res.status != "ok":
            print(f"{over} = {v:.4f}: {res.status}; restarting the next point from MODEL.md's state")
            state = None
            continue
        out[i] = res.poincare_m[:, node - 1, 0] / res.clearance_m
        state = res.final_state.copy()
        # the coupling angle φ (pin) turns continuously in the racing regime; taken mod 2π (the
        # equations are 2π-periodic in it) so that chained runs do not accumulate it past the
        # integrator's divergence limit (1e4 on any coordinate). In a speed sweep the state is
        # non-dimensional (velocities per radian), so a step of a few r/min changes it by < 1 %:
        # an initial condition, and the transient settles it.
        state[10] = np.remainder(state[10], 2 * np.pi)
    return out


#: bifurcation markers drawn: kind -> (marker, label)
MARKERS = {"fold": ("^", "LP"), "neimark_sacker": ("s", "NS"), "period_doubling": ("v", "PD")}

#: a record whose section x spreads by more than this (x/c) is whirling (not period-1)
WHIRL_SPREAD = 0.01


#: two section x/c values repeat when they differ by less than this
PERIOD_TOL = 1e-4


def _period(row: np.ndarray) -> int:
    """Least n (≤ half the record) with x[k + n] = x[k] within PERIOD_TOL for all k; 0 if none."""
    if not np.all(np.isfinite(row)):
        return 0
    for n in range(1, row.size // 2 + 1):
        if np.max(np.abs(row[n:] - row[:-n])) < PERIOD_TOL:
            return n
    return 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("branches", type=Path, help="HDF5 of rotordiag continue --over misalignment")
    ap.add_argument("png", type=Path)
    ap.add_argument("--extra", type=Path, action="append", default=[],
                    help="further branches files (same plant, speed), e.g. period-n windows")
    ap.add_argument("--from", dest="lo", type=float, default=0.15)
    ap.add_argument("--to", dest="hi", type=float, default=0.26)
    ap.add_argument("--step", type=float, default=0.0025)
    ap.add_argument("--transient-revs", type=int, default=300)
    ap.add_argument("--record-revs", type=int, default=8)
    args = ap.parse_args()
    data = read_branches(args.branches)
    inp = data["inputs"]
    over = str(data.get("parameter", "misalignment"))
    speed, unb, node = float(inp["speed_rpm"]), float(inp["unbalance"]), int(inp["node"])
    fixed = float(inp["misalignment"]) if over == "speed_rpm" else speed
    mechanism = str(inp.get("mechanism", "pin"))
    sym = "speed (r/min)" if over == "speed_rpm" else "Δ"
    plant = Plant.from_dict(inp["plant"])
    light = plant != Plant.default()
    branches = list(data["branches"]) + [b for f in args.extra for b in read_branches(f)["branches"]]
    up = np.arange(args.lo, args.hi + args.step * 1e-9, args.step)
    down = up[::-1]
    x_up = sweep(plant, up, over, fixed, unb, mechanism, node, args.transient_revs, args.record_revs)
    x_down = sweep(plant, down, over, fixed, unb, mechanism, node, args.transient_revs, args.record_revs)
    for name, d, x in (("up", up, x_up), ("down", down, x_down)):
        m = np.nanmean(x, axis=1)
        j = int(np.nanargmax(np.abs(np.diff(m))))
        print(f"{name}-sweep jump between {sym} = {d[j]:.4f} and {d[j + 1]:.4f}: x/c {m[j]:.4f} -> {m[j + 1]:.4f}")
        whirl = np.nanmax(x, axis=1) - np.nanmin(x, axis=1) > WHIRL_SPREAD
        if whirl.any() and not whirl.all():
            k = int(np.argmax(whirl != whirl[0]))
            print(f"  {name}-sweep: {'whirl starts' if not whirl[0] else 'whirl ends'} between {sym} = "
                  f"{d[k - 1]:.4f} and {d[k]:.4f} (section x spread > {WHIRL_SPREAD} x/c)")
        periods = [_period(row) for row in x]
        runs = []
        for k, n in enumerate(periods):
            if runs and runs[-1][0] == n:
                runs[-1][2] = d[k]
            else:
                runs.append([n, d[k], d[k]])
        print(f"  {name}-sweep, period of the recorded x (≤ {args.record_revs // 2}, within {PERIOD_TOL:g} x/c; "
              "0: none): " + ", ".join(f"{n} @ {a:.4f}–{b:.4f}" for n, a, b in runs))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5.5))
    for br in branches:
        p, st = br["parameter"], br["stability"]
        margin = 8 * args.step
        keep = (p >= args.lo - margin) & (p <= args.hi + margin)
        for k in range(br["section_x"].shape[1]):  # every section point of a period-n orbit
            x = br["section_x"][:, k]
            for j in np.flatnonzero(keep[:-1] & keep[1:]):
                stable = st[j] == "stable" and st[j + 1] == "stable"
                ax.plot(p[j:j + 2], x[j:j + 2], "-" if stable else "--", color="C0" if stable else "C3",
                        lw=1.6 if stable else 1.0)
        b = br["bifurcations"]
        for kind, pv, sx in zip(b["kind"], b["parameter"], b["section_x"]):
            if kind in MARKERS and args.lo - margin <= pv <= args.hi + margin:
                ax.plot(np.full(len(sx), pv), sx, MARKERS[kind][0], color="k", mfc="none", ms=9)
                ax.annotate(f"{MARKERS[kind][1]} {pv:.4f}", (pv, sx[0]), textcoords="offset points", xytext=(6, -12),
                            fontsize=8)
    ax.plot([], [], "-", color="C0", label="continuation, stable")
    ax.plot([], [], "--", color="C3", label="continuation, unstable")
    ax.plot([], [], "^", color="k", mfc="none", label="fold (LP)")
    ax.plot([], [], "s", color="k", mfc="none", label="torus (NS)")
    shift = 0.16 * args.step
    ax.plot(np.repeat(up, args.record_revs) - shift, x_up.ravel(), ">", color="C2", ms=4,
            label="up-sweep (brute force, from previous state)")
    ax.plot(np.repeat(down, args.record_revs) + shift, x_down.ravel(), "<", color="C1", ms=4,
            label="down-sweep (brute force, from previous state)")
    ax.set_xlim(args.lo - 4 * args.step, args.hi + 4 * args.step)
    ax.set_xlabel("speed (r/min)" if over == "speed_rpm" else "Δ = δ/c")
    ax.set_ylabel(f"Poincaré x of node {node} (x/c)")
    where = f"Δ = {fixed:g}" if over == "speed_rpm" else f"{speed:g} r/min"
    ax.set_title(f"Hysteresis at {where}: {mechanism}, A = {unb:g}, {'light-exciter' if light else 'default'} plant")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(args.png, dpi=100)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
