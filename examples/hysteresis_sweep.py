"""Up-sweep / down-sweep in Δ overlaid on the continuation branch (issue 16 item 3).

Brute-force sweeps in increasing and in decreasing Δ at a fixed speed, each point started from
the previous point's end state (``simulate(initial_state=...)``; the library's sweeps start
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

Prints the Δ of each jump (the largest change of the section coordinate between neighbours).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from rotordiag.simulator import Plant, simulate  # noqa: E402
from rotordiag.simulator.steady.report import read_branches  # noqa: E402


def sweep(plant: Plant, deltas: np.ndarray, speed_rpm: float, unbalance: float, node: int, transient_revs: int,
          record_revs: int) -> np.ndarray:
    """Section x/c of ``node`` (record_revs per Δ), each Δ started from the previous end state."""
    state = None
    out = np.full((deltas.size, record_revs), np.nan)
    for i, d in enumerate(deltas):
        res = simulate(plant, speed_rpm, float(d), unbalance, transient_revs=transient_revs,
                       record_revs=record_revs, samples_per_rev=8, initial_state=state, settle_tol=1e-9)
        if res.status != "ok":
            print(f"Δ = {d:.4f}: {res.status}; restarting the next point from MODEL.md's state")
            state = None
            continue
        out[i] = res.poincare_m[:, node - 1, 0] / res.clearance_m
        state = res.final_state.copy()
        # the coupling angle φ (pin) turns continuously in the racing regime; taken mod 2π (the
        # equations are 2π-periodic in it) so that chained runs do not accumulate it past the
        # integrator's divergence limit (1e4 on any coordinate)
        state[10] = np.remainder(state[10], 2 * np.pi)
    return out


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
    speed, unb, node = float(inp["speed_rpm"]), float(inp["unbalance"]), int(inp["node"])
    plant = Plant.from_dict(inp["plant"])
    light = plant != Plant.default()
    branches = list(data["branches"]) + [b for f in args.extra for b in read_branches(f)["branches"]]
    up = np.arange(args.lo, args.hi + 1e-12, args.step)
    down = up[::-1]
    x_up = sweep(plant, up, speed, unb, node, args.transient_revs, args.record_revs)
    x_down = sweep(plant, down, speed, unb, node, args.transient_revs, args.record_revs)
    for name, d, x in (("up", up, x_up), ("down", down, x_down)):
        m = np.nanmean(x, axis=1)
        j = int(np.nanargmax(np.abs(np.diff(m))))
        print(f"{name}-sweep jump between Δ = {d[j]:.4f} and {d[j + 1]:.4f}: x/c {m[j]:.4f} -> {m[j + 1]:.4f}")
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
        keep = (p >= args.lo - 0.02) & (p <= args.hi + 0.02)
        for k in range(br["section_x"].shape[1]):  # every section point of a period-n orbit
            x = br["section_x"][:, k]
            for j in np.flatnonzero(keep[:-1] & keep[1:]):
                stable = st[j] == "stable" and st[j + 1] == "stable"
                ax.plot(p[j:j + 2], x[j:j + 2], "-" if stable else "--", color="C0" if stable else "C3",
                        lw=1.6 if stable else 1.0)
        b = br["bifurcations"]
        for kind, pv, sx in zip(b["kind"], b["parameter"], b["section_x"]):
            if kind == "fold" and args.lo - 0.02 <= pv <= args.hi + 0.02:
                ax.plot(np.full(len(sx), pv), sx, "^", color="k", mfc="none", ms=9)
                ax.annotate(f"LP {pv:.4f}", (pv, sx[0]), textcoords="offset points", xytext=(6, -12), fontsize=8)
    ax.plot([], [], "-", color="C0", label="continuation, stable")
    ax.plot([], [], "--", color="C3", label="continuation, unstable")
    ax.plot([], [], "^", color="k", mfc="none", label="fold (LP)")
    ax.plot(np.repeat(up, args.record_revs) - 0.0004, x_up.ravel(), ">", color="C2", ms=4,
            label="up-sweep (brute force, from previous state)")
    ax.plot(np.repeat(down, args.record_revs) + 0.0004, x_down.ravel(), "<", color="C1", ms=4,
            label="down-sweep (brute force, from previous state)")
    ax.set_xlim(args.lo - 0.01, args.hi + 0.01)
    ax.set_xlabel("Δ = δ/c")
    ax.set_ylabel(f"Poincaré x of node {node} (x/c)")
    ax.set_title(f"Hysteresis at {speed:g} r/min: pin, A = {unb:g}, {'light-exciter' if light else 'default'} plant")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(args.png, dpi=100)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
