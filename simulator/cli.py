"""CLI commands of the simulator: ``rotordiag simulate`` and ``rotordiag modal``."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

MECHANISM_HELP = "Coupling model: pin (the paper's holonomic constraint), rigid (offset carried by the shaft) or aligned."


def load_plant(path: Optional[Path]):
    """Plant from a TOML/JSON file, or the MODEL.md default; errors become BadParameter."""
    from simulator import Plant

    if path is None:
        return Plant.default()
    try:
        return Plant.from_file(path)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--plant") from None


def _summary(res) -> dict:
    from simulator.simulate import order_amplitudes

    out = {"status": res.status, "message": res.message, "speed_rpm": res.speed_rpm,
           "misalignment": res.inputs["misalignment"], "unbalance": res.inputs["unbalance"],
           "mechanism": res.inputs["mechanism"], "wall_time_s": round(res.wall_time_s, 4),
           "steps_per_rev": round(res.n_accepted / max(1, res.inputs["transient_revs"] + res.inputs["record_revs"]), 1),
           "bearings": []}
    d = res.journal_displacements_m * 1e6
    try:
        amps = order_amplitudes(res) * 1e6
    except ValueError:
        amps = None
    for b in range(4):
        entry = {"bearing": b + 1}
        if len(d):
            entry["peak_to_peak_um"] = {k: float(d[:, b, i].max() - d[:, b, i].min()) for i, k in enumerate("xy")}
            entry["mean_eccentricity"] = float((abs(d[:, b, 0] + 1j * d[:, b, 1]) / (res.clearance_m * 1e6)).mean())
        if amps is not None:
            for i, k in enumerate("xy"):
                a1, a2, a3 = amps[b, i]
                entry[f"{k}_1x_um"], entry[f"{k}_2x_um"], entry[f"{k}_3x_um"] = float(a1), float(a2), float(a3)
                entry[f"{k}_2x_1x"] = float(a2 / a1) if a1 > 0 else float("nan")
        out["bearings"].append(entry)
    return out


def _write_h5(res, path: Path) -> None:
    import h5py

    from rotordiag import code_version

    with h5py.File(path, "w") as f:
        f.create_dataset("time_s", data=res.time_s)
        f.create_dataset("positions_m", data=res.positions_m, compression="gzip")
        f.create_dataset("phi_rad", data=res.phi_rad)
        f.create_dataset("poincare_m", data=res.poincare_m)
        f["positions_m"].attrs["axes"] = "sample, node 1..6, (x horizontal, y vertical up)"
        f.attrs["status"] = res.status
        f.attrs["message"] = res.message
        f.attrs["inputs_json"] = json.dumps(res.inputs)
        f.attrs["code_version"] = code_version()


def _plot(res, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    c_um = res.clearance_m * 1e6
    d = res.journal_displacements_m * 1e6
    pc = (res.poincare_m[:, [0, 2, 3, 5], :] - res.bearing_offset_m[None]) * 1e6
    fig, axes = plt.subplots(2, 4, figsize=(16, 8))
    for b in range(4):
        ax = axes[0, b]
        ax.plot(d[:, b, 0], d[:, b, 1], lw=0.6, color="C0", label="orbit")
        ax.plot(pc[:, b, 0], pc[:, b, 1], "o", ms=4, color="C3", label="Poincaré (1/rev)")
        if len(d):
            cx, cy = d[:, b].mean(axis=0)
            half = 0.6 * max(np.ptp(d[:, b, 0]), np.ptp(d[:, b, 1]), 1e-3 * c_um)
            if half > 0.3 * c_um:  # large orbit: show it inside the clearance circle
                t = np.linspace(0, 2 * np.pi, 200)
                ax.plot(c_um * np.cos(t), c_um * np.sin(t), "k--", lw=0.5, label="clearance")
            else:
                ax.set_xlim(cx - half, cx + half)
                ax.set_ylim(cy - half, cy + half)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"Bearing {b + 1} journal orbit")
        ax.set_xlabel("x horizontal (µm)")
        ax.set_ylabel("y vertical (µm)")
        if b == 0:
            ax.legend(fontsize=7, loc="upper right")
        ax2 = axes[1, b]
        n = len(d)
        if n > 8:
            dt = res.time_s[1] - res.time_s[0]
            f_order = np.fft.rfftfreq(n, dt) / (res.speed_rpm / 60.0)
            for i, k in enumerate("xy"):
                ax2.semilogy(f_order, np.abs(np.fft.rfft(d[:, b, i] - d[:, b, i].mean())) * 2 / n + 1e-6, lw=0.8, label=k)
        ax2.set_xlim(0, 5)
        ax2.set_xlabel("frequency / running speed (order, X)")
        ax2.set_ylabel("amplitude 0-pk (µm)")
        ax2.set_title(f"Bearing {b + 1} spectrum")
        ax2.legend(fontsize=7)
    inp = res.inputs
    fig.suptitle(f"{inp['mechanism']} Δ={inp['misalignment']:g} A={inp['unbalance']:g} "
                 f"{inp['speed_rpm']:g} r/min — status {res.status}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def register(app: typer.Typer) -> None:
    """Add ``simulate`` and ``modal`` to the ``rotordiag`` app."""

    @app.command()
    def simulate(
        speed_rpm: float = typer.Option(..., help="Running speed, r/min (100–6000)."),
        misalignment: float = typer.Option(..., help="Non-dimensional parallel misalignment Δ = δ/c (0–0.9)."),
        unbalance: float = typer.Option(0.05, help="Non-dimensional generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        transient_revs: int = typer.Option(400, help="Revolutions discarded before recording."),
        record_revs: int = typer.Option(128, help="Revolutions recorded."),
        samples_per_rev: int = typer.Option(128, help="Samples per revolution."),
        exciter_unbalance: float = typer.Option(0.0, help="Exciter unbalance a2/c (0–0.5)."),
        exciter_unbalance_phase_deg: float = typer.Option(0.0, help="Exciter unbalance phase θ2, degrees."),
        offset_angle_deg: float = typer.Option(0.0, help="rigid: offset direction φ0, degrees."),
        as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
        plot: Optional[Path] = typer.Option(None, help="Write a PNG: journal orbits with Poincaré points, spectra."),
        out: Optional[Path] = typer.Option(None, help="Write the time series to this HDF5 file."),
    ) -> None:
        """Simulate one operating point and summarise the journal vibration."""
        import math

        from simulator import simulate as run

        pl = load_plant(plant)
        try:
            res = run(pl, speed_rpm, misalignment, unbalance, mechanism=mechanism,
                      transient_revs=transient_revs, record_revs=record_revs, samples_per_rev=samples_per_rev,
                      exciter_unbalance=exciter_unbalance,
                      exciter_unbalance_phase_rad=math.radians(exciter_unbalance_phase_deg),
                      offset_angle_rad=math.radians(offset_angle_deg))
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        summary = _summary(res)
        if as_json:
            typer.echo(json.dumps(summary, indent=2))
        else:
            typer.echo(f"status: {res.status} ({res.message}); {summary['wall_time_s']} s, "
                       f"{summary['steps_per_rev']} steps/rev")
            typer.echo(f"{'bearing':>7} {'dir':>3} {'1X µm':>9} {'2X µm':>9} {'3X µm':>9} {'2X/1X':>7} {'pk-pk µm':>9}")
            for e in summary["bearings"]:
                for k in "xy":
                    if f"{k}_1x_um" in e:
                        typer.echo(f"{e['bearing']:>7} {k:>3} {e[f'{k}_1x_um']:9.2f} {e[f'{k}_2x_um']:9.2f} "
                                   f"{e[f'{k}_3x_um']:9.2f} {e[f'{k}_2x_1x']:7.3f} {e['peak_to_peak_um'][k]:9.2f}")
        if plot is not None:
            _plot(res, plot)
            typer.echo(f"wrote {plot}", err=True)
        if out is not None:
            _write_h5(res, out)
            typer.echo(f"wrote {out}", err=True)

    @app.command()
    def modal(
        speed_rpm: float = typer.Option(1950.0, help="Running speed, r/min."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON)."),
        as_json: bool = typer.Option(False, "--json", help="Print as JSON."),
    ) -> None:
        """Natural frequencies and damping of the rotor linearised about its static equilibrium."""
        from simulator import modal as run

        pl = load_plant(plant)
        try:
            res = run(pl, speed_rpm)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        if as_json:
            typer.echo(json.dumps({"speed_rpm": speed_rpm, "frequencies_hz": res.frequencies_hz.tolist(),
                                   "damping_ratios": res.damping_ratios.tolist(),
                                   "stability_margin_per_s": res.stability_margin_per_s}, indent=2))
            return
        typer.echo(f"speed {speed_rpm:g} r/min ({speed_rpm / 60:.2f} Hz); "
                   f"{'stable' if res.stable else 'UNSTABLE'} (largest Re λ = {res.stability_margin_per_s:.3f} 1/s)")
        typer.echo(f"{'mode':>4} {'f (Hz)':>8} {'f/running':>9} {'ζ':>7}")
        for i, (f, z) in enumerate(zip(res.frequencies_hz, res.damping_ratios), start=1):
            typer.echo(f"{i:>4} {f:8.2f} {f / (speed_rpm / 60):9.3f} {z:7.3f}")
