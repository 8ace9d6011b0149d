"""Shaft trains for the API: the train of a request (a preset, shaft-line tables or a shaft-line TOML text), its
summary and its simulated recording.

Domain code below the API layer (it raises :class:`service.errors.InputError`; ``service/api/routes/trains.py``
gives the HTTP statuses). :func:`simulate_train_request` runs in a diagnosis worker (``service.pool.TrainSimulate``)
or a thread with the same time limit, as other heavy requests do.
"""
from __future__ import annotations

import dataclasses
import tempfile
import tomllib
from pathlib import Path
from typing import Any

from .errors import InputError

__all__ = ["line_of_request", "simulate_train_request"]


def line_of_request(body: Any) -> tuple[Any, float | None]:
    """The shaft line of a request with exactly one of ``preset``, ``shaftline``, ``shaftline_toml``, and the speed
    to use (the request's, else the preset's rated speed)."""
    from rotordiag.simulator.shaftline import ShaftLine
    from rotordiag.simulator.train.shaftline import shaftline_of

    given = [k for k in ("preset", "shaftline", "shaftline_toml") if getattr(body, k) is not None]
    if len(given) != 1:
        raise InputError("give exactly one of `preset`, `shaftline` (tables) or `shaftline_toml` (file text); "
                         f"got {given or 'none'}")
    if body.preset is None and body.speed_rpm is None:
        raise InputError("give `speed_rpm`: a shaft line carries no rated speed")
    rated = None
    try:
        if body.preset is not None:
            line, rated = shaftline_of(body.preset)
        elif body.shaftline is not None:
            line = ShaftLine.from_dict(body.shaftline)
        else:
            try:
                tables = tomllib.loads(body.shaftline_toml or "")
            except tomllib.TOMLDecodeError as exc:
                raise InputError(f"shaftline_toml is not valid TOML: {exc}") from None
            line = ShaftLine.from_dict(tables)
    except InputError:
        raise
    except (ValueError, TypeError, ArithmeticError, LookupError, AttributeError) as exc:
        raise InputError(f"shaft line: {exc}") from None
    return line, rated


def _file_bytes(rec: Any, fmt: str) -> bytes:
    """The recording's probes and keyphasor as the CLI's ``--probes-out`` writes them (``simulator.cli.write_probes``)."""
    from rotordiag.simulator.cli import write_probes
    from rotordiag.simulator.transient import keyphasor_pulse_signal

    p = rec.probes
    with tempfile.TemporaryDirectory(prefix="rotordiag-train-") as tmp:
        path = Path(tmp) / f"train.{fmt}"
        write_probes(path, p.waveforms_um, p.channels, p.sample_rate_hz, speed_rpm=p.speed_rpm,
                     clearance_um=min(p.clearance_um.values()),
                     keyphasor_signal=keyphasor_pulse_signal(rec.time_s, p.sample_rate_hz, p.keyphasor_times_s))
        return path.read_bytes()


def simulate_train_request(body: Any) -> dict[str, Any]:
    """The steady recording a :class:`service.schemas.TrainSimulateRequest` asks for.

    Returns ``{"json": TrainSimulateOut fields}`` or ``{"file": bytes, "warnings": [...]}`` (``format`` csv/h5);
    a bad train, offset or speed raises :class:`InputError` saying what to fix (a journal pressed on its metal names
    the bearing and the largest offset the train takes).
    """
    from rotordiag.simulator.train import TrainError
    from rotordiag.simulator.train.recording import train_recording
    from rotordiag.simulator.train.shaftline import train_from_shaftline

    line, rated = line_of_request(body)
    speed = float(body.speed_rpm if body.speed_rpm is not None else rated)  # type: ignore[arg-type]
    try:
        if body.coupling is not None:
            line = dataclasses.replace(line, coupling=body.coupling)
        train = train_from_shaftline(line)
        rec = train_recording(train, speed, offset_um=body.offset_um, angular_mrad=body.angular_mrad,
                              direction_deg=body.offset_angle_deg, unbalance_kg_m=body.unbalance_kg_m,
                              transient_revs=body.transient_revs, record_revs=body.record_revs,
                              samples_per_rev=body.samples_per_rev,
                              snr_db=float("inf") if body.snr_db is None else body.snr_db, seed=body.seed,
                              probes=None if body.probes is None else [(p.bearing, p.angle_deg) for p in body.probes])
    except (TrainError, ValueError, ArithmeticError) as exc:
        raise InputError(f"train: {exc}") from None
    if body.format != "json":
        return {"file": _file_bytes(rec, body.format), "warnings": rec.warnings}
    p = rec.probes
    channels = [{"bearing": int(b), "angle_deg": float(a), "units": "um", "data": p.waveforms_um[k].tolist()}
                for k, (b, a) in enumerate(p.channels)]
    inputs = {**rec.inputs, "coupling": line.coupling}
    if inputs.get("snr_db") == float("inf"):
        inputs["snr_db"] = None       # JSON has no infinity
    return {"json": {"source": body.preset or "shaftline", "speed_rpm": float(p.speed_rpm),
                     "sample_rate_hz": float(p.sample_rate_hz), "channels": channels,
                     "keyphasor_times_s": [float(t) for t in p.keyphasor_times_s],
                     "clearance_um": {str(b): float(c) for b, c in sorted(p.clearance_um.items())},
                     "log_decrement": float(rec.inputs["log_decrement"]), "warnings": list(rec.warnings),
                     "inputs": inputs}}
