"""CLI commands of the simulator: ``rotordiag simulate`` and ``rotordiag modal``."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Optional

import typer

MECHANISM_HELP = (
    "Coupling model: pin (the paper's holonomic constraint); rigid (the offset turns with the shaft: "
    "a rotating coupling eccentricity, reads as 1X runout/unbalance); offset (stationary parallel offset "
    "of the exciter shaft line, coupling rigid; with --angular-misalignment-mrad also tilted about the coupling); flexible (stationary offset across a flexible coupling "
    "with its 2X reaction, stiffness from the plant's coupling_stiffness_n_m); aligned."
)


def load_plant(path: Optional[Path]):
    """Plant from a TOML/JSON file, or the MODEL.md default; errors become BadParameter."""
    from rotordiag.simulator import Plant

    if path is None:
        return Plant.default()
    try:
        return Plant.from_file(path)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--plant") from None


def _shaftline(file: Optional[Path], preset: Optional[str]):
    """The :class:`~rotordiag.simulator.shaftline.ShaftLine` of a file or a named preset (exactly one given)."""
    from rotordiag.simulator.train.shaftline import shaftline_of

    try:
        return shaftline_of(preset, file)[0]
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--train") from None


def _shaftline_train(file: Optional[Path], preset: Optional[str], line: Any = None):
    """The finite-element :class:`~rotordiag.simulator.train.Train` of a shaft-line file or preset."""
    from rotordiag.simulator.train.shaftline import train_from_shaftline

    try:
        return train_from_shaftline(line if line is not None else _shaftline(file, preset))
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def _summary(res) -> dict:
    from rotordiag.simulator.simulate import order_amplitudes

    out = {"status": res.status, "message": res.message, "speed_rpm": res.speed_rpm,
           "misalignment": res.inputs["misalignment"], "unbalance": res.inputs["unbalance"],
           "mechanism": res.inputs["mechanism"],
           "angular_misalignment_mrad": res.inputs.get("angular_misalignment_mrad", 0.0),
           "wall_time_s": round(res.wall_time_s, 4),
           "steps_per_rev": round(res.n_accepted / max(1, res.inputs["transient_revs"] + res.inputs["record_revs"]), 1),
           "bearings": []}
    d = res.journal_displacements_m * 1e6
    try:
        amps = order_amplitudes(res) * 1e6
    except ValueError:
        amps = None
    for b in range(4):
        entry: dict[str, Any] = {"bearing": b + 1}
        if len(d):
            entry["peak_to_peak_um"] = {k: float(d[:, b, i].max() - d[:, b, i].min()) for i, k in enumerate("xy")}
            entry["mean_eccentricity"] = float((abs(d[:, b, 0] + 1j * d[:, b, 1]) / (res.clearance_m * 1e6)).mean())
            entry["static_eccentricity"] = float(res.static_eccentricity[b])
            entry["attitude_angle_deg"] = float(res.attitude_angle_deg[b])
            entry["static_load_n"] = [float(v) for v in res.mean_bearing_load_n[b]]
        if amps is not None:
            for i, k in enumerate("xy"):
                a1, a2, a3 = amps[b, i]
                # order amplitudes are 0-pk (the line's amplitude); peak_to_peak_um is pk-pk of the waveform
                entry[f"{k}_1x_um_0pk"], entry[f"{k}_2x_um_0pk"], entry[f"{k}_3x_um_0pk"] = \
                    float(a1), float(a2), float(a3)
                entry[f"{k}_2x_1x"] = float(a2 / a1) if a1 > 0 else float("nan")
        out["bearings"].append(entry)
    return out


def _write_h5(res, path: Path) -> None:
    import h5py

    from rotordiag.core.version import code_version

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


def probe_recording(res, sample_rate_hz: float, snr_db: float, runout_um: float, seed: int):
    """What the probes would record of a simulation: the dataset's measurement model applied.

    Eight probes (bearings 1-4 at 45° and 135°), the record as long as the simulation allows
    at ``sample_rate_hz``; noise at ``snr_db`` and 1X runout of ``runout_um`` drawn from ``seed``.
    Returns ``(waveforms_um (8, n), channels [(bearing, angle_deg)], sample_rate_hz)``.
    """
    import math

    import numpy as np

    from rotordiag.simulator.dataset.measurement import MeasurementDraws, MeasurementSettings, probe_waveforms_um

    spr = res.inputs.get("samples_per_rev") or 128
    n_rec = res.journal_displacements_m.shape[0]
    revs_avail = n_rec / spr - 1.0
    n_points = int(math.floor(revs_avail * 60.0 / res.speed_rpm * sample_rate_hz))
    if n_points < 16:
        raise ValueError("--probes-out: the record is too short; raise --record-revs")
    settings = MeasurementSettings(bearings=(1, 2, 3, 4), probe_angles_deg=(45.0, 135.0),
                                   sample_rate_hz=sample_rate_hz, n_points=n_points)
    rng = np.random.default_rng(seed)
    r1 = np.full(4, float(runout_um))
    draws = MeasurementDraws(snr_db=snr_db, start_angle_rad=0.0, speed_fluctuation_phase_rad=0.0,
                             runout_1x_um=r1, runout_1x_phase_rad=rng.uniform(0, 2 * math.pi, 4),
                             runout_2x_um=np.zeros(4), runout_2x_phase_rad=np.zeros(4))
    w = probe_waveforms_um(res.journal_displacements_m, spr, res.speed_rpm, settings, draws, rng)
    return w.astype(np.float64), settings.channels, sample_rate_hz


def write_probes(path: Path, waveforms_um, channels, sample_rate_hz: float, *, speed_rpm: float | None = None,
                 clearance_um: float | None = None, keyphasor_signal=None) -> None:
    """:func:`_write_probes_now` into a temporary file beside ``path``, renamed into place when complete: a
    failed write leaves nothing half-written (``ValueError`` says why)."""
    tmp = path.with_name(f".{path.name}.part{path.suffix}")
    try:
        _write_probes_now(tmp, waveforms_um, channels, sample_rate_hz, speed_rpm=speed_rpm, clearance_um=clearance_um,
                          keyphasor_signal=keyphasor_signal)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)


def _write_probes_now(path: Path, waveforms_um, channels, sample_rate_hz: float, *, speed_rpm: float | None = None,
                 clearance_um: float | None = None, keyphasor_signal=None) -> None:
    """Write probe waveforms (µm) as .csv (``time_s`` then ``b<bearing>@<angle>`` columns, times to
    6 significant digits as DAQ exports print them), .npy (channels × points), .h5 (``waveforms``,
    ``channels`` table, ``sample_rate_hz`` / ``units`` / ``speed_rpm`` / ``clearance_um`` attributes) or
    .uff/.unv (universal file, one binary type-58b time record per probe, ID line 1 ``b<bearing>@<angle>``,
    ordinate unit label ``um``; written with pyuff). A ``keyphasor_signal`` (raw pulse channel) goes last: a
    ``kp`` column / record, or the last row of .npy / .h5 (read with ``--keyphasor-channel <its index>``)."""
    import numpy as np

    suffix = path.suffix.lower()
    names = [f"b{b}@{a:g}" for b, a in channels]
    if keyphasor_signal is not None:
        waveforms_um = np.vstack([waveforms_um, np.asarray(keyphasor_signal, dtype=float)[None]])
        names = names + ["kp"]
    if suffix == ".csv":
        t = np.arange(waveforms_um.shape[1]) / sample_rate_hz
        with path.open("w") as fh:
            fh.write("time_s," + ",".join(names) + "\n")
            for k in range(t.size):
                fh.write(f"{t[k]:.6g}," + ",".join(f"{v:.3f}" for v in waveforms_um[:, k]) + "\n")
    elif suffix == ".npy":
        np.save(path, waveforms_um.astype(np.float32))
    elif suffix in (".h5", ".hdf5"):
        import h5py

        table = np.array(list(channels), dtype=[("bearing", "i1"), ("angle_deg", "f8")])
        with h5py.File(path, "w") as f:
            f.create_dataset("waveforms", data=waveforms_um.astype(np.float32), compression="gzip", shuffle=True)
            f.create_dataset("channels", data=table)
            f.attrs["sample_rate_hz"] = float(sample_rate_hz)
            f.attrs["units"] = "um"
            if speed_rpm is not None:
                f.attrs["speed_rpm"] = float(speed_rpm)
            if clearance_um is not None:
                f.attrs["clearance_um"] = float(clearance_um)
    elif suffix in (".uff", ".unv"):
        import pyuff

        path.unlink(missing_ok=True)  # pyuff appends to an existing file
        uff = pyuff.UFF(str(path))
        for k, (name, (bearing, _angle)) in enumerate(zip(names, [*channels, (0, 0.0)])):
            record = {
                "type": 58, "binary": 1, "id1": name, "id2": "rotordiag simulate --probes-out", "id3": "",
                "id4": "", "id5": "", "func_type": 1, "func_id": k + 1, "ver_num": 0, "load_case_id": 0,
                "rsp_ent_name": "NONE", "rsp_node": int(bearing), "rsp_dir": k % 2 + 1, "ref_ent_name": "NONE",
                "ref_node": 0, "ref_dir": 0, "ord_data_type": 4, "num_pts": waveforms_um.shape[1],
                "abscissa_spacing": 1, "abscissa_min": 0.0, "abscissa_inc": 1.0 / sample_rate_hz,
                "z_axis_value": 0.0, "data": np.asarray(waveforms_um[k], dtype=np.float64),
                "x": np.arange(waveforms_um.shape[1]) / sample_rate_hz,
            }
            # record 9-12: abscissa (time, s), ordinate (displacement 8, µm), denominator, z axis
            for axis, (spec, label, units) in {"abscissa": (17, "Time", "s"),
                                               "ordinate": (8, "Displacement", "um"),
                                               "orddenom": (0, "NONE", "NONE"), "z_axis": (0, "NONE", "NONE")}.items():
                record.update({f"{axis}_spec_data_type": spec, f"{axis}_len_unit_exp": 0,
                               f"{axis}_force_unit_exp": 0, f"{axis}_temp_unit_exp": 0,
                               f"{axis}_axis_lab": label, f"{axis}_axis_units_lab": units})
            uff.write_sets(record, mode="add")
    else:
        raise ValueError(f"--probes-out: unknown ending {suffix!r}; use .csv, .npy, .h5 or .uff")


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


def _simulate_train(tr: Any, speed_rpm: float, *, probes_out: Optional[Path], as_json: bool, **kw: Any) -> None:
    """``simulate --train``: the train's steady recording (``simulator.train.recording``), its summary per
    bearing and, with ``probes_out``, its probes and keyphasor written as for the paper model (nothing half-written)."""
    import numpy as np

    from rotordiag.simulator.train import TrainError
    from rotordiag.simulator.train.recording import train_recording
    from rotordiag.simulator.transient import keyphasor_pulse_signal

    try:
        rec = train_recording(tr, speed_rpm, **kw)
    except (TrainError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from None
    for note in rec.warnings:
        typer.secho(f"warning: {note}", fg=typer.colors.YELLOW, err=True)
    p = rec.probes
    rows: list[dict[str, Any]] = []
    for b, cl in sorted(p.clearance_um.items()):
        pair = [k for k, (bb, _) in enumerate(p.channels) if bb == b]
        wave = p.waveforms_um[pair]
        rows.append({"bearing": b, "clearance_um": cl, "dc_um": [round(float(v), 2) for v in wave.mean(axis=1)],
                     "pk_pk_um": [round(float(v), 2) for v in np.ptp(wave, axis=1)]})
    summary = {"speed_rpm": p.speed_rpm, "inputs": rec.inputs, "warnings": rec.warnings, "bearings": rows,
               "wall_time_s": round(rec.run.wall_time_s, 3)}
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
    else:
        typer.echo(f"train at {p.speed_rpm:g} r/min: {rec.run.wall_time_s:.2f} s; least log decrement "
                   f"{rec.inputs['log_decrement']:.3f}")
        typer.echo(f"{'bearing':>7} {'c µm':>7} {'DC 45° µm':>10} {'DC 135° µm':>11} {'pk-pk 45°':>10} {'pk-pk 135°':>11}")
        for r in rows:
            typer.echo(f"{r['bearing']:>7} {r['clearance_um']:7.0f} {r['dc_um'][0]:10.1f} {r['dc_um'][1]:11.1f} "
                       f"{r['pk_pk_um'][0]:10.1f} {r['pk_pk_um'][1]:11.1f}")
    if probes_out is not None:
        try:
            write_probes(probes_out, p.waveforms_um, p.channels, p.sample_rate_hz, speed_rpm=p.speed_rpm,
                         clearance_um=min(p.clearance_um.values()),
                         keyphasor_signal=keyphasor_pulse_signal(rec.time_s, p.sample_rate_hz, p.keyphasor_times_s))
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint="--probes-out") from None
        typer.echo(f"wrote {probes_out} ({len(p.channels)} probes + keyphasor × {p.waveforms_um.shape[1]} "
                   f"samples at {p.sample_rate_hz:g} Hz, µm)", err=True)


def register(app: typer.Typer) -> None:
    """Add ``simulate`` and ``modal`` to the ``rotordiag`` app."""

    @app.command()
    def simulate(
        speed_rpm: float = typer.Option(..., help="Running speed, r/min (100–6000)."),
        misalignment: Optional[float] = typer.Option(None, help="Non-dimensional parallel misalignment Δ = δ/c "
                                                     "(0–0.9) of the paper's model (required for it; a train takes "
                                                     "--offset-um)."),
        unbalance: float = typer.Option(0.05, help="Non-dimensional generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        transient_revs: int = typer.Option(400, help="Revolutions discarded before recording."),
        record_revs: int = typer.Option(128, help="Revolutions recorded."),
        samples_per_rev: int = typer.Option(128, help="Samples per revolution."),
        exciter_unbalance: float = typer.Option(0.0, help="Exciter unbalance a2/c (0–0.5)."),
        exciter_unbalance_phase_deg: float = typer.Option(0.0, help="Exciter unbalance phase θ2, degrees."),
        offset_angle_deg: Optional[float] = typer.Option(
            None, help="Offset direction, degrees from +x (horizontal) toward +y (vertical up): -90 = the exciter "
                       "low, 0 = sideways. A train (--train/--shaftline): direction of --offset-um and the angle, "
                       "default -90 (a vertical offset, the common case in a plant). The paper's model: φ0, the "
                       "rotating eccentricity at t = 0 (rigid) or the stationary exciter shaft-line offset (offset, "
                       "flexible), default 0 (the paper's convention)."),
        coupling_phase_deg: float = typer.Option(0.0, help="flexible: phase ψ of the coupling's 2X excitation, degrees."),
        angular_misalignment_mrad: float = typer.Option(
            0.0, "--angular-misalignment-mrad",
            help="offset/flexible: angular offset α, mrad: the exciter shaft line tilted about the coupling in the "
                 "offset direction (bearing 4 moves by α × the plant's exciter_bearing_span_m); may be used with "
                 "misalignment 0."),
        as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
        plot: Optional[Path] = typer.Option(None, help="Write a PNG: journal orbits with Poincaré points, spectra."),
        out: Optional[Path] = typer.Option(None, help="Write the simulator's time series (journal positions, m) to this HDF5 file."),
        probes_out: Optional[Path] = typer.Option(None, "--probes-out", help="Write what 8 proximity probes would record (µm, the dataset's measurement model) as .csv/.npy/.h5/.uff, readable by 'rotordiag diagnose'."),
        probe_sample_rate_hz: float = typer.Option(2560.0, "--probe-sample-rate-hz", min=100, max=1e6, help="Sample rate of --probes-out, Hz."),
        snr_db: float = typer.Option(40.0, "--snr-db", help="Probe noise of --probes-out: signal-to-noise ratio, dB (inf: none)."),
        runout_um: float = typer.Option(0.0, "--runout-um", min=0, help="1X mechanical/electrical runout of --probes-out, µm."),
        seed: int = typer.Option(0, "--seed", help="Seed of the --probes-out noise and runout phases."),
        train: Optional[str] = typer.Option(None, "--train", help="Simulate a finite-element shaft train instead of "
                                            "the paper's model: a preset name (gen50_2pole, gen200_2pole, "
                                            "gen600_2pole, gen600_4pole)."),
        shaftline: Optional[Path] = typer.Option(None, "--shaftline", help="Simulate the finite-element train of "
                                                 "this shaft-line file (TOML/JSON)."),
        offset_um: float = typer.Option(0.0, "--offset-um", help="A train's parallel offset at the coupling, µm, "
                                        "along --offset-angle-deg (default -90: the exciter low), set by moving the "
                                        "exciter's bearings."),
        unbalance_kg_m: Optional[float] = typer.Option(None, "--unbalance-kg-m", help="A train's unbalance at the "
                                                       "middle of the generator, kg·m, at the keyphasor mark, in "
                                                       "place of its own (a preset's: ISO 21940-11 G2.5)."),
    ) -> None:
        """Simulate one operating point and summarise the journal vibration: the paper's model, or a shaft
        train (--train / --shaftline: misaligned by --offset-um and --angular-misalignment-mrad)."""
        import math

        from rotordiag.simulator import simulate as run

        if train is not None or shaftline is not None:
            if misalignment is not None or plant is not None:
                raise typer.BadParameter("--misalignment and --plant are the paper model's; a train takes "
                                         "--offset-um and --angular-misalignment-mrad", param_hint="--train")
            _simulate_train(_shaftline_train(shaftline, train), speed_rpm, offset_um=offset_um,
                            angular_mrad=angular_misalignment_mrad,
                            direction_deg=-90.0 if offset_angle_deg is None else offset_angle_deg,
                            unbalance_kg_m=unbalance_kg_m, transient_revs=min(transient_revs, 320),
                            record_revs=record_revs, samples_per_rev=samples_per_rev, snr_db=snr_db, seed=seed,
                            probes_out=probes_out, as_json=as_json)
            return
        if misalignment is None:
            raise typer.BadParameter("give --misalignment (Δ = δ/c) for the paper's model, or --train/--shaftline",
                                     param_hint="--misalignment")
        pl = load_plant(plant)
        try:
            res = run(pl, speed_rpm, misalignment, unbalance, mechanism=mechanism,
                      transient_revs=transient_revs, record_revs=record_revs, samples_per_rev=samples_per_rev,
                      exciter_unbalance=exciter_unbalance,
                      exciter_unbalance_phase_rad=math.radians(exciter_unbalance_phase_deg),
                      offset_angle_rad=math.radians(offset_angle_deg or 0.0),
                      coupling_phase_rad=math.radians(coupling_phase_deg),
                      angular_misalignment_mrad=angular_misalignment_mrad)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        summary = _summary(res)
        if as_json:
            typer.echo(json.dumps(summary, indent=2))
        else:
            typer.echo(f"status: {res.status} ({res.message}); {summary['wall_time_s']} s, "
                       f"{summary['steps_per_rev']} steps/rev")
            typer.echo(f"{'bearing':>7} {'dir':>3} {'1X µm 0-pk':>10} {'2X µm 0-pk':>10} {'3X µm 0-pk':>10} "
                       f"{'2X/1X':>7} {'µm pk-pk':>9}")
            for e in summary["bearings"]:
                for k in "xy":
                    if f"{k}_1x_um_0pk" in e:
                        typer.echo(f"{e['bearing']:>7} {k:>3} {e[f'{k}_1x_um_0pk']:10.2f} {e[f'{k}_2x_um_0pk']:10.2f} "
                                   f"{e[f'{k}_3x_um_0pk']:10.2f} {e[f'{k}_2x_1x']:7.3f} {e['peak_to_peak_um'][k]:9.2f}")
            typer.echo("static journal position over the record:")
            typer.echo(f"{'bearing':>7} {'ε':>6} {'attitude °':>10} {'load x kN':>10} {'load y kN':>10}")
            for e in summary["bearings"]:
                if "static_eccentricity" in e:
                    lx, ly = e["static_load_n"]
                    typer.echo(f"{e['bearing']:>7} {e['static_eccentricity']:6.3f} {e['attitude_angle_deg']:10.1f} "
                               f"{lx / 1e3:10.2f} {ly / 1e3:10.2f}")
        if plot is not None:
            _plot(res, plot)
            typer.echo(f"wrote {plot}", err=True)
        if out is not None:
            _write_h5(res, out)
            typer.echo(f"wrote {out}", err=True)
        if probes_out is not None:
            try:
                w, chans, fs = probe_recording(res, probe_sample_rate_hz, snr_db, runout_um, seed)
                write_probes(probes_out, w, chans, fs)
            except ValueError as exc:
                raise typer.BadParameter(str(exc), param_hint="--probes-out") from None
            typer.echo(f"wrote {probes_out} ({w.shape[0]} probes × {w.shape[1]} samples at {fs:g} Hz, µm)", err=True)

    @app.command()
    def runup(
        profile: str = typer.Option(..., help="Speed profile: start, end and duration separated by colons (r/min, r/min, s), e.g. "
                                              "100:3000:60 (a run-up; 3000:120:60 a coast-down), or time@speed "
                                              "points, e.g. 0@100,20@1500,60@3000. The model covers 100–6000 r/min."),
        misalignment: float = typer.Option(0.0, help="Non-dimensional parallel misalignment Δ = δ/c (0–0.9)."),
        unbalance: float = typer.Option(0.05, help="Non-dimensional generator unbalance A = a/c (0–0.5)."),
        mechanism: str = typer.Option("pin", help=MECHANISM_HELP),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON); default MODEL.md's plant."),
        sample_rate_hz: float = typer.Option(2560.0, "--sample-rate-hz", help="Acquisition rate, Hz."),
        settle_revs: int = typer.Option(200, help="Revolutions at the first speed before t = 0 (a settled start)."),
        offset_angle_deg: Optional[float] = typer.Option(
            None, help="Offset direction, degrees from +x toward +y (as `simulate`): a train's --offset-um, default -90 "
                       "(the exciter low); the paper model's φ0, default 0."),
        snr_db: float = typer.Option(40.0, "--snr-db", help="Probe noise, dB (inf: none)."),
        seed: int = typer.Option(0, "--seed", help="Seed of the probe noise."),
        out: Path = typer.Option(..., "--out", help="Probe file: .csv (with a kp keyphasor column), .npy/.h5 (the "
                                                    "keyphasor as the last channel, index 8) or .uff."),
        train: Optional[str] = typer.Option(None, "--train", help="Run a finite-element shaft train instead of the "
                                                                  "paper's model: a preset (gen50_2pole, gen200_2pole, "
                                                                  "gen600_2pole, gen600_4pole)."),
        shaftline: Optional[Path] = typer.Option(None, "--shaftline", help="Run the finite-element train of this "
                                                                           "shaft-line TOML (examples/shaftline_200mw.toml)."),
        offset_um: float = typer.Option(0.0, "--offset-um", help="A train's parallel offset at its first coupling, µm, "
                                                                 "along --offset-angle-deg (default -90: downward; "
                                                                 "--misalignment is the paper model's)."),
        unbalance_kg_m: Optional[float] = typer.Option(None, "--unbalance-kg-m", help="A train's unbalance at the "
                                                       "middle of its first rotor, kg·m, along +x at the keyphasor "
                                                       "mark, in place of its own (a preset's: ISO 21940-11 G2.5; "
                                                       "--unbalance is the paper model's)."),
    ) -> None:
        """Simulate a run-up or coast-down of the paper's model (or of a shaft train: --train / --shaftline) and
        write what its probes (x/y at 45° and 135° at every bearing) and a keyphasor record."""
        import math

        from rotordiag.simulator.transient import DEFAULT_CHANNELS, SpeedProfile, simulate_transient

        model: Any
        channels = DEFAULT_CHANNELS
        if train is not None or shaftline is not None:
            from rotordiag.simulator.train import TrainError
            from rotordiag.simulator.train import misaligned as train_misaligned
            from rotordiag.simulator.train.transient import TrainTransientModel, train_channels, unbalanced

            if misalignment or plant is not None:
                raise typer.BadParameter("--misalignment and --plant are the paper model's; a train takes "
                                         "--offset-um", param_hint="--train")
            tr = _shaftline_train(shaftline, train)
            try:
                if offset_um:
                    tr = train_misaligned(tr, offset_m=offset_um * 1e-6, direction_rad=math.radians(
                        -90.0 if offset_angle_deg is None else offset_angle_deg))
                model = TrainTransientModel(tr if unbalance_kg_m is None
                                            else unbalanced(tr, unbalance_kg_m, replace_own=True))
            except (TrainError, ValueError) as exc:
                raise typer.BadParameter(str(exc), param_hint="--offset-um") from None
            channels = train_channels(model.n_bearings)
            clearance_um = model.clearance_m * 1e6
        else:
            model = load_plant(plant)
            clearance_um = model.clearance_m * 1e6
        try:
            prof = SpeedProfile.parse(profile)
            res = simulate_transient(model, prof, misalignment, unbalance, mechanism=mechanism,
                                     sample_rate_hz=sample_rate_hz, settle_revs=settle_revs,
                                     offset_angle_rad=math.radians(offset_angle_deg or 0.0))
            w = res.probe_waveforms_um(channels, snr_db=snr_db, seed=seed)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        typer.echo(f"{prof.kind} {prof.speeds_rpm[0]:g} → {prof.speeds_rpm[-1]:g} r/min in {prof.duration_s:g} s: "
                   f"status {res.status} ({res.message}); {res.time_s.size} samples, "
                   f"{res.keyphasor_times_s.size} keyphasor pulses, {res.wall_time_s:.1f} s", err=True)
        if res.time_s.size < 16:
            raise typer.BadParameter("the run stopped before it recorded anything; nothing written")
        try:
            write_probes(out, w, channels, sample_rate_hz, clearance_um=clearance_um,
                         keyphasor_signal=res.keyphasor_signal())
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint="--out") from None
        typer.echo(f"wrote {out} ({len(channels)} probes + keyphasor × {w.shape[1]} samples at {sample_rate_hz:g} Hz, "
                   "µm)", err=True)

    plant_app = typer.Typer(help="Build plant files.", no_args_is_help=True)
    app.add_typer(plant_app, name="plant")

    @plant_app.command("from-shaftline")
    def from_shaftline(
        file: Optional[Path] = typer.Argument(None, help="Shaft-line TOML (see examples/shaftline_200mw.toml)."),
        preset: Optional[str] = typer.Option(None, help="A named machine instead of FILE: gen50_2pole, "
                                                        "gen200_2pole, gen600_2pole, gen600_4pole."),
        out: Optional[Path] = typer.Option(None, help="Lumped plant file to write (.toml or .json), for the "
                                                      "paper model; without it only the train is checked."),
        speed_rpm: Optional[float] = typer.Option(None, help="Check the finite-element train at this speed: "
                                                             "static bearing loads and stability margin."),
        bearing_stiffness_n_m: float = typer.Option(1e9, help="Bearing stiffness of the critical-speed check."),
    ) -> None:
        """Build the finite-element train of a shaft line (its static state and stability margin at
        --speed-rpm); with --out also reduce it to the lumped plant of the paper model and print the
        first two critical speeds of the beam model and of the lumped plant (the reduction's check)."""
        from rotordiag.simulator import shaftline as sl
        from rotordiag.simulator.train import TrainError, static_state
        from rotordiag.simulator.train.stability import stability

        if (file is None) == (preset is None):
            raise typer.BadParameter("give either FILE or --preset", param_hint="FILE")
        if out is None and speed_rpm is None:
            raise typer.BadParameter("give --out (the lumped plant) and/or --speed-rpm (check the train)",
                                     param_hint="--out")
        line = _shaftline(file, preset)
        train = _shaftline_train(file, preset, line)
        if speed_rpm is not None:
            try:
                st = static_state(train, speed_rpm)
                stab = stability(train, speed_rpm)
            except (TrainError, ValueError) as exc:
                raise typer.BadParameter(str(exc), param_hint="--speed-rpm") from None
            n = sum(r.n_stations for r in train.rotors)
            typer.echo(f"train: {n} stations; at {speed_rpm:g} r/min:")
            for (_, s), load, e in zip(train.supports(), st.bearing_load_n, st.eccentricity, strict=True):
                typer.echo(f"  {s.name}: {type(s.bearing).__name__}, load {-load[1] / 1e3:.1f} kN down, "
                           f"{load[0] / 1e3:+.1f} kN horizontal, |e|/c {e:.2f}")
            typer.echo(f"  least-damped mode {stab.frequency_hz:.1f} Hz "
                       f"({'forward' if stab.forward else 'backward'}), log decrement {stab.log_decrement:.3f} "
                       f"({'stable' if stab.stable else 'UNSTABLE: beyond the stability threshold'})")
        if out is None:
            return
        try:
            pl = sl.to_plant(line)
            pl.to_file(out)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        fe = sl.train_critical_speeds(line, bearing_stiffness_n_m)
        lu = sl.lumped_critical_speeds(pl, bearing_stiffness_n_m)
        typer.echo(f"wrote {out}")
        typer.echo(f"critical speeds with {bearing_stiffness_n_m:.1e} N/m bearings (non-rotating, r/min): "
                   f"beam model {fe[0] * 60:.0f}, {fe[1] * 60:.0f}; lumped plant {lu[0] * 60:.0f}, {lu[1] * 60:.0f} "
                   f"({(lu[0] / fe[0] - 1) * 100:+.1f} %, {(lu[1] / fe[1] - 1) * 100:+.1f} %)")

    @app.command()
    def modal(
        speed_rpm: float = typer.Option(1950.0, help="Running speed, r/min."),
        plant: Optional[Path] = typer.Option(None, help="Plant file (TOML or JSON)."),
        as_json: bool = typer.Option(False, "--json", help="Print as JSON."),
    ) -> None:
        """Natural frequencies and damping of the rotor linearised about its static equilibrium."""
        from rotordiag.simulator import modal as run

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
