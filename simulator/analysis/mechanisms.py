"""Every coupling mechanism side by side (issue 13, docs/reproduction.md "Misalignment mechanisms").

:func:`mechanism_survey` runs each mechanism at a few speeds over Δ on one plant and
records, per bearing, the 1X and 2X amplitudes (µm, zero-to-peak, horizontal and
vertical), 2X/1X, and the static journal position (eccentricity, attitude angle,
load). It also runs the ``flexible`` mechanism's sensitivity to the phase ψ and to
the coupling stiffness k_c. :func:`survey_figure` draws the PNG and
:func:`survey_markdown` the tables of docs/reproduction.md; the CLI is
``rotordiag mechanisms --out DIR``.
"""
from __future__ import annotations

import math
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: What the survey runs by default (docs/reproduction.md).
SPEEDS_RPM: tuple[float, ...] = (1500.0, 1950.0, 3000.0)
DELTAS: tuple[float, ...] = (0.0, 0.05, 0.1, 0.2, 0.3, 0.5)
#: mechanism label -> (mechanism, offset_angle_rad)
CASES: dict[str, tuple[str, float]] = {
    "pin": ("pin", 0.0),
    "rigid": ("rigid", 0.0),
    "offset-down": ("offset", -0.5 * math.pi),
    "offset-horiz": ("offset", 0.0),
    "flexible": ("flexible", 0.0),
}
PHASES_DEG: tuple[float, ...] = tuple(range(0, 360, 30))
COUPLING_STIFFNESSES_N_M: tuple[float, ...] = (1e7, 3e7, 1e8, 3e8, 1e9)


@dataclass(frozen=True)
class SurveyPoint:
    """One run of the survey and what it measured (arrays over bearings 1..4, directions x, y)."""

    case: str
    mechanism: str
    speed_rpm: float
    misalignment: float
    coupling_phase_deg: float
    coupling_stiffness_n_m: float
    status: str
    amp_1x_um_0pk: list[list[float]] = field(default_factory=list)
    amp_2x_um_0pk: list[list[float]] = field(default_factory=list)
    static_eccentricity: list[float] = field(default_factory=list)
    attitude_angle_deg: list[float] = field(default_factory=list)
    static_load_n: list[list[float]] = field(default_factory=list)
    wall_time_s: float = 0.0
    angular_misalignment_mrad: float = 0.0

    def ratio(self, bearing: int, direction: int = 0) -> float:
        a1 = self.amp_1x_um_0pk[bearing][direction]
        return self.amp_2x_um_0pk[bearing][direction] / a1 if a1 > 0 else float("nan")


def _run(task: tuple) -> SurveyPoint:
    from rotordiag.simulator import Plant, simulate
    from rotordiag.simulator.simulate import order_amplitudes

    case, mech, angle, speed, delta, psi_deg, kc, plant_dict, unbalance, revs = task[:10]
    alpha_mrad = float(task[10]) if len(task) > 10 else 0.0  # angular offset (offset/flexible)
    exciter_unbalance = float(task[11]) if len(task) > 11 else 0.0
    plant = Plant.from_dict(plant_dict).replace(coupling_stiffness_n_m=kc)
    res = simulate(plant, speed, delta, unbalance, mechanism=mech if delta > 0 or alpha_mrad else "aligned",
                   offset_angle_rad=angle, coupling_phase_rad=math.radians(psi_deg),
                   angular_misalignment_mrad=alpha_mrad, exciter_unbalance=exciter_unbalance,
                   transient_revs=400, record_revs=revs, samples_per_rev=64, settle_tol=1e-8)
    if res.status != "ok":
        return SurveyPoint(case, mech, speed, delta, psi_deg, kc, res.status, wall_time_s=res.wall_time_s,
                           angular_misalignment_mrad=alpha_mrad)
    amps = order_amplitudes(res, (1, 2)) * 1e6
    return SurveyPoint(
        case, mech, speed, delta, psi_deg, kc, res.status,
        amp_1x_um_0pk=amps[:, :, 0].tolist(), amp_2x_um_0pk=amps[:, :, 1].tolist(),
        static_eccentricity=res.static_eccentricity.tolist(), attitude_angle_deg=res.attitude_angle_deg.tolist(),
        static_load_n=res.mean_bearing_load_n.tolist(), wall_time_s=res.wall_time_s,
        angular_misalignment_mrad=alpha_mrad,
    )


def mechanism_survey(plant: Any = None, *, speeds_rpm: tuple[float, ...] = SPEEDS_RPM,
                     deltas: tuple[float, ...] = DELTAS, unbalance: float = 0.05,
                     phase_delta: float = 0.3, phase_speed_rpm: float = 1950.0, record_revs: int = 64,
                     workers: int | None = None) -> list[SurveyPoint]:
    """Run the survey (default plant: MODEL.md's). ``workers`` processes (default: usable CPUs, 0 = here)."""
    from rotordiag.simulator import Plant

    plant = Plant.default() if plant is None else plant
    pd = plant.to_dict()
    kc0 = plant.coupling_stiffness_n_m
    tasks = []
    for speed in speeds_rpm:
        for case, (mech, angle) in CASES.items():
            for d in deltas:
                if d == 0 and case != "pin":
                    continue  # Δ = 0 is the aligned run, once per speed (labelled pin)
                tasks.append((case if d > 0 else "aligned", mech, angle, speed, d, 0.0, kc0, pd, unbalance, record_revs))
    for psi in PHASES_DEG:
        tasks.append(("flexible-phase", "flexible", 0.0, phase_speed_rpm, phase_delta, float(psi), kc0, pd,
                      unbalance, record_revs))
    for kc in COUPLING_STIFFNESSES_N_M:
        for d in deltas[1:]:
            tasks.append(("flexible-kc", "flexible", 0.0, phase_speed_rpm, d, 0.0, kc, pd, unbalance, record_revs))
    n = len(os.sched_getaffinity(0)) if workers is None else int(workers)
    if n <= 0:
        return [_run(t) for t in tasks]
    with ProcessPoolExecutor(max_workers=n) as pool:
        return list(pool.map(_run, tasks))


def survey_markdown(points: list[SurveyPoint]) -> str:
    """The tables of docs/reproduction.md (horizontal direction, amplitudes µm 0-pk)."""
    lines = ["| case | r/min | Δ | 1X b1..b4 (µm 0-pk, x) | 2X b1..b4 (µm 0-pk, x) | 2X/1X b2, b3 (x) | "
             "ε b1..b4 | attitude b2, b3 (°) | load b2, b3 (kN, y) |", "|" + "---|" * 9]
    main = [p for p in points if p.case not in ("flexible-phase", "flexible-kc")]
    for p in main:
        if p.status != "ok":
            lines.append(f"| {p.case} | {p.speed_rpm:g} | {p.misalignment:g} | {p.status} | | | | | |")
            continue
        a1 = " / ".join(f"{p.amp_1x_um_0pk[b][0]:.1f}" for b in range(4))
        a2 = " / ".join(f"{p.amp_2x_um_0pk[b][0]:.1f}" for b in range(4))
        ecc = " / ".join(f"{e:.2f}" for e in p.static_eccentricity)
        lines.append(f"| {p.case} | {p.speed_rpm:g} | {p.misalignment:g} | {a1} | {a2} | "
                     f"{p.ratio(1):.2f}, {p.ratio(2):.2f} | {ecc} | {p.attitude_angle_deg[1]:.0f}, "
                     f"{p.attitude_angle_deg[2]:.0f} | {p.static_load_n[1][1] / 1e3:.1f}, "
                     f"{p.static_load_n[2][1] / 1e3:.1f} |")
    lines += ["", "| ψ (°) | 2X b2 x (µm) | 2X/1X b2 x | 2X b3 x (µm) | 2X/1X b3 x |", "|---|---|---|---|---|"]
    for p in (p for p in points if p.case == "flexible-phase" and p.status == "ok"):
        lines.append(f"| {p.coupling_phase_deg:g} | {p.amp_2x_um_0pk[1][0]:.2f} | {p.ratio(1):.2f} | "
                     f"{p.amp_2x_um_0pk[2][0]:.2f} | {p.ratio(2):.2f} |")
    lines += ["", "| k_c (N/m) | Δ | 2X/1X b2 x | 2X/1X b3 x | 2X b3 x (µm) |", "|---|---|---|---|---|"]
    for p in (p for p in points if p.case == "flexible-kc" and p.status == "ok"):
        lines.append(f"| {p.coupling_stiffness_n_m:.0e} | {p.misalignment:g} | {p.ratio(1):.2f} | {p.ratio(2):.2f} | "
                     f"{p.amp_2x_um_0pk[2][0]:.2f} |")
    return "\n".join(lines) + "\n"


def survey_figure(points: list[SurveyPoint], path: str | Path) -> None:
    """PNG: 2X/1X at bearings 2 and 3 and static eccentricity at bearing 3 versus Δ per mechanism and
    speed, plus the ``flexible`` phase and stiffness sensitivity."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    speeds = sorted({p.speed_rpm for p in points if p.case not in ("flexible-phase", "flexible-kc")})
    fig, axes = plt.subplots(3, len(speeds) + 1, figsize=(4.2 * (len(speeds) + 1), 11))
    colors = {c: f"C{i}" for i, c in enumerate(CASES)}
    for j, speed in enumerate(speeds):
        ok = [p for p in points if p.speed_rpm == speed and p.status == "ok"
              and p.case not in ("flexible-phase", "flexible-kc")]
        aligned = [p for p in ok if p.case == "aligned"]
        for case in CASES:
            pts = aligned + sorted((p for p in ok if p.case == case), key=lambda p: p.misalignment)
            d = [p.misalignment for p in pts]
            for row, b, fn in ((0, 1, lambda p: p.ratio(1)), (1, 2, lambda p: p.ratio(2)),
                               (2, 2, lambda p: p.static_eccentricity[2])):
                axes[row, j].plot(d, [fn(p) for p in pts], "o-", ms=3, color=colors[case], label=case)
        axes[0, j].set_title(f"{speed:g} r/min: 2X/1X bearing 2 (generator, x)")
        axes[1, j].set_title(f"{speed:g} r/min: 2X/1X bearing 3 (exciter, x)")
        axes[2, j].set_title(f"{speed:g} r/min: static ε bearing 3")
        for row in range(3):
            axes[row, j].set_xlabel("Δ = δ/c")
            if row < 2:
                axes[row, j].set_yscale("log")
                axes[row, j].axhline(1.0, color="k", lw=0.5, ls="--")
    axes[0, 0].legend(fontsize=7)
    ph = sorted((p for p in points if p.case == "flexible-phase" and p.status == "ok"),
                key=lambda p: p.coupling_phase_deg)
    ax = axes[0, -1]
    ax.plot([p.coupling_phase_deg for p in ph], [p.ratio(1) for p in ph], "o-", label="bearing 2")
    ax.plot([p.coupling_phase_deg for p in ph], [p.ratio(2) for p in ph], "s-", label="bearing 3")
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.5, ls="--")
    if ph:
        ax.set_title(f"flexible: 2X/1X (x) vs ψ, Δ = {ph[0].misalignment:g}, {ph[0].speed_rpm:g} r/min")
    ax.set_xlabel("ψ (degrees)")
    ax.legend(fontsize=7)
    kcs = sorted({p.coupling_stiffness_n_m for p in points if p.case == "flexible-kc"})
    for row, b in ((1, 1), (2, 2)):
        ax = axes[row, -1]
        for i, kc in enumerate(kcs):
            pts = sorted((p for p in points if p.case == "flexible-kc" and p.coupling_stiffness_n_m == kc
                          and p.status == "ok"), key=lambda p: p.misalignment)
            ax.plot([p.misalignment for p in pts], [p.ratio(b) for p in pts], "o-", ms=3, color=f"C{i}",
                    label=f"k_c = {kc:.0e} N/m")
        ax.set_yscale("log")
        ax.axhline(1.0, color="k", lw=0.5, ls="--")
        ax.set_title(f"flexible: 2X/1X bearing {b + 1} (x) vs Δ and k_c")
        ax.set_xlabel("Δ = δ/c")
        ax.legend(fontsize=7)
    fig.suptitle("Coupling mechanisms on the MODEL.md default plant, A = 0.05 (amplitudes from the "
                 "horizontal probe, 0-pk; ψ = 0, k_c = plant default unless varied)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


#: The ``flexible`` range survey (docs/reproduction.md "flexible across k_c and ψ"): every speed of the
#: survey, the explored k_c range (docs/model.md), four phases ψ and Δ up to 0.3.
RANGE_STIFFNESSES_N_M: tuple[float, ...] = (1e7, 3e7, 1e8, 3e8, 1e9)
RANGE_PHASES_DEG: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)
RANGE_DELTAS: tuple[float, ...] = (0.05, 0.1, 0.2, 0.3)


def flexible_range_survey(plant: Any = None, *, speeds_rpm: tuple[float, ...] = SPEEDS_RPM,
                          stiffnesses_n_m: tuple[float, ...] = RANGE_STIFFNESSES_N_M,
                          phases_deg: tuple[float, ...] = RANGE_PHASES_DEG,
                          deltas: tuple[float, ...] = RANGE_DELTAS, unbalance: float = 0.05,
                          exciter_unbalance: float = 0.0, record_revs: int = 32,
                          workers: int | None = None) -> list[SurveyPoint]:
    """``flexible`` over speed × k_c × ψ × Δ (offset horizontal), plus the aligned run per speed
    (case ``"aligned"``, Δ = 0). Same measurements as :func:`mechanism_survey`; ``exciter_unbalance``
    a2/c (phase 0) for every run."""
    from rotordiag.simulator import Plant

    plant = Plant.default() if plant is None else plant
    pd = plant.to_dict()
    a2 = float(exciter_unbalance)
    tasks = [("aligned", "flexible", 0.0, s, 0.0, 0.0, plant.coupling_stiffness_n_m, pd, unbalance, record_revs,
              0.0, a2) for s in speeds_rpm]
    tasks += [("flexible-range", "flexible", 0.0, s, d, float(psi), kc, pd, unbalance, record_revs, 0.0, a2)
              for s in speeds_rpm for kc in stiffnesses_n_m for psi in phases_deg for d in deltas]
    n = len(os.sched_getaffinity(0)) if workers is None else int(workers)
    if n <= 0:
        return [_run(t) for t in tasks]
    with ProcessPoolExecutor(max_workers=n) as pool:
        return list(pool.map(_run, tasks))


def _range_verdict(points: list[SurveyPoint], speed: float, kc: float, bearing: int) -> dict[str, Any]:
    """At one speed, k_c and bearing (x probe), over the phases ψ: for how many ψ the 2X grows
    monotonically over Δ > 0; the smallest Δ from which 2X/1X > 1 for every ψ (None: never); the
    ranges over ψ of 2X/1X and of the 2X amplitude (µm 0-pk) at the largest Δ; the aligned 2X."""
    ref = [p for p in points if p.case == "aligned" and p.speed_rpm == speed and p.status == "ok"]
    pts = [p for p in points if p.case == "flexible-range" and p.speed_rpm == speed
           and p.coupling_stiffness_n_m == kc]
    phases = sorted({p.coupling_phase_deg for p in pts})
    deltas = sorted({p.misalignment for p in pts})
    grows = 0
    for psi in phases:
        run = sorted((p for p in pts if p.coupling_phase_deg == psi), key=lambda p: p.misalignment)
        a2 = [p.amp_2x_um_0pk[bearing][0] if p.status == "ok" else float("nan") for p in run]
        grows += int(all(b > a for a, b in zip(a2, a2[1:])))
    above = [d for d in deltas if all(p.status == "ok" and p.ratio(bearing) > 1.0
                                      for p in pts if p.misalignment == d)]
    first = next((d for i, d in enumerate(deltas) if all(e in above for e in deltas[i:])), None)
    last = [p for p in pts if p.misalignment == deltas[-1] and p.status == "ok"] if deltas else []
    ratios = [p.ratio(bearing) for p in last]
    amps = [p.amp_2x_um_0pk[bearing][0] for p in last]
    return {"grows": f"{grows}/{len(phases)}", "first_delta_above_1": first,
            "ratio": (min(ratios), max(ratios)) if ratios else (float("nan"),) * 2,
            "amp_2x_um": (min(amps), max(amps)) if amps else (float("nan"),) * 2,
            "aligned_2x_um": ref[0].amp_2x_um_0pk[bearing][0] if ref else float("nan")}


def range_markdown(points: list[SurveyPoint]) -> str:
    """Table of :func:`flexible_range_survey`, per speed and k_c, at bearings 2 and 3 (x probe): for
    how many phases ψ the 2X grows monotonically over Δ > 0, from which Δ 2X/1X > 1 for every ψ, the
    ranges over ψ of 2X/1X and 2X (µm 0-pk) at the largest Δ against the aligned 2X; then every run."""
    speeds = sorted({p.speed_rpm for p in points})
    kcs = sorted({p.coupling_stiffness_n_m for p in points if p.case == "flexible-range"})
    dmax = max(p.misalignment for p in points)
    lines = [f"| r/min | k_c (N/m) | bearing | 2X grows over Δ > 0 (ψ) | 2X/1X > 1 for every ψ from Δ = | "
             f"2X/1X at Δ = {dmax:g} (over ψ) | 2X µm 0-pk at Δ = {dmax:g} (over ψ) | 2X µm aligned |",
             "|" + "---|" * 8]
    for s in speeds:
        for kc in kcs:
            for b in (1, 2):
                v = _range_verdict(points, s, kc, b)
                first = "never" if v["first_delta_above_1"] is None else f"{v['first_delta_above_1']:g}"
                lines.append(f"| {s:g} | {kc:.0e} | {b + 1} | {v['grows']} | {first} | {v['ratio'][0]:.2f}–"
                             f"{v['ratio'][1]:.2f} | {v['amp_2x_um'][0]:.1f}–{v['amp_2x_um'][1]:.1f} | "
                             f"{v['aligned_2x_um']:.1f} |")
    lines += ["", "| r/min | k_c (N/m) | ψ (°) | Δ | 1X b2, b3 (µm 0-pk, x) | 2X b2, b3 (µm 0-pk, x) | 2X/1X b2, b3 |",
              "|" + "---|" * 7]
    for p in points:
        if p.status != "ok":
            lines.append(f"| {p.speed_rpm:g} | {p.coupling_stiffness_n_m:.0e} | {p.coupling_phase_deg:g} | "
                         f"{p.misalignment:g} | {p.status} | | |")
            continue
        kc_text = "—" if p.case == "aligned" else f"{p.coupling_stiffness_n_m:.0e}"
        lines.append(f"| {p.speed_rpm:g} | {kc_text} | {p.coupling_phase_deg:g} | {p.misalignment:g} | "
                     f"{p.amp_1x_um_0pk[1][0]:.1f}, {p.amp_1x_um_0pk[2][0]:.1f} | "
                     f"{p.amp_2x_um_0pk[1][0]:.2f}, {p.amp_2x_um_0pk[2][0]:.2f} | {p.ratio(1):.2f}, {p.ratio(2):.2f} |")
    return "\n".join(lines) + "\n"


def range_figure(points: list[SurveyPoint], path: str | Path, exciter_unbalance: float = 0.0) -> None:
    """PNG: 2X/1X (x) at bearings 2 and 3 versus Δ, one panel per speed and bearing, a line per k_c with
    the spread over ψ shaded (min–max) and ψ = 0 drawn; ``exciter_unbalance`` (a2/c) goes in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    speeds = sorted({p.speed_rpm for p in points})
    kcs = sorted({p.coupling_stiffness_n_m for p in points if p.case == "flexible-range"})
    fig, axes = plt.subplots(2, len(speeds), figsize=(4.6 * len(speeds), 8), squeeze=False)
    for j, s in enumerate(speeds):
        ref = [p for p in points if p.case == "aligned" and p.speed_rpm == s and p.status == "ok"]
        for row, b in ((0, 1), (1, 2)):
            ax = axes[row, j]
            for i, kc in enumerate(kcs):
                pts = [p for p in points if p.case == "flexible-range" and p.speed_rpm == s
                       and p.coupling_stiffness_n_m == kc and p.status == "ok"]
                ds = sorted({p.misalignment for p in pts})
                lo = [min(p.ratio(b) for p in pts if p.misalignment == d) for d in ds]
                hi = [max(p.ratio(b) for p in pts if p.misalignment == d) for d in ds]
                x0 = [0.0] if ref else []
                r0 = [ref[0].ratio(b)] if ref else []
                ax.fill_between(x0 + ds, r0 + lo, r0 + hi, color=f"C{i}", alpha=0.18)
                z = sorted((p for p in pts if p.coupling_phase_deg == 0.0), key=lambda p: p.misalignment)
                ax.plot(x0 + [p.misalignment for p in z], r0 + [p.ratio(b) for p in z], "o-", ms=3, color=f"C{i}",
                        label=f"k_c = {kc:.0e} N/m (ψ = 0; band: all ψ)")
            ax.set_yscale("log")
            ax.axhline(1.0, color="k", lw=0.6, ls="--")
            ax.set_xlabel("Δ = δ/c (horizontal offset)")
            ax.set_ylabel("2X/1X (x probe)")
            ax.set_title(f"{s:g} r/min, bearing {b + 1} ({'generator' if b == 1 else 'exciter'}, coupling end)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("flexible: 2X/1X vs Δ across the coupling stiffness k_c and phase ψ (default plant, A = 0.05, "
                 f"exciter unbalance a2/c = {exciter_unbalance:g})")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


#: The angular-offset survey (docs/reproduction.md "Angular offset"): α in mrad (the default plant allows
#: |α| ≤ 0.0926 mrad: bearing 4 moves by α·3.4 m ≤ 0.9 c), downward and horizontal, alone and with Δ = 0.2.
ANGULAR_MRAD: tuple[float, ...] = (0.03, 0.06, 0.09)
ANGULAR_CASES: dict[str, tuple[float, float]] = {  # label -> (offset_angle_rad, Δ)
    "angular-down": (-0.5 * math.pi, 0.0),
    "angular-horiz": (0.0, 0.0),
    "parallel+angular-down": (-0.5 * math.pi, 0.2),
}


def angular_survey(plant: Any = None, *, speeds_rpm: tuple[float, ...] = SPEEDS_RPM,
                   alphas_mrad: tuple[float, ...] = ANGULAR_MRAD, unbalance: float = 0.05, record_revs: int = 32,
                   workers: int | None = None) -> list[SurveyPoint]:
    """``offset`` with an angular offset (exciter line tilted about the coupling) per speed: the aligned
    run, the parallel Δ = 0.2 downward run, and each :data:`ANGULAR_CASES` × α."""
    from rotordiag.simulator import Plant

    plant = Plant.default() if plant is None else plant
    pd = plant.to_dict()
    kc = plant.coupling_stiffness_n_m
    tasks: list[tuple] = []
    for s in speeds_rpm:
        tasks.append(("aligned", "offset", 0.0, s, 0.0, 0.0, kc, pd, unbalance, record_revs, 0.0))
        tasks.append(("parallel-down", "offset", -0.5 * math.pi, s, 0.2, 0.0, kc, pd, unbalance, record_revs, 0.0))
        for case, (angle, delta) in ANGULAR_CASES.items():
            tasks += [(case, "offset", angle, s, delta, 0.0, kc, pd, unbalance, record_revs, a) for a in alphas_mrad]
    n = len(os.sched_getaffinity(0)) if workers is None else int(workers)
    if n <= 0:
        return [_run(t) for t in tasks]
    with ProcessPoolExecutor(max_workers=n) as pool:
        return list(pool.map(_run, tasks))


def angular_markdown(points: list[SurveyPoint]) -> str:
    """Table of :func:`angular_survey` (x probe amplitudes, 0-pk; static values from the mean film force)."""
    lines = ["| case | r/min | Δ | α (mrad) | 1X b3, b4 (µm 0-pk, x) | 2X b3, b4 (µm 0-pk, x) | 2X/1X b3 | "
             "ε b1..b4 | attitude b3, b4 (°) | load b1..b4 (kN, y) |", "|" + "---|" * 10]
    for p in points:
        if p.status != "ok":
            lines.append(f"| {p.case} | {p.speed_rpm:g} | {p.misalignment:g} | {p.angular_misalignment_mrad:g} | "
                         f"{p.status} | | | | | |")
            continue
        ecc = " / ".join(f"{e:.2f}" for e in p.static_eccentricity)
        load = " / ".join(f"{w[1] / 1e3:.1f}" for w in p.static_load_n)
        lines.append(f"| {p.case} | {p.speed_rpm:g} | {p.misalignment:g} | {p.angular_misalignment_mrad:g} | "
                     f"{p.amp_1x_um_0pk[2][0]:.1f}, {p.amp_1x_um_0pk[3][0]:.1f} | "
                     f"{p.amp_2x_um_0pk[2][0]:.2f}, {p.amp_2x_um_0pk[3][0]:.2f} | {p.ratio(2):.2f} | {ecc} | "
                     f"{p.attitude_angle_deg[2]:.0f}, {p.attitude_angle_deg[3]:.0f} | {load} |")
    return "\n".join(lines) + "\n"
