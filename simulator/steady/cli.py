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
    ) -> None:
        """Follow periodic orbits (shooting + pseudo-arclength) and mark folds, period doublings and tori."""
        import numpy as np

        from rotordiag.simulator.cli import load_plant

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
