"""CLI commands of the nonlinear-analysis package: ``bifurcate``, ``lyapunov``, ``figures``."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Optional

import typer

MECHANISM_HELP = ("Coupling model: pin (the paper's holonomic constraint), rigid (rotating coupling eccentricity), "
                  "offset (stationary shaft-line offset), flexible (offset across a flexible coupling, 2X reaction).")
TRAIN_HELP = "A preset shaft train: gen50_2pole, gen200_2pole, gen600_2pole, gen600_4pole (the finite-element train)."
SHAFTLINE_HELP = "A shaft-line TOML file (examples/shaftline_200mw.toml) built as a finite-element train."
UNBALANCE_HELP = ("Train: generator unbalance, kg·m, at its heaviest body mass, in place of the train's own (a preset's: "
                  "ISO 21940-11 G2.5 at its middle); default: its own.")
WORKERS_HELP = "Local Dask worker processes (default: all usable CPUs; 0 = run in this process, no Dask)."
SCHEDULER_HELP = "Address of an existing Dask scheduler, e.g. tcp://host:8786 (instead of a local cluster)."


def _fail(message: str) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)


def _pyplot() -> Any:
    """matplotlib's pyplot on the file-only Agg backend, imported when a command draws (the CLI starts fast)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _write_png(fig: Any, path: Path) -> None:
    """Lay ``fig`` out, write it to ``path`` (110 dpi), close it and say where on stderr."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    typer.echo(f"wrote {path}", err=True)


def _run_opts(workers: Optional[int], scheduler: Optional[str]) -> dict:
    if workers is not None and scheduler is not None:
        raise typer.BadParameter("give either --workers or --scheduler, not both", param_hint="--workers")
    if workers is not None and workers < 0:
        raise typer.BadParameter("must be >= 0", param_hint="--workers")
    return dict(n_workers=workers, scheduler_address=scheduler)


def register(app: typer.Typer) -> None:
    """Add ``bifurcate``, ``lyapunov`` and ``figures`` to the ``rotordiag`` app."""

    @app.command()
    def bifurcate(
        over: str = typer.Option(..., help="Swept parameter: speed or misalignment."),
        from_: float = typer.Option(..., "--from", help="Start of the sweep (r/min, or Δ)."),
        to: float = typer.Option(..., help="End of the sweep (r/min, or Δ)."),
        points: int = typer.Option(50, help="Number of sweep points (≥ 2)."),
        misalignment: Optional[float] = typer.Option(None, help="Δ = δ/c for --over speed (0–0.9)."),
        speed_rpm: Optional[float] = typer.Option(None, help="Running speed, r/min, for --over misalignment."),
        unbalance: float = typer.Option(0.05, help="Generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        node: int = typer.Option(3, help="Node of the diagram (1–6; 3 = generator journal at the coupling)."),
        direction: str = typer.Option("x", help="x (horizontal, the paper's) or y (vertical)."),
        transient_revs: int = typer.Option(400, help="Revolutions discarded at each point."),
        record_revs: int = typer.Option(128, help="Revolutions recorded (Poincaré points per parameter value)."),
        lle_revs: int = typer.Option(0, help="Revolutions of the Lyapunov exponent at each point (0: none)."),
        steady_start: str = typer.Option(
            "shooting", help="shooting: start a point's record on its stable period-1 orbit where the transient "
                             "approaches one (else the rest of the transient); integrate: always the whole transient."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        plot: Optional[Path] = typer.Option(None, help="Write the bifurcation diagram (PNG)."),
        out: Optional[Path] = typer.Option(None, help="Write the sweep data (HDF5)."),
        workers: Optional[int] = typer.Option(None, help=WORKERS_HELP),
        scheduler: Optional[str] = typer.Option(None, help=SCHEDULER_HELP),
        progress: bool = typer.Option(True, help="Show a progress bar."),
        train: Optional[str] = typer.Option(None, help=TRAIN_HELP + " --over speed; --out a JSON file."),
        shaftline: Optional[Path] = typer.Option(None, help=SHAFTLINE_HELP),
        unbalance_kg_m: Optional[float] = typer.Option(None, help=UNBALANCE_HELP),
    ) -> None:
        """Bifurcation diagram: Poincaré points of X = x/c against speed or misalignment; for a shaft train
        (--train/--shaftline) the amplitude–speed curves (1X, 2X at each bearing) and Poincaré points."""
        import numpy as np

        from rotordiag.simulator.cli import load_plant

        if train is not None or shaftline is not None:
            _train_bifurcate(train, shaftline, over, from_, to, points, unbalance_kg_m, transient_revs, record_revs,
                             out, plot)
            return

        if over not in ("speed", "misalignment"):
            raise typer.BadParameter("must be 'speed' or 'misalignment'", param_hint="--over")
        if points < 2:
            raise typer.BadParameter("need at least 2 points", param_hint="--points")
        if to <= from_:
            raise typer.BadParameter(f"--to ({to:g}) must be greater than --from ({from_:g})", param_hint="--to")
        for path, hint in ((plot, "--plot"), (out, "--out")):
            if path is not None and not path.parent.exists():
                raise typer.BadParameter(f"directory {path.parent} does not exist", param_hint=hint)
        opts = _run_opts(workers, scheduler)
        pl = load_plant(plant)
        values = np.linspace(from_, to, points)
        kw = dict(mechanism=mechanism, node=node, direction=direction, transient_revs=transient_revs,
                  record_revs=record_revs, lle_revs=lle_revs, steady_start=steady_start, progress=progress, **opts)
        from rotordiag.simulator.analysis.sweeps import misalignment_sweep, speed_sweep

        try:
            if over == "speed":
                if misalignment is None:
                    raise typer.BadParameter("--over speed needs --misalignment", param_hint="--misalignment")
                sweep = speed_sweep(pl, values, misalignment, unbalance, **kw)
            else:
                if speed_rpm is None:
                    raise typer.BadParameter("--over misalignment needs --speed-rpm", param_hint="--speed-rpm")
                sweep = misalignment_sweep(pl, speed_rpm, values, unbalance, **kw)
        except ValueError as exc:
            _fail(str(exc))
        except OSError as exc:
            _fail(f"could not reach the Dask scheduler: {exc}")
        from rotordiag.simulator.analysis.figures import motion_windows

        for w in motion_windows(sweep):
            lle = "" if w["lle_min"] is None else f"  LLE {w['lle_min']:+.4f} .. {w['lle_max']:+.4f} /rev"
            typer.echo(f"{w['from']:>10.4g} – {w['to']:<10.4g} {w['motion']:<16} ({w['n_points']} points){lle}")
        if out is not None:
            sweep.to_hdf5(out)
            typer.echo(f"wrote {out}", err=True)
        if plot is not None:
            plt = _pyplot()

            from rotordiag.simulator.analysis.figures import plot_bifurcation, plot_lle

            rows = 2 if lle_revs > 0 else 1
            fig, axes = plt.subplots(rows, 1, figsize=(8, 4 * rows), squeeze=False, sharex=True)
            plot_bifurcation(axes[0, 0], sweep, size=2)
            fixed = f"Δ = {misalignment:g}" if over == "speed" else f"{speed_rpm:g} r/min"
            axes[0, 0].set_title(f"{fixed}, A = {unbalance:g}, {mechanism}", fontsize=9)
            if rows == 2:
                plot_lle(axes[1, 0], sweep)
            _write_png(fig, plot)

    @app.command()
    def campbell(
        train: Optional[str] = typer.Option(None, help=TRAIN_HELP),
        shaftline: Optional[Path] = typer.Option(None, help=SHAFTLINE_HELP),
        plant: Optional[Path] = typer.Option(None, help="Paper-model plant file (TOML or JSON) instead of a train; "
                                                        "neither: MODEL.md's plant."),
        from_: float = typer.Option(300.0, "--from", help="Lowest speed, r/min."),
        to: Optional[float] = typer.Option(None, help="Highest speed, r/min (default: 1.3 × rated, or 4000)."),
        points: int = typer.Option(24, help="Number of speeds (2–200; a static solution and an eigenproblem each)."),
        n_modes: int = typer.Option(8, "--modes", help="Modes per speed, lowest first (train: 1–40)."),
        speed_rpm: Optional[float] = typer.Option(
            None, help="Speed of the stability margin (default: the preset's rated speed, else the top speed)."),
        plot: Optional[Path] = typer.Option(None, help="Write the Campbell diagram (PNG)."),
        as_json: bool = typer.Option(False, "--json", help="Print the table as JSON."),
    ) -> None:
        """Campbell diagram of a shaft train (--train/--shaftline) or the paper model (--plant): damped modes
        against speed, the 1X/2X critical speeds with their half-power widths, and the stability margin
        (log decrement of the least-damped mode)."""
        import math

        import numpy as np

        if points < 2 or points > 200:
            raise typer.BadParameter("give 2 to 200 points", param_hint="--points")
        if plot is not None and not plot.parent.exists():
            raise typer.BadParameter(f"directory {plot.parent} does not exist", param_hint="--plot")
        rated = None
        log_decrements = None
        try:
            if train is not None or shaftline is not None:
                if plant is not None:
                    raise typer.BadParameter("give a train (--train/--shaftline) or --plant, not both",
                                             param_hint="--plant")
                from rotordiag.simulator.train.campbell import train_campbell
                from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline
                from rotordiag.simulator.train.stability import stability

                line, rated = shaftline_of(train, shaftline)
                tr = train_from_shaftline(line)
                top = to if to is not None else (1.3 * rated if rated else 4000.0)
                if not (math.isfinite(top) and top > from_ > 0):
                    raise typer.BadParameter(f"need 0 < --from < --to (got {from_:g}, {top:g})", param_hint="--to")
                tc = train_campbell(tr, np.linspace(from_, top, points), n_modes)
                data, log_decrements = tc.data, tc.log_decrements
                crit = tc.critical_speeds((1, 2))
                at = speed_rpm if speed_rpm is not None else (rated if rated else top)
                marg = stability(tr, at)
                margin: dict[str, Any] = dict(speed_rpm=at, log_decrement=marg.log_decrement, frequency_hz=marg.frequency_hz,
                              forward=marg.forward, stable=marg.stable)
                what = train if train is not None else str(shaftline)
            else:
                from rotordiag.simulator import modal as run_modal
                from rotordiag.simulator.campbell import campbell as paper_campbell
                from rotordiag.simulator.campbell import critical_speeds
                from rotordiag.simulator.cli import load_plant

                pl = load_plant(plant)
                top = to if to is not None else 4000.0
                data = paper_campbell(pl, np.linspace(from_, top, points))
                crit = critical_speeds(data, (1, 2))
                at = speed_rpm if speed_rpm is not None else top
                res = run_modal(pl, at)
                i = int(np.argmin(res.damping_ratios))
                z = float(res.damping_ratios[i])
                margin = dict(speed_rpm=at, log_decrement=2 * math.pi * z / math.sqrt(max(1 - z * z, 1e-12)),
                              frequency_hz=float(res.frequencies_hz[i]), forward=None, stable=bool(res.stable))
                what = str(plant) if plant is not None else "MODEL.md plant"
        except ValueError as exc:
            _fail(str(exc))
        rows = [dict(order=c.order, speed_rpm=c.speed_rpm, frequency_hz=c.frequency_hz, damping_ratio=c.damping_ratio,
                     amplification_factor=c.amplification_factor, half_power_width_rpm=c.half_power_width_rpm)
                for c in crit]
        if as_json:
            out = dict(source=what, speeds_rpm=data.speeds_rpm.tolist(),
                       frequencies_hz=[[None if not np.isfinite(v) else float(v) for v in r] for r in data.frequencies_hz],
                       damping_ratios=[[None if not np.isfinite(v) else float(v) for v in r] for r in data.damping_ratios],
                       critical_speeds=rows, stability_margin=margin)
            if log_decrements is not None:
                out["log_decrements"] = [[None if not np.isfinite(v) else float(v) for v in r] for r in log_decrements]
            typer.echo(json.dumps(out, indent=1))
        else:
            typer.echo(f"{what}: {points} speeds {from_:g}–{data.speeds_rpm[-1]:g} r/min")
            typer.echo(f"{'order':>5} {'speed (r/min)':>13} {'f (Hz)':>8} {'ζ':>6} {'AF':>5} {'half-power width (r/min)':>25}")
            for r in rows:
                typer.echo(f"{r['order']:>4}X {r['speed_rpm']:13.0f} {r['frequency_hz']:8.2f} {r['damping_ratio']:6.3f} "
                           f"{r['amplification_factor']:5.1f} {r['half_power_width_rpm']:25.0f}")
            if not rows:
                typer.echo("  no critical speed with AF ≥ 2.5 in this range")
            state = "stable" if margin["stable"] else "UNSTABLE (beyond the stability threshold)"
            typer.echo(f"stability margin at {margin['speed_rpm']:g} r/min: log decrement {margin['log_decrement']:.3f} "
                       f"of the least-damped mode ({margin['frequency_hz']:.1f} Hz), {state}")
        if plot is not None:
            plt = _pyplot()

            from rotordiag.simulator.analysis.figures import plot_campbell

            fig, ax = plt.subplots(figsize=(8, 5.5))
            sc = plot_campbell(ax, data, crit, title=f"Campbell diagram: {what} (linearised about the static state); "
                                                    f"δ = {margin['log_decrement']:.3f} at {margin['speed_rpm']:g} r/min")
            if sc is not None:
                fig.colorbar(sc, ax=ax, label="damping ratio ζ (< 0: unstable)")
            _write_png(fig, plot)

    @app.command()
    def lyapunov(
        speed_rpm: float = typer.Option(..., help="Running speed, r/min (100–6000)."),
        misalignment: Optional[float] = typer.Option(None, help="Δ = δ/c (0–0.9); paper model only (required there)."),
        unbalance: float = typer.Option(0.05, help="Generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        revs: int = typer.Option(150, help="Revolutions averaged (Benettin, renormalised once per revolution)."),
        transient_revs: int = typer.Option(400, help="Revolutions discarded first."),
        separation: float = typer.Option(1e-6, help="Neighbour separation (non-dimensional state)."),
        seed: int = typer.Option(0, help="Seed of the initial perturbation direction."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON)."),
        plot: Optional[Path] = typer.Option(None, help="Write the convergence history (PNG)."),
        as_json: bool = typer.Option(False, "--json", help="Print the result as JSON."),
        train: Optional[str] = typer.Option(None, help=TRAIN_HELP),
        shaftline: Optional[Path] = typer.Option(None, help=SHAFTLINE_HELP),
        unbalance_kg_m: Optional[float] = typer.Option(None, help=UNBALANCE_HELP),
    ) -> None:
        """Largest Lyapunov exponent and motion type at one operating point (the paper model, or a shaft
        train with --train/--shaftline)."""
        import numpy as np
        from tqdm.auto import tqdm

        if train is not None or shaftline is not None:
            _train_lyapunov(train, shaftline, speed_rpm, unbalance_kg_m, revs, transient_revs, seed, plot, as_json)
            return
        if misalignment is None:
            raise typer.BadParameter("the paper model needs --misalignment", param_hint="--misalignment")

        from rotordiag.simulator import simulate
        from rotordiag.simulator.analysis import FlowMapError, classify_motion
        from rotordiag.simulator.analysis.sweeps import rotor_lyapunov
        from rotordiag.simulator.cli import load_plant

        if revs < 10:
            raise typer.BadParameter("need at least 10 revolutions", param_hint="--revs")
        if plot is not None and not plot.parent.exists():
            raise typer.BadParameter(f"directory {plot.parent} does not exist", param_hint="--plot")
        pl = load_plant(plant)
        try:
            res = simulate(pl, speed_rpm, misalignment, unbalance, mechanism=mechanism,
                           transient_revs=transient_revs, record_revs=max(64, 3 * 16))
            if res.status != "ok":
                _fail(f"the run did not reach a steady state: {res.message}")
            with tqdm(total=revs, desc="Lyapunov", unit="rev") as bar:
                lle = rotor_lyapunov(pl, speed_rpm, misalignment, unbalance, n_revs=revs, transient_revs=0,
                                     initial_state=res.final_state, mechanism=mechanism, separation=separation,
                                     seed=seed, progress=bar.update)
        except ValueError as exc:
            _fail(str(exc))
        except FlowMapError as exc:
            _fail(str(exc))
        c = pl.clearance_m
        orbit = float(np.max(np.ptp(res.positions_m / c, axis=0)))
        motion = classify_motion(res.poincare_m / c, lle, orbit_size=orbit)
        summary = dict(speed_rpm=speed_rpm, misalignment=misalignment, unbalance=unbalance, mechanism=mechanism,
                       lle_per_rev=lle.lle_per_interval, lle_per_s=lle.lle_per_s,
                       stderr_per_rev=lle.stderr_per_interval, revs=lle.n_intervals, motion=motion.label,
                       evidence=motion.evidence)
        _report_lle(lle, summary, f"{motion.label} ({motion.evidence})", as_json, plot,
                    f"{speed_rpm:g} r/min, Δ = {misalignment:g}, A = {unbalance:g}")

    @app.command()
    def mechanisms(
        out: Path = typer.Option(..., help="Directory for mechanisms.png, mechanisms.md and mechanisms.json."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        workers: Optional[int] = typer.Option(None, help="Worker processes (default: usable CPUs; 0 = here)."),
        quick: bool = typer.Option(False, "--quick", help="One speed (1950 r/min) and Δ = 0, 0.1, 0.3 only."),
        flexible_range: bool = typer.Option(
            False, "--flexible-range",
            help="Instead: flexible only, at the three speeds across k_c 1e7–1e9 N/m, ψ = 0/90/180/270° and "
                 "Δ ≤ 0.3 (flexible_range.png/.md/.json)."),
        exciter_unbalance: float = typer.Option(
            0.0, "--exciter-unbalance", min=0.0, max=0.5,
            help="With --flexible-range: exciter unbalance a2/c of every run (default 0)."),
        angular: bool = typer.Option(
            False, "--angular",
            help="Instead: the angular shaft-line offset (offset mechanism, α = 0.03/0.06/0.09 mrad, down and "
                 "horizontal, alone and with Δ = 0.2) at the three speeds (angular.md/.json)."),
    ) -> None:
        """Every coupling mechanism at 1500, 1950, 3000 r/min versus Δ: 1X, 2X, 2X/1X, static journal positions,
        and the flexible coupling's phase and stiffness sensitivity (docs/reproduction.md)."""
        from dataclasses import asdict

        from rotordiag.simulator.analysis.mechanisms import (
            angular_markdown,
            angular_survey,
            flexible_range_survey,
            mechanism_survey,
            range_figure,
            range_markdown,
            survey_figure,
            survey_markdown,
        )
        from rotordiag.simulator.cli import load_plant

        if workers is not None and workers < 0:
            raise typer.BadParameter("must be >= 0", param_hint="--workers")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise typer.BadParameter(f"cannot create {out}: {exc}", param_hint="--out") from None
        if angular:
            points = angular_survey(load_plant(plant), workers=workers)
            (out / "angular.json").write_text(json.dumps([asdict(p) for p in points], indent=1))
            (out / "angular.md").write_text(angular_markdown(points))
            typer.echo(f"{len(points)} runs; wrote {out / 'angular.md'}, angular.json")
            return
        if flexible_range:
            points = flexible_range_survey(load_plant(plant), workers=workers, exciter_unbalance=exciter_unbalance)
            (out / "flexible_range.json").write_text(json.dumps([asdict(p) for p in points], indent=1))
            (out / "flexible_range.md").write_text(range_markdown(points))
            range_figure(points, out / "flexible_range.png", exciter_unbalance=exciter_unbalance)
            typer.echo(f"{len(points)} runs; wrote {out / 'flexible_range.png'}, flexible_range.md, flexible_range.json")
            return
        if quick:
            points = mechanism_survey(load_plant(plant), workers=workers, speeds_rpm=(1950.0,), deltas=(0.0, 0.1, 0.3))
        else:
            points = mechanism_survey(load_plant(plant), workers=workers)
        (out / "mechanisms.json").write_text(json.dumps([asdict(p) for p in points], indent=1))
        (out / "mechanisms.md").write_text(survey_markdown(points))
        survey_figure(points, out / "mechanisms.png")
        typer.echo(f"{len(points)} runs; wrote {out / 'mechanisms.png'}, mechanisms.md, mechanisms.json")

    @app.command()
    def figures(
        out: Path = typer.Option(..., help="Directory for the PNGs, sweep data and summary.json."),
        quick: bool = typer.Option(False, "--quick", help="Coarse grids: a few minutes on 2 cores."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        workers: Optional[int] = typer.Option(None, help=WORKERS_HELP),
        scheduler: Optional[str] = typer.Option(None, help=SCHEDULER_HELP),
        train: Optional[str] = typer.Option(None, help=TRAIN_HELP + " Its figure set instead of the paper's."),
        shaftline: Optional[Path] = typer.Option(None, help=SHAFTLINE_HELP),
        unbalance_kg_m: Optional[float] = typer.Option(None, help=UNBALANCE_HELP),
        speed_rpm: Optional[float] = typer.Option(None, help="Train: speed of the orbits and spectra (default: the "
                                                             "preset's rated speed; required for a file)."),
    ) -> None:
        """Regenerate the paper's figure set (Figs 4–15) as PNGs; with --train/--shaftline the train's: orbits and
        spectra at the bearings, the centreline in the clearance circle and the amplitude–speed curves."""
        from dataclasses import replace

        if train is not None or shaftline is not None:
            import numpy as np

            from rotordiag.simulator.analysis.figures import train_figures

            tr, rated = _train_of(train, shaftline, unbalance_kg_m)
            at = speed_rpm if speed_rpm is not None else rated
            if at is None or not at > 0:
                raise typer.BadParameter("give --speed-rpm (a shaft-line file carries no rated speed)",
                                         param_hint="--speed-rpm")
            try:
                out.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise typer.BadParameter(f"cannot create {out}: {exc}", param_hint="--out") from None
            grid = np.linspace(0.2 * at, 1.1 * at, 8 if quick else 24)
            try:
                summary = train_figures(out, tr, name=train or str(shaftline), speed_rpm=at, speeds_rpm=grid,
                                        transient_revs=120 if quick else 320, record_revs=16 if quick else 32)
            except ValueError as exc:
                _fail(str(exc))
            typer.echo(f"wrote {len(summary['files'])} figures to {out} in {summary['wall_time_s']:.0f} s")
            return

        from rotordiag.simulator.analysis.figures import FULL, QUICK, paper_figures
        from rotordiag.simulator.cli import load_plant

        opts = _run_opts(workers, scheduler)
        if mechanism not in ("pin", "rigid", "offset", "flexible"):
            raise typer.BadParameter("must be 'pin', 'rigid', 'offset' or 'flexible'", param_hint="--mechanism")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise typer.BadParameter(f"cannot create {out}: {exc}", param_hint="--out") from None
        pl = load_plant(plant)
        settings = replace(QUICK if quick else FULL, mechanism=mechanism)
        if not quick:
            typer.echo("full resolution: 459 operating points, about 15-25 min on 2 cores (use --quick for a coarse set)", err=True)
        try:
            summary = paper_figures(out, settings, plant=pl, **opts)
        except ValueError as exc:
            _fail(str(exc))
        except OSError as exc:
            _fail(f"could not reach the Dask scheduler: {exc}")
        typer.echo(f"wrote {len(summary['files'])} figures to {out} in {summary['wall_time_s']:.0f} s")


def _train_of(preset: Optional[str], shaftline: Optional[Path], unbalance_kg_m: Optional[float]):
    """The finite-element train of a preset or a shaft-line file, with its own generator unbalance or, given one,
    ``unbalance_kg_m`` in its place."""
    from rotordiag.simulator.analysis.train import with_unbalance
    from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline

    try:
        line, rated = shaftline_of(preset, shaftline)
        tr = train_from_shaftline(line)
        return (tr if unbalance_kg_m is None else with_unbalance(tr, unbalance_kg_m, replace_own=True)), rated
    except ValueError as exc:
        _fail(str(exc))
        raise  # unreachable: _fail exits


def _unbalance_of(train: Any) -> float:
    """The train's unbalance in all (kg·m): what its 1X answers to."""
    return float(sum(u.amount_kg_m for r in train.rotors for u in r.unbalances))


def _train_lyapunov(preset, shaftline, speed_rpm: float, unbalance_kg_m: Optional[float], revs: int,
                    transient_revs: int,
                    seed: int, plot: Optional[Path], as_json: bool) -> None:
    from rotordiag.simulator.analysis.train import train_lyapunov

    if revs < 10:
        raise typer.BadParameter("need at least 10 revolutions", param_hint="--revs")
    if plot is not None and not plot.parent.exists():
        raise typer.BadParameter(f"directory {plot.parent} does not exist", param_hint="--plot")
    tr, _ = _train_of(preset, shaftline, unbalance_kg_m)
    unbalance_kg_m = _unbalance_of(tr)
    try:
        lle, _ = train_lyapunov(tr, speed_rpm, n_revs=revs, transient_revs=transient_revs, seed=seed)
    except ValueError as exc:
        _fail(str(exc))
    except RuntimeError as exc:  # FlowMapError
        _fail(str(exc))
    lo, hi = lle.lle_per_interval - 3 * lle.stderr_per_interval, lle.lle_per_interval + 3 * lle.stderr_per_interval
    motion = ("periodic (attracting: negative exponent)" if hi < 0 else
              "chaotic (positive exponent)" if lo > 0 else "near-zero exponent: quasi-periodic or whirl limit cycle")
    summary = dict(source=preset or str(shaftline), speed_rpm=speed_rpm, unbalance_kg_m=unbalance_kg_m,
                   lle_per_rev=lle.lle_per_interval, lle_per_s=lle.lle_per_s, stderr_per_rev=lle.stderr_per_interval,
                   revs=lle.n_intervals, motion=motion)
    _report_lle(lle, summary, motion, as_json, plot,
                f"{summary['source']}, {speed_rpm:g} r/min, unbalance {unbalance_kg_m:g} kg·m")


def _report_lle(lle: Any, summary: dict, motion: str, as_json: bool, plot: Optional[Path], title: str) -> None:
    """The ``lyapunov`` command's answer: the summary (JSON or two lines) and the running estimate's PNG."""
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
    else:
        typer.echo(f"LLE = {lle.lle_per_interval:+.5f} ± {lle.stderr_per_interval:.5f} per revolution "
                   f"= {lle.lle_per_s:+.4f} per second ({lle.n_intervals} revolutions)")
        typer.echo(f"motion: {motion}")
    if plot is not None:
        import numpy as np

        plt = _pyplot()

        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(np.arange(1, lle.n_intervals + 1), lle.history_per_interval, c="black")
        ax.axhline(0, c="0.5", lw=0.8)
        ax.set_xlabel("revolutions averaged")
        ax.set_ylabel("running LLE estimate (1/rev)")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        _write_png(fig, plot)


def _train_bifurcate(preset, shaftline, over: str, from_: float, to: float, points: int,
                     unbalance_kg_m: Optional[float],
                     transient_revs: int, record_revs: int, out: Optional[Path], plot: Optional[Path]) -> None:
    import numpy as np

    from rotordiag.simulator.analysis.train import half_power_band, train_speed_sweep

    if over != "speed":
        raise typer.BadParameter("a train is swept over speed only (misalignment: move its bearings)",
                                 param_hint="--over")
    if points < 2 or points > 200:
        raise typer.BadParameter("give 2 to 200 points", param_hint="--points")
    if not (0 < from_ < to):
        raise typer.BadParameter(f"need 0 < --from < --to (got {from_:g}, {to:g})", param_hint="--to")
    if out is not None and out.suffix.lower() != ".json":
        raise typer.BadParameter("a train's sweep is written as JSON: give --out FILE.json", param_hint="--out")
    for path, hint in ((plot, "--plot"), (out, "--out")):
        if path is not None and not path.parent.exists():
            raise typer.BadParameter(f"directory {path.parent} does not exist", param_hint=hint)
    tr, _ = _train_of(preset, shaftline, unbalance_kg_m)
    unbalance_kg_m = _unbalance_of(tr)
    try:
        sw = train_speed_sweep(tr, np.linspace(from_, to, points), transient_revs=transient_revs,
                               record_revs=max(record_revs, 2))
    except ValueError as exc:
        _fail(str(exc))
    names = sw.bearing_names
    typer.echo(f"{'speed (r/min)':>13}  " + "  ".join(f"{n + ' 1X':>8} {n + ' 2X':>8}" for n in names) + "  (µm pk-pk)")
    for i, s in enumerate(sw.speeds_rpm):
        cells = "  ".join(f"{sw.amp_1x_um_pp[i, b]:8.1f} {sw.amp_2x_um_pp[i, b]:8.1f}" for b in range(len(names)))
        flag = "" if sw.status[i] == "ok" else f"  {sw.status[i]}"
        typer.echo(f"{s:13.1f}  {cells}{flag}")
    bands = {}
    if unbalance_kg_m > 0 and np.isfinite(sw.amp_1x_um_pp).any():
        for b, n in enumerate(names):
            pk, lo, hi = half_power_band(sw.speeds_rpm, sw.amp_1x_um_pp[:, b])
            bands[n] = dict(peak_rpm=pk, half_power_lo_rpm=lo, half_power_hi_rpm=hi)
            typer.echo(f"{n}: 1X peak at {pk:.0f} r/min, half-power band {lo:.0f}–{hi:.0f} r/min")
    if out is not None:
        def rows(a):
            return [[None if not np.isfinite(v) else float(v) for v in r] for r in a]

        out.write_text(json.dumps(dict(source=preset or str(shaftline), unbalance_kg_m=unbalance_kg_m,
                                       speeds_rpm=sw.speeds_rpm.tolist(), bearings=names,
                                       amp_1x_um_pp=rows(sw.amp_1x_um_pp), amp_2x_um_pp=rows(sw.amp_2x_um_pp),
                                       half_power=bands, status=sw.status), indent=1))
        typer.echo(f"wrote {out}", err=True)
    if plot is not None:
        plt = _pyplot()

        from rotordiag.simulator.analysis.figures import plot_train_sweep

        fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        plot_train_sweep(axes, sw, title=f"{preset or shaftline}, unbalance {unbalance_kg_m:g} kg·m")
        _write_png(fig, plot)
