"""Continuation output: HDF5 file and bifurcation diagram (stable solid, unstable dashed)."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from .continuation import KINDS, Branch
from .rotor import RotorFamily

__all__ = ["write_branches", "read_branches", "bifurcation_figure", "FORMAT"]

FORMAT = "rotordiag-branches-1"


def write_branches(path: str | Path, family: RotorFamily, branches: list[Branch], *, node: int = 3,
                   direction: int = 0, brute: Any = None) -> None:
    """HDF5: one group per branch (parameter, reduced states, section coordinate of ``node``,
    multipliers, stability, bifurcations), the inputs as JSON, and the brute-force sweep if given."""
    import h5py

    with h5py.File(path, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["parameter"] = family.parameter
        f.attrs["inputs_json"] = json.dumps(dict(
            plant=family.plant.to_dict(), speed_rpm=family.speed_rpm, misalignment=family.misalignment,
            unbalance=family.unbalance, mechanism=family.mechanism, rtol=family.rtol, atol=family.atol,
            node=node, direction="xy"[direction], **family.system_kwargs))
        for i, br in enumerate(branches):
            g = f.create_group(f"branch_{i}")
            g.attrs["n_periods"] = br.n_periods
            g.attrs["message"] = br.message
            g.create_dataset("parameter", data=br.values)
            g.create_dataset("states", data=br.states)
            g.create_dataset("section_x", data=_section_coords(family, br, node, direction))
            g.create_dataset("multipliers", data=np.array([p.multipliers for p in br.points]))
            g.create_dataset("stability", data=br.stability.astype("S"))
            bg = g.create_group("bifurcations")
            bg.create_dataset("kind", data=np.array([b.kind for b in br.bifurcations], dtype="S"))
            bg.create_dataset("parameter", data=np.array([b.parameter for b in br.bifurcations], dtype=float))
            bg.create_dataset("located", data=np.array([b.located for b in br.bifurcations], dtype=bool))
            bg.create_dataset("index", data=np.array([b.index for b in br.bifurcations], dtype=np.int64))
            bx = [_section_one(family, b.parameter, b.sections, node, direction) for b in br.bifurcations]
            # a branch without bifurcations still needs a (0, n) array (reshape(0, -1) is ambiguous)
            bg.create_dataset("section_x", data=np.array(bx).reshape(len(bx), -1) if bx
                              else np.empty((0, br.n_periods)))
        if brute is not None:
            g = f.create_group("brute_force")
            g.create_dataset("values", data=brute.values)
            g.create_dataset("poincare", data=brute.poincare)
            g.create_dataset("motion", data=brute.motion.astype("S"))


def read_branches(path: str | Path) -> dict[str, Any]:
    """Read a file of :func:`write_branches` into plain arrays."""
    import h5py

    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{path} is not a rotordiag branches file")
        out: dict[str, Any] = dict(parameter=str(f.attrs["parameter"]), inputs=json.loads(f.attrs["inputs_json"]),
                                   branches=[])
        for name in sorted(k for k in f if k.startswith("branch_")):
            g = f[name]
            out["branches"].append(dict(
                n_periods=int(g.attrs["n_periods"]), parameter=g["parameter"][()], states=g["states"][()],
                section_x=g["section_x"][()], multipliers=g["multipliers"][()],
                stability=g["stability"][()].astype(str),
                bifurcations=dict(kind=g["bifurcations/kind"][()].astype(str),
                                  parameter=g["bifurcations/parameter"][()],
                                  located=g["bifurcations/located"][()],
                                  index=g["bifurcations/index"][()],
                                  section_x=g["bifurcations/section_x"][()])))
        if "brute_force" in f:
            out["brute_force"] = dict(values=f["brute_force/values"][()], poincare=f["brute_force/poincare"][()],
                                      motion=f["brute_force/motion"][()].astype(str))
        return out


def _section_one(family: RotorFamily, value: float, sections: np.ndarray, node: int, direction: int) -> np.ndarray:
    return family.node_sections(value, sections, node, direction)


def _section_coords(family: RotorFamily, br: Branch, node: int, direction: int) -> np.ndarray:
    return np.array([_section_one(family, p.parameter, p.sections, node, direction) for p in br.points]).reshape(
        len(br.points), br.n_periods)


def bifurcation_figure(path: str | Path, data: dict[str, Any], *, title: str = "") -> None:
    """PNG from :func:`read_branches` data: branches (stable solid, unstable dashed, one colour per
    period), bifurcation points marked (LP fold ▲, PD period doubling ■, NS torus ◆), brute-force
    Poincaré points overlaid (grey dots)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5.5))
    bf = data.get("brute_force")
    if bf is not None:
        vals = np.repeat(bf["values"][:, None], bf["poincare"].shape[1], axis=1)
        ax.plot(vals.ravel(), bf["poincare"].ravel(), ".", color="0.55", ms=2.5, label="brute force (Poincaré)",
                zorder=1)
    markers = {"fold": "^", "period_doubling": "s", "neimark_sacker": "D"}
    seen: set[str] = set()
    for i, br in enumerate(data["branches"]):
        color = f"C{i}"
        p, xs, st = _with_bifurcations(br)
        for k in range(xs.shape[1]):
            for j in range(len(p) - 1):
                pair = {st[j], st[j + 1]}
                solid = "unstable" not in pair and "marginal" not in pair
                lab = f"period-{br['n_periods']} {'stable' if solid else 'unstable'}"
                ax.plot(p[j:j + 2], xs[j:j + 2, k], "-" if solid else "--", color=color, lw=1.6 if solid else 1.1,
                        label=None if lab in seen else lab, zorder=2)
                seen.add(lab)
        b = br["bifurcations"]
        for kind, pv, sx in zip(b["kind"], b["parameter"], b["section_x"]):
            ax.plot(np.full(len(sx), pv), sx, markers[kind], color="k", mfc="none" if kind == "fold" else "k",
                    ms=7, label=None if kind in seen else KINDS[kind], zorder=3)
            seen.add(kind)
    ax.set_xlabel("speed (r/min)" if data["parameter"] == "speed_rpm" else "Δ = δ/c")
    inp = data["inputs"]
    ax.set_ylabel(f"Poincaré {inp['direction']} of node {inp['node']} (x/c)")
    ax.set_title(title or f"Continuation: {inp['mechanism']}, A = {inp['unbalance']:g}")
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _with_bifurcations(br: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Branch arrays with each located bifurcation inserted where it lies (between its two points),
    marked "boundary", so that the solid and dashed pieces change exactly there."""
    p = list(br["parameter"])
    xs = list(br["section_x"])
    st = list(br["stability"])
    b = br["bifurcations"]
    # from the last to the first, so earlier insertions do not shift the later indices
    for i in sorted(range(len(b["kind"])), key=lambda i: -int(b["index"][i])):
        if b["located"][i]:
            j = int(b["index"][i]) + 1
            p.insert(j, b["parameter"][i])
            xs.insert(j, b["section_x"][i])
            st.insert(j, "boundary")
    return np.asarray(p), np.asarray(xs).reshape(len(p), -1), np.asarray(st)
