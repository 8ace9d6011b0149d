"""CLI command ``rotordiag continue``: periodic-orbit branches in speed or Δ (issue 16)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer

MECHANISM_HELP = "Coupling model: pin, rigid, aligned, offset or flexible (docs/model.md)."


def register(app: typer.Typer) -> None:
    """Add ``continue`` to the ``rotordiag`` app."""

    @app.command(name="continue")
    def continue_(
        over: str = typer.Option(..., help="Continuation parameter: speed or misalignment."),
        from_: float = typer.Option(..., "--from", help="Start (r/min, or Δ): the orbit is found here by shooting."),
        to: float = typer.Option(..., help="End (r/min, or Δ); may be below --from (a down-sweep)."),
        misalignment: Optional[float] = typer.Option(None, help="Δ = δ/c for --over speed (0–0.9)."),
        speed_rpm: Optional[float] = typer.Option(None, help="Running speed, r/min, for --over misalignment."),
        unbalance: float = typer.Option(0.05, help="Generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        max_points: int = typer.Option(150, help="Most points per branch."),
        ds: float = typer.Option(0.02, help="First arclength step (state in clearances, speed in 1000 r/min)."),
        ds_max: float = typer.Option(0.05, help="Largest arclength step."),
        switch: bool = typer.Option(True, help="Switch onto period-doubled branches at located PD points."),
        period: Optional[int] = typer.Option(None, min=1, max=16, help="Period n of the orbit to follow (1–16); "
                                             "default: what the start shows."),
        lo: Optional[float] = typer.Option(None, help="Lower bound of the continuation (default: min(--from, --to))."),
        hi: Optional[float] = typer.Option(None, help="Upper bound of the continuation (default: max(--from, --to))."),
        start_revs: int = typer.Option(0, min=0, help="Start from a brute-force point: integrate this many "
                                       "revolutions at --from, then shoot for the period its record shows "
                                       "(how a period-n window's orbit is reached); 0: a 40-revolution warm-up."),
        brute_points: int = typer.Option(15, help="Brute-force sweep points overlaid on the diagram (0: none)."),
        node: int = typer.Option(3, help="Node of the diagram (1–6)."),
        out: Path = typer.Option(..., help="Branches (HDF5)."),
        plot: Optional[Path] = typer.Option(None, help="Bifurcation diagram (PNG)."),
        workers: Optional[int] = typer.Option(0, help="Workers of the brute-force sweep (0: this process)."),
        train: Optional[str] = typer.Option(None, help="A preset shaft train (gen50_2pole, gen200_2pole, gen600_2pole, "
                                                       "gen600_4pole) instead of the paper model: --over speed; "
                                                       "--out a JSON file."),
        shaftline: Optional[Path] = typer.Option(None, help="A shaft-line TOML built as a finite-element train "
                                                           "(as --train)."),
    ) -> None:
        """Follow periodic orbits (shooting + pseudo-arclength) and mark folds, period doublings and tori."""
        import numpy as np

        from rotordiag.simulator.cli import load_plant

        if train is not None or shaftline is not None:
            _train_continue(train, shaftline, over, from_, to, max_points, ds, ds_max, lo, hi, out, plot)
            return

        if over not in ("speed", "misalignment"):
            raise typer.BadParameter("must be 'speed' or 'misalignment'", param_hint="--over")
        for path, hint in ((plot, "--plot"), (out, "--out")):
            if path is not None and not path.parent.exists():
                raise typer.BadParameter(f"directory {path.parent} does not exist", param_hint=hint)
        if from_ == to:
            raise typer.BadParameter("--from and --to must differ", param_hint="--to")
        if not 1 <= node <= 6:
            raise typer.BadParameter("must be 1..6", param_hint="--node")
        if over == "speed" and misalignment is None:
            raise typer.BadParameter("--over speed needs --misalignment", param_hint="--misalignment")
        if over == "misalignment" and speed_rpm is None:
            raise typer.BadParameter("--over misalignment needs --speed-rpm", param_hint="--speed-rpm")
        bounds = None
        if lo is not None or hi is not None:
            bounds = (min(from_, to) if lo is None else lo, max(from_, to) if hi is None else hi)
            if not bounds[0] <= from_ <= bounds[1]:
                raise typer.BadParameter(f"--from {from_:g} must lie in [--lo, --hi] = [{bounds[0]:g}, {bounds[1]:g}]",
                                         param_hint="--lo/--hi")
        pl = load_plant(plant)
        from rotordiag.simulator.steady.report import bifurcation_figure, read_branches, write_branches
        from rotordiag.simulator.steady.rotor import RotorFamily, rotor_branches

        parameter = "speed_rpm" if over == "speed" else "misalignment"
        try:
            fam = RotorFamily(pl, parameter, speed_rpm if speed_rpm is not None else from_,
                              misalignment if misalignment is not None else from_, unbalance, mechanism=mechanism)
            branches = rotor_branches(fam, from_, to, max_points=max_points, ds=ds, ds_max=ds_max, switch=switch,
                                      period=period, start_revs=start_revs, bounds=bounds)
        except ValueError as exc:
            typer.secho(f"error: {exc}", fg=typer.colors.RED, err=True)
            raise typer.Exit(code=2) from None
        brute = None
        if brute_points > 0:
            from rotordiag.simulator.analysis.sweeps import misalignment_sweep, speed_sweep

            b_lo, b_hi = bounds if bounds is not None else sorted((from_, to))
            values = np.linspace(max(b_lo, fam.floor), b_hi, brute_points)
            kw: dict[str, Any] = dict(mechanism=mechanism, node=node, record_revs=32, n_workers=workers,
                                      progress=False)
            if parameter == "speed_rpm":
                brute = speed_sweep(pl, values, fam.misalignment, unbalance, **kw)
            else:
                brute = misalignment_sweep(pl, fam.speed_rpm, values, unbalance, **kw)
        write_branches(out, fam, branches, node=node, brute=brute)
        for br in branches:
            events = ", ".join(f"{b.label} at {b.parameter:.6g}{'' if b.located else ' (bracketed)'}"
                               for b in br.bifurcations) or "none"
            typer.echo(f"period-{br.n_periods} branch: {len(br.points)} points, "
                       f"{br.values.min():.6g}–{br.values.max():.6g}; bifurcations: {events}; {br.message}")
        if plot is not None:
            bifurcation_figure(plot, read_branches(out))
            typer.echo(f"wrote {out} and {plot}")
        else:
            typer.echo(f"wrote {out}")


def _fail(message: str) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)


def _train_continue(preset: Optional[str], shaftline: Optional[Path], over: str, from_: float, to: float,
                    max_points: int, ds: float, ds_max: float, lo: Optional[float], hi: Optional[float], out: Path,
                    plot: Optional[Path]) -> None:
    """``continue --train/--shaftline``: the train's period-1 orbit at --from by shooting (its Floquet
    multipliers printed), then its branch over speed to --to with the bifurcations found on it."""
    import json
    import math

    import numpy as np

    from rotordiag.simulator.steady.continuation import continue_branch
    from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline
    from rotordiag.simulator.train.shooting import TrainSpeedFamily, train_fixed_point

    if over != "speed":
        raise typer.BadParameter("a train is continued over speed only (misalignment: move its bearings and "
                                 "run again)", param_hint="--over")
    if out.suffix.lower() != ".json":
        raise typer.BadParameter("a train's branch is written as JSON: give --out FILE.json", param_hint="--out")
    for path, hint in ((plot, "--plot"), (out, "--out")):
        if path is not None and not path.parent.exists():
            raise typer.BadParameter(f"directory {path.parent} does not exist", param_hint=hint)
    if not (math.isfinite(from_) and math.isfinite(to) and from_ > 0 and to > 0 and from_ != to):
        raise typer.BadParameter("--from and --to must be positive speeds that differ", param_hint="--to")
    p_lo = min(from_, to) if lo is None else lo
    p_hi = max(from_, to) if hi is None else hi
    try:
        line, _ = shaftline_of(preset, shaftline)
        fam = TrainSpeedFamily(train_from_shaftline(line))
        fp = train_fixed_point(fam.at(from_).kernel, from_)
        if not fp.converged:
            _fail(f"no period-1 orbit found by shooting at {from_:g} r/min ({fp.status}, residual "
                  f"{fp.residual:.2e}): the train may whirl there; start below its stability threshold "
                  "(rotordiag campbell gives the margin)")
        br = continue_branch(fam, fp.x, from_, p_min=p_lo, p_max=p_hi, direction=1 if to > from_ else -1, ds=ds,
                             ds_max=ds_max, tol=1e-10, max_points=max_points)
    except ValueError as exc:
        _fail(str(exc))
    period_s = 60.0 / from_
    mu = fp.multipliers
    typer.echo(f"period-1 orbit at {from_:g} r/min: {fp.stability}, residual {fp.residual:.1e}; Floquet multipliers "
               "(largest first; |μ| < 1 stable):")
    for m in mu[:6]:
        typer.echo(f"  |μ| = {abs(m):.5f}  arg = {math.degrees(math.atan2(m.imag, m.real)):+8.2f}°  "
                   f"(decay rate {math.log(max(abs(m), 1e-300)) / period_s:+.3f} 1/s)")
    events = ", ".join(f"{b.label} at {b.parameter:.6g} r/min{'' if b.located else ' (bracketed)'}"
                       for b in br.bifurcations) or "none"
    typer.echo(f"period-1 branch: {len(br.points)} points, {br.values.min():.6g}–{br.values.max():.6g} r/min; "
               f"bifurcations: {events}; {br.message}")
    typer.echo(f"{'speed (r/min)':>13} {'max |μ|':>9}  stability")
    for p in br.points:
        typer.echo(f"{p.parameter:13.1f} {float(np.abs(p.multipliers).max()):9.5f}  {p.stability}")

    def cplx(v) -> list[list[float]]:
        return [[float(z.real), float(z.imag)] for z in v]

    data = {"source": preset or str(shaftline), "parameter": "speed_rpm",
            "start": {"speed_rpm": from_, "stability": fp.stability, "residual": float(fp.residual),
                      "multipliers": cplx(mu)},
            "points": [{"speed_rpm": float(p.parameter), "stability": p.stability,
                        "max_multiplier": float(np.abs(p.multipliers).max()), "multipliers": cplx(p.multipliers)}
                       for p in br.points],
            "bifurcations": [{"kind": b.kind, "label": b.label, "speed_rpm": float(b.parameter), "located": b.located,
                              "multipliers": cplx(b.multipliers)} for b in br.bifurcations],
            "message": br.message}
    out.write_text(json.dumps(data, indent=1))
    if plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4))
        ax.plot(br.values, br.max_multiplier, "o-", c="black", ms=3, label="period-1 orbit")
        ax.axhline(1.0, c="0.5", lw=0.8)
        for b in br.bifurcations:
            ax.axvline(b.parameter, c="C3", ls="--", lw=1)
            ax.text(b.parameter, ax.get_ylim()[1], f" {b.label}", color="C3", va="top", fontsize=8, rotation=90)
        ax.set_xlabel("speed (r/min)")
        ax.set_ylabel("largest Floquet multiplier |μ|")
        ax.set_title(f"{data['source']}: period-1 branch (> 1: unstable)", fontsize=9)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(plot, dpi=110)
        plt.close(fig)
        typer.echo(f"wrote {out} and {plot}")
    else:
        typer.echo(f"wrote {out}")
