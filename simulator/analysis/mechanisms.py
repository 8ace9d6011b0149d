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

    def ratio(self, bearing: int, direction: int = 0) -> float:
        a1 = self.amp_1x_um_0pk[bearing][direction]
        return self.amp_2x_um_0pk[bearing][direction] / a1 if a1 > 0 else float("nan")


def _run(task: tuple) -> SurveyPoint:
    from rotordiag.simulator import Plant, simulate
    from rotordiag.simulator.simulate import order_amplitudes

    case, mech, angle, speed, delta, psi_deg, kc, plant_dict, unbalance, revs = task
    plant = Plant.from_dict(plant_dict).replace(coupling_stiffness_n_m=kc)
    res = simulate(plant, speed, delta, unbalance, mechanism=mech if delta > 0 else "aligned",
                   offset_angle_rad=angle, coupling_phase_rad=math.radians(psi_deg),
                   transient_revs=400, record_revs=revs, samples_per_rev=64, settle_tol=1e-8)
    if res.status != "ok":
        return SurveyPoint(case, mech, speed, delta, psi_deg, kc, res.status, wall_time_s=res.wall_time_s)
    amps = order_amplitudes(res, (1, 2)) * 1e6
    return SurveyPoint(
        case, mech, speed, delta, psi_deg, kc, res.status,
        amp_1x_um_0pk=amps[:, :, 0].tolist(), amp_2x_um_0pk=amps[:, :, 1].tolist(),
        static_eccentricity=res.static_eccentricity.tolist(), attitude_angle_deg=res.attitude_angle_deg.tolist(),
        static_load_n=res.mean_bearing_load_n.tolist(), wall_time_s=res.wall_time_s,
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
