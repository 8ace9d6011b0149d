"""``rotordiag plots``: the start-up / coast-down plots of a recording as PNG (issue 46)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer


def _fail(message: str, code: int = 2) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


def read_transient(path: Path, given: dict[str, Any], sidecar: Path | None = None, *, keyphasor: bool = True):
    """Read a start-up recording with the transient limits (:data:`rotordiag.features.transient.TRANSIENT_READ_LIMITS`)
    and the options ``rotordiag diagnose`` takes; ``keyphasor=False`` drops any keyphasor (speed from the signal)."""
    from dataclasses import replace

    from rotordiag.features.reader import read_recording
    from rotordiag.features.transient import TRANSIENT_READ_LIMITS

    from .diagnose_files import load_options

    opts = load_options(path, sidecar, given)
    res = read_recording(path, options=opts, limits=TRANSIENT_READ_LIMITS)
    if not keyphasor and res.recording.keyphasor_times_s is not None:
        res.recording = replace(res.recording, keyphasor_times_s=None)
        res.notes.append("keyphasor left out (--no-keyphasor): the speed is tracked from the signal")
    return res


def parse_speeds(text: str | None) -> list[float] | None:
    if not text:
        return None
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(f"--orbit-speeds {text!r}: give r/min values separated by commas, e.g. 1000,1500") from None


def register(app: typer.Typer) -> None:
    """Add ``plots`` to the ``rotordiag`` app."""

    @app.command()
    def plots(
        file: Path = typer.Argument(..., help="A start-up or coast-down recording (.csv, .npy, .h5, .uff, .json)."),
        out_dir: Path = typer.Option(..., "--out-dir", help="Folder for the PNGs (created)."),
        sample_rate_hz: Optional[float] = typer.Option(None, "--sample-rate-hz", help="Sample rate, Hz (or a time_s column)."),
        units: Optional[str] = typer.Option(None, "--units", help="um | mm | m | mil | V."),
        channels: Optional[str] = typer.Option(None, "--channels", help="Probe layout in file order, BEARING@ANGLE."),
        keyphasor_channel: Optional[str] = typer.Option(None, "--keyphasor-channel", help="Raw keyphasor channel: CSV column or index (default: a CSV column named kp)."),
        keyphasor_edge: str = typer.Option("falling", "--keyphasor-edge", help="falling | rising."),
        no_keyphasor: bool = typer.Option(False, "--no-keyphasor", help="Ignore the keyphasor: track the speed from the signal (phases then not referenced)."),
        rotation: str = typer.Option("ccw", "--rotation", help="Shaft rotation seen from the driver end: ccw | cw."),
        viewed_from: str = typer.Option("driver", "--viewed-from", help="End the probe angles are measured from: driver | non-driver."),
        clearance_um: Optional[float] = typer.Option(None, "--clearance-um", help="Radial bearing clearance, µm (the centreline's circle)."),
        dc_removed: bool = typer.Option(False, "--dc-removed", help="AC-coupled probes: no centreline."),
        sidecar: Optional[Path] = typer.Option(None, "--sidecar", help="JSON with the read options by name."),
        revs_per_step: int = typer.Option(1, "--revs-per-step", help="Revolutions per tracked step (1: every revolution)."),
        orbit_speeds: Optional[str] = typer.Option(None, "--orbit-speeds", help="Speeds of the orbit plots, r/min, e.g. 1000,1500,2900 (default: 10, 50, 90 % of the run)."),
        plant: Optional[Path] = typer.Option(None, "--plant", help="Plant file for the Campbell diagram (TOML/JSON)."),
        campbell: bool = typer.Option(False, "--campbell", help="Campbell diagram of the default plant (MODEL.md) when no --plant is given."),
        centreline_reference: str = typer.Option("as recorded", "--centreline-reference", help="'as recorded' (the probes' zero: the bearing centre for rotordiag's recordings) | 'slow roll at the bottom'."),
        output_units: str = typer.Option("um", "--output-units", help="Lengths on the plots: um | mil."),
        cascade_scale: str = typer.Option("db", "--cascade-scale", help="Trace height of the waterfall and full-spectrum cascades: db (dB below the largest line, 60 dB shown) | row (each trace to its own largest line) | linear (one scale: a whip line dwarfs the low speeds)."),
        as_json: bool = typer.Option(False, "--json", help="Print the tracked 1X/2X peaks and the files as JSON."),
    ) -> None:
        """Bode, polar, waterfall, full spectrum, centreline, orbit and Campbell plots of a start-up or coast-down."""
        import json

        from rotordiag.features.plots import save_figures, transient_figures
        from rotordiag.features.transient import track_orders

        given = {"sample_rate_hz": sample_rate_hz, "units": units, "channels": channels,
                 "keyphasor_channel": keyphasor_channel, "keyphasor_edge": keyphasor_edge, "rotation": rotation,
                 "viewed_from": viewed_from, "clearance_um": clearance_um, "dc_removed": dc_removed or None}
        try:
            res = read_transient(file, given, sidecar, keyphasor=not no_keyphasor)
            track = track_orders(res.recording, revs_per_step=revs_per_step)
            pl = None
            if plant is not None or campbell:
                from rotordiag.simulator import Plant

                pl = Plant.from_file(plant) if plant is not None else Plant.default()
            figs = transient_figures(res.recording, track, orbit_speeds_rpm=parse_speeds(orbit_speeds), plant=pl,
                                     centreline_reference=centreline_reference, units=output_units,
                                     cascade_scale=cascade_scale)
            paths = save_figures(figs, out_dir)
        except ValueError as exc:
            _fail(f"{file}: {exc}")
        for note in res.notes + track.notes:
            typer.echo(f"note: {note}", err=True)
        peaks = track.peaks(1) + track.peaks(2)
        if as_json:
            typer.echo(json.dumps({"kind": track.kind, "speed_source": track.speed_source,
                                   "speed_range_rpm": [float(track.speed_rpm.min()), float(track.speed_rpm.max())],
                                   "peaks": peaks, "files": [str(p) for p in paths], "conventions": track.conventions,
                                   "notes": res.notes + track.notes}, indent=2))
            return
        typer.echo(f"{track.kind}, {track.speed_rpm.min():.0f}–{track.speed_rpm.max():.0f} r/min, "
                   f"{track.speed_rpm.size} steps, speed from the {track.speed_source}")
        for p in peaks:
            typer.echo(f"  {p['order']}X peak b{p['bearing']}@{p['angle_deg']:g}: {p['amp_um_pp']:.1f} µm pk-pk "
                       f"at {p['speed_rpm']:.0f} r/min")
        typer.echo(f"wrote {len(paths)} PNG(s) to {out_dir}")
