"""One reader for recordings: CSV, NPY, HDF5, UFF (type 58) and JSON → :class:`rotordiag.features.Recording`.

The CLI (``rotordiag diagnose``), the service (``/diagnose`` JSON, binary and multipart,
``/diagnose/batch``) and the web page (``/ui/plot-data``) all call :func:`read_recording`
(or :func:`recording_from_dict` for a JSON object already decoded), so one file means one
recording whichever door it comes through. Every file is treated as hostile: HDF5 goes
through :func:`rotordiag.features.safe_io.check_hdf5` and is decoded in a child process
with a memory and a time limit (:mod:`rotordiag.features.sandbox`; the HDF5 library itself
can loop or crash on a corrupt file), NPY through ``load_npy_bounded`` and JSON through
``loads_json_finite`` before any value is read.

What a file may say, and what :class:`ReadOptions` may add (options win over the file):

- **Channel layout** (bearing 1–8 along the train and probe angle of every probe). CSV header names
  ``b<bearing>@<angle>`` (``b2@45``; ``2@45`` too) give it; or ``ReadOptions.channels``:
  a list in file order (``"1@45,1@135,2@45,2@135"`` or ``[(1, 45.0), ...]``) or a mapping
  from column name to ``"b2@45"`` (``{"GEN DE X": "b2@45", ...}``; other columns are
  ignored). Without either, 8 channels are read as the dataset default
  b1@45, b1@135, b2@45, …, b4@135; any other count is an error.
- **Time base**: ``sample_rate_hz``, or a time column (``time``, ``t`` or LabVIEW's ``X_Value``, with
  its unit in any common spelling: ``Time (s)``, ``Time [ms]``, ``t_s``, ``time_us``, or in a unit row
  below the names; seconds when none), or a collector's metadata line (``Delta_X``, ``Sample Rate: 4096 Hz``).
  The rate is the mean spacing; every time must lie within
  ``TIME_TOLERANCE`` (a fifth) of a sample interval of the uniform grid, which the
  rounding of real DAQ exports (times printed to 6 significant digits) passes; a dropped
  or repeated sample fails with the row named.
- **Keyphasor**: pulse times (``keyphasor_times_s``), or a raw keyphasor channel (a CSV
  column named ``kp``, ``keyphasor`` or ``kph``, or ``ReadOptions.keyphasor_channel``):
  a pulse is counted where the signal crosses the threshold (default: halfway between the
  channel's 1st and 99th percentile) on the chosen edge (default ``falling``: a notch in
  the shaft opens the gap and drives a proximity-probe keyphasor more negative; use
  ``rising`` for a projection or a TTL pulse). Crossings are re-armed only after the signal
  has gone back past the threshold by a tenth of the span (hysteresis), and each time is
  interpolated linearly between the two samples around the crossing.
- **Units**: ``um`` (``µm``), ``mm``, ``m``, ``mil``, or ``V`` / ``mV`` with
  ``sensitivity_v_per_mm`` (7.87, or as the datasheet says it: ``"200 mV/mil"``, ``"7.87 mV/um"``) and
  ``gap_voltage_v`` (the DC gap voltage in V; without it the mean is removed), see
  :func:`rotordiag.core.units.volts_to_um`. A file states them in the column names (``GEN DE X [mV]``),
  a unit row below the names, or a metadata line (``Units: mil``; LabVIEW ``Y_Unit_Label``).
- **Direction**: probe angles are degrees counter-clockwise from the horizontal to the
  observer's right, seen from ``viewed_from`` (``driver``: the turbine/generator end,
  API 670's convention; ``non-driver``: the exciter end). ``rotation`` is the direction
  the shaft turns seen from the **driver** end (``ccw`` or ``cw``). The feature extractor
  works in a frame where the shaft turns counter-clockwise; when the shaft turns clockwise
  seen from the end the angles are measured from, every angle α becomes 180° − α (the
  view mirrored about the vertical), so a mirrored installation is not read as reverse whirl.

Formats:

- **CSV**: one column per channel, one row per sample, comma (or semicolon / tab)
  separated; an optional header row, optionally followed by a unit row; ``#`` comment lines and a
  collector's metadata block above the column names (a LabVIEW .lvm header, ``Key: value`` lines)
  are skipped. A column that is neither time, keyphasor, named ``b2@45`` nor mapped is never read
  as a probe: without a mapping it is refused by name, with one it is left out and a note names it.
- **NPY**: a 2-D numeric array, channels × points (points × channels is transposed when
  only that matches the layout); never unpickled.
- **HDF5**: a rotordiag dataset file (``waveforms`` (N, C, P) with the ``channels``
  compound table, ``done`` flags and per-sample ``parameters/…``; ``sample_index`` picks
  the row) or a file with a 2-D ``waveforms`` array, ``sample_rate_hz`` / ``units`` /
  ``speed_rpm`` / ``clearance_um`` attributes and a ``channels`` table (compound with
  ``bearing`` and ``angle_deg`` fields, or a group with those two datasets).
- **JSON**: the ``/diagnose`` request body (``sample_rate_hz``, ``channels`` each with
  ``bearing``, ``angle_deg``, ``units``, ``data``; optional ``speed_rpm``,
  ``keyphasor_times_s``, ``clearance_um``).
"""
from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rotordiag.core.units import INPUT_UNITS, UNITS_TO_UM, VOLTS_PER, input_unit, sensitivity_v_per_mm, volts_to_um

from ._acquisitions import acquisitions_in_order, parse_keyphasor_takes
from ._recording import ProbeChannel, Recording, parse_speed_range
from .safe_io import check_hdf5, load_npy_bounded, loads_json_finite
from .sandbox import call_isolated

__all__ = ["ReadOptions", "ReadLimits", "ReadResult", "read_recording", "recording_from_dict", "parse_layout",
           "parse_channel_map", "TIME_UNITS",
           "keyphasor_times_from_pulses", "keyphasor_channels", "sample_rate_from_times", "DEFAULT_LAYOUT", "FORMATS", "TIME_TOLERANCE"]

#: layout assumed for an 8-channel file that does not say its own (the dataset default)
DEFAULT_LAYOUT: tuple[tuple[int, float], ...] = tuple((b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0))
#: formats and the file-name endings that select them
FORMATS: dict[str, tuple[str, ...]] = {"csv": (".csv", ".txt", ".lvm"), "npy": (".npy",), "hdf5": (".h5", ".hdf5", ".hdf"),
                                       "json": (".json",), "uff": (".uff", ".unv")}
#: largest deviation of a time stamp from the uniform grid, in sample intervals
TIME_TOLERANCE = 0.2
#: time units a time column may be in (its name, ``Time [ms]``, or the unit row below the names) → seconds
TIME_UNITS: dict[str, float] = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0, "ms": 1e-3,
                                "msec": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3, "us": 1e-6, "µs": 1e-6,
                                "μs": 1e-6, "usec": 1e-6, "microsecond": 1e-6, "microseconds": 1e-6, "ns": 1e-9}
#: a time column: ``time``, ``t``, ``X_Value`` (LabVIEW .lvm), ``elapsed time``, with an optional unit
#: (``Time (s)``, ``Time [ms]``, ``t_s``, ``time_us``, ``time/s``); the unit must be one of TIME_UNITS
_TIME_NAME_RE = re.compile(r"^(?:time|t|x_value|elapsed[ _]?time|zeit)(?:[\s_/-]*[(\[]?\s*([a-zµμ]+)\s*[)\]]?)?$",
                           re.IGNORECASE)
#: a column name that ends in its unit: ``GEN DE X [mV]``, ``b2@45 (um)``
_NAME_UNIT_RE = re.compile(r"^(.*?)\s*[(\[]\s*([^()\[\]]+?)\s*[)\]]\s*$")
#: header lines of a metadata block that give the sample interval (s) or the sample rate (Hz)
_META_INTERVAL_KEYS = ("delta_x", "sample interval", "sample_interval_s", "dt")
_META_RATE_KEYS = ("sample rate", "sampling rate", "sample_rate", "sample_rate_hz", "sampling frequency", "fs",
                   "sample rate (hz)", "sampling rate (hz)", "sample frequency")
#: header lines that give when the recording was made (a LabVIEW .lvm header has ``Date`` and ``Time`` lines)
_META_WHEN_KEYS = ("recorded at", "recorded_at", "recorded", "recording time", "start time", "start_time",
                   "timestamp", "acquisition time", "trigger time", "date/time", "datetime", "measurement time")
_META_DATE_KEYS = ("date", "start date", "recording date")
_META_CLOCK_KEYS = ("time", "start clock", "time of day")
_WHEN_FORMATS = ("%Y-%m-%d %H:%M:%S.%f", "%Y-%m-%d %H:%M:%S", "%Y-%m-%d %H:%M", "%Y/%m/%d %H:%M:%S.%f",
                 "%Y/%m/%d %H:%M:%S", "%Y/%m/%d %H:%M", "%d.%m.%Y %H:%M:%S", "%d.%m.%Y %H:%M", "%d-%b-%y %H:%M:%S",
                 "%d-%b-%Y %H:%M:%S", "%m/%d/%Y %H:%M:%S", "%m/%d/%Y %I:%M:%S %p")


def parse_recorded_at(text: str) -> str | None:
    """When a recording was made, from a header's text: ISO 8601 or a collector's common spellings
    (``2026/03/02 10:00:00.5``, ``02.03.2026 10:00``, ``02-Mar-26 10:00:00``); ISO 8601 back (an offset kept, none
    meaning UTC), or None when the text is no such time. A day-first/month-first ambiguity (``03/02/2026``) is
    read month first (US collectors' exports) only in the ``m/d/Y`` spellings."""
    import datetime as dt

    t = " ".join(re.sub(r"(\d)T(\d)", r"\1 \2", str(text).strip()).split())
    if not t or len(t) > 60:
        return None
    t = re.sub(r"(:\d\d\.\d{6})\d+", r"\1", t)          # LabVIEW writes 7 decimals of a second
    try:
        return dt.datetime.fromisoformat(t.replace("Z", "+00:00")).isoformat()
    except ValueError:
        pass
    for fmt in _WHEN_FORMATS:
        try:
            return dt.datetime.strptime(t, fmt).isoformat()
        except ValueError:
            continue
    return None


_META_UNIT_KEYS = ("units", "unit", "y_unit_label", "engineering units", "eu")
_KP_COLUMNS = ("kp", "keyphasor", "kph", "keyphasor_v")
_LAYOUT_RE = re.compile(r"^\s*b?([1-8])\s*@\s*(-?\d+(?:\.\d*)?)\s*$", re.IGNORECASE)
#: CSV column names: ``b2@45`` and the spelled-out ``b2_45deg_um`` / ``b2 45° mil`` (unit suffix optional)
_HEADER_RE = re.compile(r"^\s*b([1-8])\s*[@_ ]\s*(-?\d+(?:\.\d*)?)\s*(?:deg|°)?"
                        r"(?:[_ ]*[\[(]?(um|µm|μm|mm|mils?|mv|v)[\])]?)?\s*$", re.IGNORECASE)
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_NPY_MAGIC = b"\x93NUMPY"
#: a universal file starts with a "-1" delimiter line followed by the dataset type (58: function at a DOF)
_UFF_START = re.compile(rb"^\s*-1\s*\r?\n\s*(58b?|151|164)\b")


@dataclass(frozen=True)
class ReadLimits:
    """Bounds on what a file may make the reader allocate.

    The defaults suit one recording (up to 16 probes, 16 s at 16 kHz); the CLI raises
    ``max_file_bytes`` / ``max_hdf5_bytes`` for local dataset files.
    """

    max_channels: int = 16                 # two probes at each of up to MAX_BEARING (8) bearings
    max_points: int = 262_144
    max_file_bytes: int = 256 * 2**20
    max_hdf5_bytes: int = 256 * 2**20
    max_chunk_ratio: float = 200.0
    max_keyphasor_pulses: int = 100_000
    #: chunks an HDF5 file may be stored in (each costs a call when its compression ratio is checked)
    max_hdf5_chunks: int = 200_000
    #: HDF5 is decoded in a child process (:mod:`rotordiag.features.sandbox`) with this much
    #: memory (``None``: 3 x ``max_hdf5_bytes`` + 256 MiB) and this wall-clock limit;
    #: ``isolate_hdf5=False`` decodes in the calling process (trusted files only).
    isolate_hdf5: bool = True
    hdf5_memory_bytes: int | None = None
    hdf5_timeout_s: float = 30.0


@dataclass(frozen=True)
class ReadOptions:
    """What the caller knows about a recording beyond the file (``None`` = take it from the file).

    Parameters
    ----------
    sample_rate_hz : float, optional
    units : str, optional
        ``um``, ``mm``, ``m``, ``mil``, ``V`` or ``mV`` (default: the file's, else ``um``).
    sensitivity_v_per_mm : float or str, optional
        For ``units`` V or mV: the probe scale factor, a positive number of V/mm or text with its units as a
        datasheet states it (``"200 mV/mil"``, ``"7.87 mV/um"``; :func:`rotordiag.core.units.sensitivity_v_per_mm`).
    gap_voltage_v : float, optional
        For ``units`` V or mV: the DC gap voltage, in V (``-10``) whatever the file's voltage unit.
    channels : str, sequence or mapping, optional
        Layout in file order, or column name → ``"b<bearing>@<angle>"`` (see module docstring; a text
        mapping ``"GEN DE X=b2@45;GEN DE Y=b2@135"`` is read by :func:`parse_channel_map`).
    keyphasor_channel : str or int, optional
        Column name or index (file order) of a raw keyphasor pulse channel; with ``acquisitions``, one per
        acquisition separated by semicolons (``"kp_a;kp_b"``), in the order the acquisitions are listed.
    keyphasor_threshold_v : float, optional
        Threshold of the pulse detection, in the channel's own units.
    keyphasor_edge : {"falling", "rising"}
    keyphasor_times_s : sequence of float, or of sequences of float, optional
        Pulse times (s from the first sample); wins over a keyphasor channel. With ``acquisitions``, one sequence
        per acquisition, on its take's clock (``Recording.keyphasor_times_s``).
    speed_rpm, clearance_um : float, optional
    speed_range_rpm : (float, float) or str, optional
        The running speed's range (min, max) r/min, or ``"min,max"``, when the speed is not
        known exactly (the machine's nominal speed): restricts the speed estimate.
    rotation : {"ccw", "cw"}
        Shaft rotation seen from the driver end.
    viewed_from : {"driver", "non-driver"}
        The end the probe angles are measured from.
    sample_index : int, optional
        Row of a dataset HDF5 file (required when it holds more than one).
    dc_removed : bool, optional
        The channels' DC part is no shaft position (AC-coupled acquisition): no centreline
        features (``Recording.dc_removed``). Set for ``units="V"`` without ``gap_voltage_v``.
    acquisitions : str or sequence of sequences of int, optional
        Groups of bearings sampled together when the channels come from separate acquisitions, e.g.
        ``"1,2;3,4"`` (``Recording.acquisitions``).
    """

    sample_rate_hz: float | None = None
    units: str | None = None
    sensitivity_v_per_mm: float | str | None = None
    gap_voltage_v: float | None = None
    channels: str | Sequence[Any] | Mapping[str, str] | None = None
    keyphasor_channel: str | int | None = None
    keyphasor_threshold_v: float | None = None
    keyphasor_edge: Literal["falling", "rising"] = "falling"
    keyphasor_times_s: Sequence[float] | Sequence[Sequence[float]] | None = None
    speed_rpm: float | None = None
    clearance_um: float | Mapping[int, float] | None = None
    speed_range_rpm: str | Sequence[float] | None = None
    rotation: Literal["ccw", "cw"] = "ccw"
    viewed_from: Literal["driver", "non-driver"] = "driver"
    sample_index: int | None = None
    dc_removed: bool | None = None
    acquisitions: str | Sequence[Sequence[int]] | None = None


@dataclass
class ReadResult:
    """A recording and what the reader found out on the way.

    Attributes
    ----------
    recording : Recording
    format : str
        ``csv``, ``npy``, ``hdf5`` or ``json``.
    notes : list of str
        Assumptions made (default layout, sample rate from the time column, mirrored angles, …).
    truth : dict, optional
        ``{"misalignment": Δ}`` of a dataset-file sample.
    asset_id, plant : str, optional
        From a JSON body.
    """

    recording: Recording
    format: str
    notes: list[str] = field(default_factory=list)
    truth: dict[str, float] | None = None
    asset_id: str | None = None
    plant: str | None = None


# --------------------------------------------------------------------------- helpers


def parse_layout(text: str | Sequence[Any]) -> list[tuple[int, float]]:
    """``"1@45,1@135"`` (or ``["b1@45", (1, 135)]``, or dicts with bearing/angle_deg) → ``[(1, 45.0), (1, 135.0)]``.

    Raises
    ------
    ValueError
        Naming the entry that is not ``BEARING@ANGLE``.
    """
    items: Sequence[Any] = text.split(",") if isinstance(text, str) else text
    out = []
    for k, item in enumerate(items):
        if isinstance(item, str):
            m = _LAYOUT_RE.match(item)
            if not m:
                raise ValueError(f"channels: entry {k + 1} {item!r} is not BEARING@ANGLE (e.g. 'b2@45' or '2@45'; "
                                 "bearing 1-8 along the train, angle in degrees)")
            out.append((int(m.group(1)), float(m.group(2))))
        elif isinstance(item, Mapping):
            try:
                out.append((int(item["bearing"]), float(item["angle_deg"])))
            except (KeyError, TypeError, ValueError):
                raise ValueError(f"channels: entry {k + 1} needs 'bearing' (1-8) and 'angle_deg', got {item!r}") from None
        else:
            try:
                b, a = item
                out.append((int(b), float(a)))
            except (TypeError, ValueError):
                raise ValueError(f"channels: entry {k + 1} {item!r} is not (bearing, angle_deg)") from None
    return out


def parse_channel_map(text: str) -> str | dict[str, str]:
    """``'GEN DE X=b2@45;GEN DE Y=b2@135'`` → a column-name mapping; text without ``=`` is a layout in file
    order and comes back as it is (the CLI's ``--channels``, the API's ``channel_map``, a sidecar).

    Raises
    ------
    ValueError
        An entry that is not ``COLUMN=b<bearing>@<angle>``, or a column named twice.
    """
    if "=" not in text:
        return text
    mapping: dict[str, str] = {}
    for part in (p for p in text.split(";") if p.strip()):
        name, sep, where = part.rpartition("=")
        if not sep or not name.strip():
            raise ValueError(f"channel mapping: {part.strip()!r} is not COLUMN=b<bearing>@<angle> (e.g. "
                             "'GEN DE X=b2@45;GEN DE Y=b2@135')")
        if name.strip().lower() in (k.lower() for k in mapping):
            raise ValueError(f"channel mapping: column {name.strip()!r} is mapped twice")
        parse_layout([where.strip()])
        mapping[name.strip()] = where.strip()
    return mapping


def sample_rate_from_times(times_s: np.ndarray, tolerance: float = TIME_TOLERANCE) -> float:
    """Sample rate (Hz) from a column of time stamps, checking they are uniformly spaced.

    The rate is one over the least-squares spacing of the stamps; every stamp must lie within
    ``tolerance`` sample intervals of that uniform grid (rounding to 6 significant digits stays
    far inside it for records of tens of seconds).

    Raises
    ------
    ValueError
        Fewer than two stamps, not increasing, or irregular (a dropped or repeated sample):
        the message names the first offending row.
    """
    t = np.asarray(times_s, dtype=np.float64)
    if t.size < 2 or not np.all(np.isfinite(t)):
        raise ValueError("time column: needs at least two finite time stamps")
    span = t[-1] - t[0]
    if not span > 0:
        raise ValueError("time column: the times do not increase; put the time of each sample in s")
    steps = np.diff(t)
    med = float(np.median(steps))
    jump = np.flatnonzero(np.abs(steps - med) > 0.5 * med) if med > 0 else np.arange(steps.size)
    if jump.size:
        row = int(jump[0]) + 1
        raise ValueError(
            f"time column: the samples are not evenly spaced (data row {row + 1}, t = {t[row]:g} s, comes "
            f"{steps[row - 1] / med if med > 0 else 0:.2f} sample intervals after the row before; a dropped or "
            "repeated sample?). Resample the record to a fixed rate, or cut it before the gap")
    k = np.arange(t.size, dtype=np.float64)
    kc = k - k.mean()
    dt = float(np.dot(kc, t - t.mean()) / np.dot(kc, kc))    # least-squares spacing: the rounding averages out
    if not dt > 0:
        raise ValueError("time column: the times do not increase; put the time of each sample in s")
    dev = np.abs(t - (t.mean() + dt * kc)) / dt
    bad = np.flatnonzero(dev > tolerance)
    if bad.size:
        row = int(bad[0])
        raise ValueError(
            f"time column: the samples drift off a uniform grid (data row {row + 1}, t = {t[row]:g} s, is "
            f"{dev[row]:.2f} sample intervals off a uniform {1 / dt:g} Hz grid; times with too few digits, or a "
            "clock that drifts?). Write the times with more digits, or give the sample rate instead")
    return 1.0 / dt


def keyphasor_channels(spec: str | int | None) -> list[str | int]:
    """The keyphasor channel(s) named by ``ReadOptions.keyphasor_channel``: a column name or an index, or one per
    acquisition separated by semicolons (``"kp_a;kp_b"``, ``"8;9"``), in the order the acquisitions are listed."""
    if spec is None:
        return []
    if isinstance(spec, int):
        return [spec]
    parts = [p.strip() for p in str(spec).split(";") if p.strip()]
    return [int(p) if p.isdigit() else p for p in parts]


def keyphasor_times_from_pulses(signal: np.ndarray, sample_rate_hz: float, *, threshold: float | None = None,
                                edge: str = "falling") -> np.ndarray:
    """Once-per-revolution pulse times (s) from a raw keyphasor channel.

    Parameters
    ----------
    signal : ndarray, shape (n_points,)
        The keyphasor probe's output (any units).
    sample_rate_hz : float
    threshold : float, optional
        Crossing level; default halfway between the 1st and 99th percentile.
    edge : {"falling", "rising"}
        Which crossing marks the pulse (``falling``: a notch seen by a proximity probe).

    Returns
    -------
    ndarray
        Crossing times, linearly interpolated between samples, s from the first sample.

    Raises
    ------
    ValueError
        A flat channel, an unknown edge, or fewer than two pulses.
    """
    x = np.asarray(signal, dtype=np.float64)
    if edge not in ("falling", "rising"):
        raise ValueError(f"keyphasor edge {edge!r}: use 'falling' or 'rising'")
    lo, hi = np.percentile(x, [1.0, 99.0])
    span = hi - lo
    if not span > 0:
        raise ValueError("keyphasor channel is flat: no pulses to detect; check the channel or give keyphasor_times_s")
    thr = 0.5 * (lo + hi) if threshold is None else float(threshold)
    if edge == "falling":
        x, thr = -x, -thr
    hyst = 0.1 * span
    times = []
    armed = bool(x[0] < thr - hyst)
    for i in range(1, x.size):            # a pulse train is short: one pass over the crossings
        if not armed:
            armed = x[i] < thr - hyst
            continue
        if x[i - 1] < thr <= x[i]:
            frac = (thr - x[i - 1]) / (x[i] - x[i - 1])
            times.append((i - 1 + frac) / sample_rate_hz)
            armed = False
    out = np.asarray(times)
    if out.size < 2:
        raise ValueError(f"keyphasor channel: {out.size} pulse(s) found on the {edge} edge at threshold {thr:g}; "
                         "check keyphasor_edge / keyphasor_threshold_v or give keyphasor_times_s")
    return out


def _detect_format(name: str, head: bytes) -> str:
    if head.startswith(_HDF5_SIGNATURE):
        return "hdf5"
    if head.startswith(_NPY_MAGIC):
        return "npy"
    lower = name.lower()
    for fmt, endings in FORMATS.items():
        if lower.endswith(endings):
            return fmt
    stripped = head.lstrip()
    if stripped[:1] in (b"{", b"["):
        return "json"
    if _UFF_START.match(head):
        return "uff"
    if not name:
        return "csv"
    raise ValueError(f"{name}: unknown file type; send a .csv, .npy, .h5/.hdf5, .json or .uff/.unv file")


# --------------------------------------------------------------------------- formats


class _CsvSyntaxError(ValueError):
    """Text the csv module cannot split (:func:`read_recording` names the file in the message)."""


#: lines a CSV file may have beyond its samples (header, comments, blank lines)
CSV_EXTRA_LINES = 1024


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _time_factor(name: str, unit_cell: str | None = None) -> float | None:
    """Seconds per unit of a time column named ``name`` (its unit from the name, else from the unit row,
    else s), or ``None`` when ``name`` is no time column."""
    m = _TIME_NAME_RE.match(name.strip())
    if m is None:
        return None
    unit = m.group(1)
    if unit is None and unit_cell:
        unit = unit_cell.strip().strip("[]()").strip()
    if not unit:
        return 1.0
    return TIME_UNITS.get(unit.lower() if unit not in ("µs", "μs") else unit)


def _metadata(lines: list[list[str]]) -> dict[str, Any]:
    """What a collector's metadata block (``key<delimiter>value`` or ``key: value`` lines above the column
    names) says of the sample rate and the units; every other line is skipped."""
    out: dict[str, Any] = {}
    for cells in lines:
        if len(cells) == 1 and (":" in cells[0] or "=" in cells[0]):
            key, _, rest = cells[0].replace("=", ":", 1).partition(":")
            cells = [key, rest]
        key = cells[0].strip().lower()
        values = [c.strip() for c in cells[1:] if c.strip()]
        if not values:
            continue
        if key in _META_INTERVAL_KEYS or key in _META_RATE_KEYS:
            first = values[0].split()
            try:
                nums = {float(v.split()[0]) for v in values}
            except ValueError:
                continue
            if len(nums) != 1 or not all(math.isfinite(v) and v > 0 for v in nums):
                raise ValueError(f"the file's header line {cells[0].strip()!r} gives {values}: one positive "
                                 "sample interval/rate is needed (every channel sampled together)")
            v = nums.pop()
            scale = {"khz": 1e3, "hz": 1.0, "ms": 1e-3, "s": 1.0, "us": 1e-6}.get(first[1].lower(), None) \
                if len(first) > 1 else 1.0
            if scale is None:
                continue
            rate = 1.0 / (v * scale) if key in _META_INTERVAL_KEYS else v * scale
            out["sample_rate_from_header"] = (_simplest_rate(1.0 / rate) if key in _META_INTERVAL_KEYS else rate,
                                              cells[0].strip())
        elif key in _META_UNIT_KEYS:
            units = {input_unit(v) for v in values}
            if len(units) == 1 and None not in units:
                out["header_units"] = (units.pop(), cells[0].strip())
        elif key in _META_WHEN_KEYS and "recorded_at" not in out:
            when = parse_recorded_at(" ".join(values))
            if when is not None:
                out["recorded_at"] = (when, cells[0].strip())
        elif key in _META_DATE_KEYS:
            when = parse_recorded_at(values[0]) if ":" in values[0] else None
            if when is not None:
                out.setdefault("recorded_at", (when, cells[0].strip()))
            else:
                out["date_text"] = values[0]
        elif key in _META_CLOCK_KEYS:
            out["clock_text"] = values[0]
    if "recorded_at" not in out and "date_text" in out:
        when = parse_recorded_at(f"{out['date_text']} {out.get('clock_text', '00:00:00')}")
        if when is not None:
            out["recorded_at"] = (when, "Date" + (" and Time" if "clock_text" in out else ""))
    return out


def _csv_table(data: bytes, max_rows: int | None = None) -> tuple[list[str] | None, np.ndarray, dict[str, Any]]:
    """Column names, the numbers (points × columns) and what the lines above the names say.

    Collectors write a block of metadata lines above the column names (a LabVIEW .lvm header, ``Key: value``
    lines); those are skipped (their sample rate and units are kept, :func:`_metadata`). The names are the
    line just above the first row of numbers, or the one above that when that line is a unit row
    (``s, mV, mV, …``).
    """
    if max_rows is not None:             # counted on the bytes, before any line is decoded or split
        n_lines = max(data.count(b"\n"), data.count(b"\r"))
        if n_lines > max_rows + CSV_EXTRA_LINES:
            raise ValueError(f"the CSV file has more than {max_rows + CSV_EXTRA_LINES} lines; at most {max_rows} "
                             "samples (rows) are accepted: send a shorter recording")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ValueError("the CSV file is not UTF-8 text; export it as UTF-8 CSV") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError("the CSV file has no data rows; put one probe per column and one sample per row")
    last = lines[-1]                       # a data row decides the delimiter (metadata lines may hold others)
    delim = "\t" if "\t" in last else (";" if ";" in last else ",")
    try:
        rows = [r[:-1] if len(r) > 1 and not r[-1].strip() else r for r in csv.reader(lines, delimiter=delim)]
    except csv.Error as exc:             # e.g. a field over the csv module's limit, or a stray NUL byte
        raise _CsvSyntaxError(f"the CSV file cannot be read as CSV ({exc}); numbers only, one probe per column and one "
                              "sample per row") from None
    start = next((i for i, r in enumerate(rows) if all(_is_number(v) for v in r)), None)
    if start is None:                      # names, then rows whose bad value is reported below
        start = 1
    preamble, rows = rows[:start], rows[start:]
    if not rows:
        raise ValueError("the CSV file has a header but no data rows")
    width = len(rows[0])
    header: list[str] | None = None
    units_row: list[str] | None = None
    if preamble:
        header = [h.strip() for h in preamble.pop()]
        if preamble and any(_is_number(h) for h in header):
            raise ValueError(f"the CSV file has a row that is neither names nor numbers ({header!r}, line "
                             f"{len(preamble) + 1} without comments) above its first row of numbers: a value that is "
                             "not a number in a data row? numbers only, one probe per column")
        if header and header[-1].lower() == "comment" and len(header) == width + 1:
            header = header[:-1]           # LabVIEW's empty Comment column
        known = sum(1 for h in header if input_unit(h) or h.strip("[]() ").lower() in TIME_UNITS)
        if preamble and len(header) == width and 2 * known >= width and len(preamble[-1]) >= width:
            units_row, header = header, [h.strip() for h in preamble.pop()][:width]
    meta = _metadata(preamble)
    meta["skipped_lines"] = len(preamble)
    meta["units_row"] = units_row
    for k, r in enumerate(rows):
        if len(r) != width:
            raise ValueError(f"CSV data row {k + 1} has {len(r)} values but the first row has {width}; "
                             "every row needs one value per column")
    try:
        table = np.array([[float(v) for v in r] for r in rows], dtype=np.float64)
    except ValueError as exc:
        raise ValueError(f"the CSV file has a value that is not a number ({exc}); "
                         "numbers only, one probe per column") from None
    if header is not None and len(header) != width:
        raise ValueError(f"the CSV header has {len(header)} names for {width} columns")
    return header, table, meta


def _read_csv(data: bytes, opts: ReadOptions, limits: ReadLimits, notes: list[str]) -> tuple[np.ndarray, dict]:
    header, table, meta = _csv_table(data, limits.max_points)
    if table.shape[0] > limits.max_points:
        raise ValueError(f"the CSV file has {table.shape[0]} rows; at most {limits.max_points} samples are accepted")
    info: dict[str, Any] = {}
    if meta["skipped_lines"]:
        notes.append(f"{meta['skipped_lines']} metadata line(s) above the column names skipped")
    if "sample_rate_from_header" in meta:
        info["sample_rate_from_header"] = meta["sample_rate_from_header"]
    if "header_units" in meta:
        info["units"], line = meta["header_units"]
        notes.append(f"units {info['units']} from the header line {line!r}")
    if "recorded_at" in meta:
        info["recorded_at"], line = meta["recorded_at"]
        notes.append(f"recorded at {info['recorded_at']} (the header's {line!r})")
    return _named_columns(header, table, opts, info, what="the CSV file", units_row=meta["units_row"], notes=notes)


def _named_columns(header: list[str] | None, table: np.ndarray, opts: ReadOptions, info: dict[str, Any], *,
                   what: str, units_row: list[str] | None = None,
                   notes: list[str] | None = None) -> tuple[np.ndarray, dict]:
    """Channels × points and what the column names say (time column, keyphasor, layout, units).

    Shared by CSV (header row) and UFF (one function record per named channel). A column is read as a
    probe only when the layout in file order says so, when the mapping names it, or when its name is
    ``b<bearing>@<angle>``; with a mapping, the other columns are left out and a note names them.
    """
    notes = notes if notes is not None else []
    names = header or [str(k) for k in range(table.shape[1])]
    keep = list(range(table.shape[1]))
    lowered = [n.strip().lower() for n in names]
    split = [_NAME_UNIT_RE.match(n) for n in names]
    bases = [(m.group(1).strip().lower() if m else n) for m, n in zip(split, lowered)]
    col_units = [input_unit(m.group(2)) if m else None for m in split]
    if units_row is not None:
        col_units = [input_unit(u) or cu for u, cu in zip(units_row, col_units)]
    if header is not None:
        for j, n in enumerate(names):
            factor = _time_factor(n, units_row[j] if units_row is not None else None)
            if factor is None:
                if _TIME_NAME_RE.match(n.strip()):
                    raise ValueError(f"{what}: the time column {n!r} has a unit that is not a time unit; use s, ms, "
                                     "us or ns (e.g. 'Time [ms]')")
                continue
            if "sample_rate_from_time" not in info:
                info["sample_rate_from_time"] = sample_rate_from_times(table[:, j] * factor)
                info["time_column"] = n
            keep.remove(j)
    kp_js: list[int] = []
    for kp_col in keyphasor_channels(opts.keyphasor_channel):
        if isinstance(kp_col, str):
            key = kp_col.strip().lower()
            if key not in lowered and key not in bases:
                raise ValueError(f"keyphasor channel {kp_col!r} is not a column of {what} (columns: {names})")
            kp_js.append(lowered.index(key) if key in lowered else bases.index(key))
        else:
            if not 0 <= kp_col < table.shape[1]:
                raise ValueError(f"keyphasor channel {kp_col} is outside the file's columns 0..{table.shape[1] - 1}")
            kp_js.append(kp_col)
    if opts.keyphasor_channel is None and header is not None:
        kp_js = [j for j in (next((j for j, n in enumerate(bases) if n in _KP_COLUMNS), None),) if j is not None]
    if kp_js:
        info["keyphasor_signal"] = table[:, kp_js[0]] if len(kp_js) == 1 else [table[:, j] for j in kp_js]
        for j in kp_js:
            if j in keep:
                keep.remove(j)
    mapping = opts.channels if isinstance(opts.channels, Mapping) else None
    if mapping is not None:
        cols, layout = [], []
        for name, where in mapping.items():
            key = name.strip().lower()
            if key in lowered:
                j = lowered.index(key)
            elif key in bases:
                j = bases.index(key)
            else:
                raise ValueError(f"channels: column {name!r} is not a channel name of {what} (names: {names})")
            if j not in keep:
                raise ValueError(f"channels: column {name!r} is the {what}'s time or keyphasor column, not a probe")
            cols.append(j)
            layout.extend(parse_layout([where]))
        info["layout"] = layout
        left = [names[j] for j in keep if j not in cols]
        if left:
            notes.append(f"column(s) {left} are neither time, keyphasor nor in the channel mapping: not read")
        _column_units(info, [names[j] for j in cols], [col_units[j] for j in cols], what)
        return table[:, cols].T, info
    if header is not None and opts.channels is None:
        kept = [names[j] for j in keep]
        matches = [_HEADER_RE.match(n) or _LAYOUT_RE.match(n) or _LAYOUT_RE.match(bases[j]) for n, j in zip(kept, keep)]
        if all(matches):
            info["layout"] = [(int(m.group(1)), float(m.group(2))) for m in matches if m]
            suffixes = {(m.group(3) or "").lower() for m in matches if m and m.lastindex == 3}
            if len(suffixes) == 1 and "" not in suffixes:
                info["units"] = input_unit(suffixes.pop())
        else:
            bad = [n for n, m in zip(kept, matches) if not m]
            raise ValueError(f"{what}: column(s) {bad} are neither a time column (e.g. 'Time (s)', 'Time [ms]', "
                             "'t_s'), a keyphasor (kp) nor named BEARING@ANGLE like 'b2@45', so they are not read "
                             "as probes; map each probe column to its bearing and angle (CLI --channels "
                             "'GEN DE X=b2@45;GEN DE Y=b2@135', API channel_map=) or rename the columns")
    info["column_names"] = [names[j] for j in keep]
    _column_units(info, [names[j] for j in keep], [col_units[j] for j in keep], what)
    return table[:, keep].T, info


def _column_units(info: dict[str, Any], names: list[str], units: list[str | None], what: str) -> None:
    """The probes' common unit from their column names or the unit row (wins over a metadata line)."""
    given = {u for u in units if u is not None}
    if len(given) > 1:
        detail = ", ".join(f"{n!r}: {u}" for n, u in zip(names, units) if u is not None)
        raise ValueError(f"{what}: the probe columns are in different units ({detail}); export every probe in the "
                         "same units")
    if given:
        info["units"] = given.pop()


#: UFF ordinate unit labels (record 10) -> reader units
_UFF_UNITS = {"um": "um", "µm": "um", "micron": "um", "microns": "um", "micrometer": "um", "mm": "mm", "m": "m",
              "mil": "mil", "mils": "mil", "v": "V", "volt": "V", "volts": "V", "mv": "mV"}


def _decode_uff(data: bytes | Path, limits: ReadLimits
                ) -> tuple[list[str], np.ndarray, float, str | None, list[str], str | None]:
    """Time histories of a universal file (type-58 records) with pyuff; runs in the sandbox.

    Returns channel names (ID line 1, else node and direction), the points × channels table,
    the sample rate, the common ordinate unit (``None`` when unlabelled or mixed), notes, and when the
    records were made (ID line 3, the record's date and time by the format's convention, when every record
    gives the same one).
    """
    import tempfile

    import pyuff

    raw = data.read_bytes() if isinstance(data, Path) else data
    if not re.search(rb"\s-1\s*$", raw[-200:]):
        raise ValueError("the universal file does not end with a record's closing '-1' line: it is truncated; "
                         "export it again")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "upload.uff"
        path.write_bytes(raw)
        try:
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
            idx = [i for i, t in enumerate(types) if t == 58]
            if not idx:
                raise ValueError(f"the universal file has no type-58 (function at a DOF) records (types: "
                                 f"{sorted(set(types))}); export the probe time waveforms as UFF 58")
            if len(idx) > limits.max_channels + 2:
                raise ValueError(f"the universal file has {len(idx)} type-58 records; at most "
                                 f"{limits.max_channels} probes and a keyphasor are accepted")
            sets = [uff.read_sets(i) for i in idx]
        except ValueError:
            raise
        except Exception as exc:  # noqa: BLE001 - pyuff raises bare Exceptions on malformed records
            raise ValueError(f"cannot read the universal file ({exc}); export it again as UFF 58 (ASCII or 58b)") \
                from None
    names, columns, incs, units = [], [], [], set()
    for k, d in enumerate(sets):
        label = str(d.get("id1", "")).strip() or f"node {d.get('rsp_node')} dir {d.get('rsp_dir')}"
        if int(d.get("func_type", 1)) != 1 and int(d.get("abscissa_spec_data_type", 17)) != 17:
            raise ValueError(f"UFF record {k + 1} ({label!r}) is not a time history (function type "
                             f"{d.get('func_type')}); export time waveforms, not spectra")
        if int(d.get("abscissa_spacing", 1)) != 1:
            raise ValueError(f"UFF record {k + 1} ({label!r}) has uneven abscissa spacing; export evenly "
                             "sampled waveforms")
        values = np.asarray(d.get("data"))
        if np.iscomplexobj(values):
            raise ValueError(f"UFF record {k + 1} ({label!r}) holds complex values; export real time waveforms")
        if values.size > limits.max_points:
            raise ValueError(f"UFF record {k + 1} has {values.size} points; at most {limits.max_points} are accepted")
        declared = int(d.get("num_pts", values.size))
        if values.size != declared:
            raise ValueError(f"UFF record {k + 1} ({label!r}) declares {declared} points but holds {values.size} "
                             "(truncated, or a binary record whose precision does not match its header); "
                             "export it again")
        names.append(label)
        columns.append(values.astype(np.float64))
        inc = float(d.get("abscissa_inc", 0.0))
        if str(d.get("abscissa_axis_units_lab", "")).strip().lower() == "ms":
            inc *= 1e-3
        incs.append(inc)
        units.add(_UFF_UNITS.get(str(d.get("ordinate_axis_units_lab", "")).strip().lower()))
    lengths = {c.size for c in columns}
    if len(lengths) != 1:
        raise ValueError(f"the UFF records have different lengths {sorted(lengths)}; export every probe over "
                         "the same time span")
    if not all(math.isfinite(i) and i > 0 for i in incs) or max(incs) - min(incs) > 1e-9 * max(incs):
        raise ValueError(f"the UFF records' sample intervals differ or are not positive ({sorted(set(incs))} s); "
                         "export every probe at the same sample rate")
    rate_hz = _simplest_rate(incs[0])
    notes = [f"UFF 58: {len(columns)} time records; sample interval {incs[0]:.6g} s in the header -> "
             f"{rate_hz:.10g} Hz"]
    unit = units.pop() if len(units) == 1 else None
    whens = {parse_recorded_at(str(d.get("id3", ""))) for d in sets}
    when = whens.pop() if len(whens) == 1 else None
    return names, np.stack(columns, axis=1), rate_hz, unit, notes, when


def _simplest_rate(interval_s: float) -> float:
    """The sample rate with the fewest significant digits whose interval prints as ``interval_s``.

    UFF record 8 holds the interval as E13.5 (6 significant digits): 2048 Hz is written
    4.88281E-04, which read back gives 2048.001 Hz. Any rate within half a unit of the 6th
    digit is what the exporter could have meant; the one with the fewest digits is taken.
    """
    raw = 1.0 / interval_s
    half_ulp = 0.5 * 10.0 ** (math.floor(math.log10(interval_s)) - 5)
    lo, hi = 1.0 / (interval_s + half_ulp), 1.0 / (interval_s - half_ulp)
    for digits in range(1, 12):
        candidate = float(f"{raw:.{digits}g}")
        if lo <= candidate <= hi:
            return candidate
    return raw


def _read_uff(data: bytes | Path, opts: ReadOptions, limits: ReadLimits, notes: list[str]) -> tuple[np.ndarray, dict]:
    memory = limits.hdf5_memory_bytes or 3 * limits.max_hdf5_bytes + 256 * 2**20
    names, table, rate_hz, unit, uff_notes, when = call_isolated(
        _decode_uff, data, limits, memory_bytes=memory, timeout_s=limits.hdf5_timeout_s, what="the universal file")
    notes.extend(uff_notes)
    info: dict[str, Any] = {"sample_rate_hz": rate_hz}
    if when is not None:
        info["recorded_at"] = when
        notes.append(f"recorded at {when} (the UFF records' ID line 3)")
    if unit is not None:
        info["units"] = unit
    return _named_columns(names, table, opts, info, what="the UFF file", notes=notes)


def _read_npy(data: bytes, limits: ReadLimits) -> np.ndarray:
    arr = load_npy_bounded(data, max_bytes=limits.max_channels * limits.max_points * 8 + 1024)
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"the NPY array has dtype {arr.dtype}; save a float32 or float64 array")
    if arr.ndim == 3 and arr.shape[0] == 1:
        arr = arr[0]
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2:
        raise ValueError(f"the NPY array has shape {arr.shape}; save a 2-D array (channels × points)")
    return arr.astype(np.float64)


def _attr(value: Any) -> Any:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item()
    return value.item() if hasattr(value, "item") else value


def _read_hdf5(data: bytes | Path, opts: ReadOptions, limits: ReadLimits) -> tuple[np.ndarray, dict]:
    """Structure check and decoding of an HDF5 recording, isolated unless ``limits`` say otherwise."""
    if not limits.isolate_hdf5:
        return _decode_hdf5(data, opts, limits)
    memory = limits.hdf5_memory_bytes or 3 * limits.max_hdf5_bytes + 256 * 2**20
    return call_isolated(_decode_hdf5, data, opts, limits, memory_bytes=memory, timeout_s=limits.hdf5_timeout_s,
                         what="the HDF5 file")


def _decode_hdf5(data: bytes | Path, opts: ReadOptions, limits: ReadLimits) -> tuple[np.ndarray, dict]:
    import h5py

    check_hdf5(data, max_decompressed_bytes=limits.max_hdf5_bytes, max_chunk_ratio=limits.max_chunk_ratio,
               max_chunks=limits.max_hdf5_chunks)
    info: dict[str, Any] = {}
    source: Any = io.BytesIO(data) if isinstance(data, bytes) else str(data)
    try:
        with h5py.File(source, "r") as f:
            ds = f.get("waveforms")
            if not isinstance(ds, h5py.Dataset):
                raise ValueError("the HDF5 file has no dataset 'waveforms' (channels × points, or "
                                 "samples × channels × points in a rotordiag dataset file)")
            if ds.dtype.kind not in "fiu":
                raise ValueError(f"HDF5 'waveforms' has dtype {ds.dtype}; store float32 or float64 values")
            for src in (f.attrs, ds.attrs):
                for key in ("sample_rate_hz", "units", "waveform_units", "speed_rpm", "clearance_um"):
                    if key in src:
                        info["units" if key == "waveform_units" else key] = _attr(src[key])
                for key in ("recorded_at", "start_time", "timestamp"):
                    if key in src and "recorded_at" not in info:
                        when = parse_recorded_at(str(_attr(src[key])))
                        if when is not None:
                            info["recorded_at"] = when
            ch = f.get("channels")
            if isinstance(ch, h5py.Dataset) and ch.dtype.names and {"bearing", "angle_deg"} <= set(ch.dtype.names):
                if ch.shape[0] <= limits.max_channels:
                    tab = ch[()]
                    info["layout"] = [(int(b), float(a)) for b, a in zip(tab["bearing"], tab["angle_deg"])]
            elif isinstance(ch, h5py.Group) and "bearing" in ch and "angle_deg" in ch:
                b, a = ch["bearing"], ch["angle_deg"]
                if isinstance(b, h5py.Dataset) and isinstance(a, h5py.Dataset) and b.ndim == a.ndim == 1 \
                        and b.shape[0] == a.shape[0] <= limits.max_channels:
                    info["layout"] = [(int(x), float(y)) for x, y in zip(b[()], a[()])]
            if ds.ndim == 3:
                n = ds.shape[0]
                i = opts.sample_index
                if i is None:
                    if n != 1:
                        raise ValueError(f"the HDF5 file is a dataset with {n} samples; choose one with the sample "
                                         f"index (0..{n - 1})")
                    i = 0
                if not 0 <= i < n:
                    raise ValueError(f"sample index {i} is outside the file's samples 0..{n - 1}")
                if ds.shape[1] > limits.max_channels or ds.shape[2] > limits.max_points:
                    raise ValueError(f"HDF5 'waveforms' has shape {ds.shape}; at most {limits.max_channels} channels "
                                     f"of {limits.max_points} points are accepted")
                done = f.get("done")
                if isinstance(done, h5py.Dataset) and done.shape == (n,) and not bool(done[i]):
                    raise ValueError(f"sample {i} of the dataset file is not finished (its 'done' flag is false); "
                                     "choose a finished sample")
                arr = np.asarray(ds[i], dtype=np.float64)
                for key, name, scale in (("speed_rpm", "parameters/speed_rpm", 1.0),
                                         ("clearance_um", "parameters/plant/clearance_m", 1e6)):
                    d = f.get(name)
                    if isinstance(d, h5py.Dataset) and d.shape == (n,):
                        info[key] = float(d[i]) * scale
                lab = f.get("labels/misalignment")
                if isinstance(lab, h5py.Dataset) and lab.shape == (n,):
                    info["truth"] = {"misalignment": float(lab[i])}
            elif ds.ndim in (1, 2):
                if ds.size > limits.max_channels * limits.max_points:
                    raise ValueError(f"HDF5 'waveforms' has shape {ds.shape}; at most {limits.max_channels} channels "
                                     f"of {limits.max_points} points are accepted")
                arr = np.atleast_2d(np.asarray(ds[()], dtype=np.float64))
            else:
                raise ValueError(f"HDF5 'waveforms' has shape {ds.shape}; expected (channels, points)")
    except ValueError:
        raise
    except (OSError, KeyError, TypeError, RuntimeError) as exc:
        raise ValueError(f"cannot read the HDF5 file (truncated or corrupt?): {exc}") from None
    return arr, info


# --------------------------------------------------------------------------- assembly


def _mirror(layout: list[tuple[int, float]], opts: ReadOptions, notes: list[str]) -> list[tuple[int, float]]:
    if opts.rotation not in ("ccw", "cw"):
        raise ValueError(f"rotation {opts.rotation!r}: use 'ccw' or 'cw' (seen from the driver end)")
    if opts.viewed_from not in ("driver", "non-driver"):
        raise ValueError(f"viewed_from {opts.viewed_from!r}: use 'driver' or 'non-driver' (the end the probe "
                         "angles are measured from)")
    cw_in_view = (opts.rotation == "cw") == (opts.viewed_from == "driver")
    if not cw_in_view:
        return layout
    notes.append("the shaft turns clockwise seen from the end the probe angles are measured from: "
                 "angles mirrored (α → 180° − α) so that forward whirl stays forward")
    return [(b, (180.0 - a) % 360.0) for b, a in layout]


def _assemble(arr: np.ndarray, info: dict[str, Any], opts: ReadOptions, limits: ReadLimits, fmt: str,
              notes: list[str]) -> ReadResult:
    if opts.channels is not None and not isinstance(opts.channels, Mapping):
        layout = parse_layout(opts.channels)
    elif "layout" in info:
        layout = info["layout"]
    elif arr.shape[0] == len(DEFAULT_LAYOUT):
        layout = list(DEFAULT_LAYOUT)
        notes.append("no channel layout given: the 8 channels are read as b1@45, b1@135, …, b4@135")
    elif arr.shape[1] <= limits.max_channels < arr.shape[0]:
        raise ValueError(f"the array has {arr.shape[0]} rows × {arr.shape[1]} columns; one row per probe is expected "
                         "(did you send (n_points, n_channels)? transpose it, or give the channel layout)")
    else:
        n = min(arr.shape)
        raise ValueError(f"channel layout unknown for {n} channels: name the CSV columns like 'b2@45', or give the "
                         "channel layout (CLI --channels '1@45,1@135,2@45,2@135'; API bearings= and angles_deg=)")
    if arr.shape[0] != len(layout):
        if arr.shape[1] == len(layout):
            arr = arr.T                                    # points × channels
        elif info.get("column_names"):
            raise ValueError(f"the file has {arr.shape[0]} columns read as probes ({info['column_names']}) but the "
                             f"layout names {len(layout)} channels; give one BEARING@ANGLE per probe column, or map "
                             "the probe columns by name (CLI --channels 'GEN DE X=b2@45;…', API channel_map=): the "
                             "columns not mapped are then left out")
        else:
            raise ValueError(f"the file has {arr.shape[0]} channels (rows) × {arr.shape[1]} points but the layout "
                             f"names {len(layout)} channels; give one BEARING@ANGLE per channel")
    if not 1 <= arr.shape[0] <= limits.max_channels:
        raise ValueError(f"the file has {arr.shape[0]} channels; 1 to {limits.max_channels} are accepted")
    if arr.shape[1] > limits.max_points:
        raise ValueError(f"the file has {arr.shape[1]} points per channel; at most {limits.max_points} are accepted")
    layout = _mirror(layout, opts, notes)

    fs = opts.sample_rate_hz if opts.sample_rate_hz is not None else info.get("sample_rate_hz")
    header_rate = info.get("sample_rate_from_header")
    if header_rate is not None and "sample_rate_from_time" in info \
            and abs(info["sample_rate_from_time"] / header_rate[0] - 1) > 1e-3:
        raise ValueError(f"the file's header line {header_rate[1]!r} ({header_rate[0]:.6g} Hz) disagrees with its "
                         f"time column {info.get('time_column')!r} ({info['sample_rate_from_time']:.6g} Hz); "
                         "give the sample rate (sample_rate_hz) to say which is right")
    if fs is None:
        fs = info.get("sample_rate_from_time")
        if fs is not None:
            notes.append(f"sample rate {fs:.6g} Hz from the time column"
                         + (f" {info['time_column']!r}" if info.get("time_column") else ""))
        elif header_rate is not None:
            fs = header_rate[0]
            notes.append(f"sample rate {fs:.6g} Hz from the file's header line {header_rate[1]!r}")
    elif "sample_rate_from_time" in info and abs(info["sample_rate_from_time"] / float(fs) - 1) > 1e-3:
        raise ValueError(f"the sample rate given ({float(fs):g} Hz) disagrees with the time column "
                         f"({info['sample_rate_from_time']:.6g} Hz); drop one of them")
    if fs is None:
        raise ValueError("sample rate unknown: add a time column (e.g. 'Time (s)', 'Time [ms]', 't_s') or give "
                         "the sample rate in Hz (CLI --sample-rate-hz, API sample_rate_hz=)")

    units_text = str(opts.units if opts.units is not None else info.get("units", "um")).strip()
    units = input_unit(units_text) or units_text
    if units not in INPUT_UNITS:
        raise ValueError(f"units {units_text!r} not understood: use one of {list(INPUT_UNITS)} "
                         "(V and mV need the probe sensitivity, e.g. 7.87 V/mm = 200 mV/mil = 7.87 mV/um)")
    file_units = input_unit(str(info["units"])) if info.get("units") is not None else None
    if opts.units is not None and file_units is not None and file_units != units:
        notes.append(f"the file says its values are in {file_units}; read as {units}, as given")
    dc_removed = opts.dc_removed if opts.dc_removed is not None else info.get("dc_removed", False)  # Recording checks it
    declared = None
    if units in VOLTS_PER:
        if opts.sensitivity_v_per_mm is None:
            raise ValueError(f"units {units}: give the probe sensitivity (e.g. '7.87 V/mm', '200 mV/mil' or "
                             "'7.87 mV/um'; CLI --sensitivity, API sensitivity=) and the gap voltage in V")
        sens = sensitivity_v_per_mm(opts.sensitivity_v_per_mm)
        arr = np.stack([volts_to_um(row * VOLTS_PER[units], sens, opts.gap_voltage_v) for row in arr])
        declared = f"{units} at {sens:.4g} V/mm" + ("" if opts.gap_voltage_v is None
                                                    else f", gap {float(opts.gap_voltage_v):g} V")
        notes.append(f"probe voltages ({units}) converted to µm at {sens:.4g} V/mm ({sens * 25.4:.4g} mV/mil)"
                     + ("" if opts.gap_voltage_v is None else f" about the gap voltage {float(opts.gap_voltage_v):g} V"))
        units = "um"
        if opts.gap_voltage_v is None:
            dc_removed = True
            notes.append("no gap voltage given: each channel's mean voltage is taken as the gap voltage, so the "
                         "DC part is no shaft position (no centreline)")
    slow = info.get("slow_roll") or [None] * len(layout)
    channels = [ProbeChannel(bearing=b, angle_deg=a, units=units, data=arr[i], slow_roll_um_pp=slow[i],
                             declared_as=declared)
                for i, (b, a) in enumerate(layout)]

    kp: Any = opts.keyphasor_times_s
    if kp is None and "keyphasor_signal" in info:
        signals = info["keyphasor_signal"]
        many = isinstance(signals, list)     # one keyphasor channel per acquisition
        if many:
            stated = opts.acquisitions if opts.acquisitions is not None else info.get("acquisitions")
            n_takes = len(acquisitions_in_order(stated)) if stated is not None else 1
            if len(signals) != n_takes:
                raise ValueError(f"{len(signals)} keyphasor channels ({opts.keyphasor_channel}) for {n_takes} "
                                 "acquisition(s): give one keyphasor channel per acquisition, in the order the "
                                 "acquisitions are listed, with acquisitions")
        trains = [keyphasor_times_from_pulses(s, float(fs), threshold=opts.keyphasor_threshold_v,
                                              edge=opts.keyphasor_edge) for s in (signals if many else [signals])]
        kp = trains if many else trains[0]
        notes.append(f"{', '.join(str(len(k)) for k in trains)} keyphasor pulses from the "
                     + (f"{len(trains)} keyphasor channels, one per acquisition" if many else "keyphasor channel")
                     + f" ({opts.keyphasor_edge} edge)")
    if kp is not None:
        kp = parse_keyphasor_takes(kp, "keyphasor_times_s")
        n_pulses = sum(t.size for t in kp) if isinstance(kp, tuple) else kp.size
        if n_pulses > limits.max_keyphasor_pulses:
            raise ValueError(f"{n_pulses} keyphasor pulses; at most {limits.max_keyphasor_pulses} are accepted")
    speed = opts.speed_rpm if opts.speed_rpm is not None else info.get("speed_rpm")
    clearance = opts.clearance_um if opts.clearance_um is not None else info.get("clearance_um")
    if isinstance(clearance, Mapping):
        clearance = {int(k): float(v) for k, v in clearance.items()}
    speed_range = opts.speed_range_rpm if opts.speed_range_rpm is not None else info.get("speed_range_rpm")
    rec = Recording(sample_rate_hz=float(fs), channels=channels, speed_rpm=speed,
                    keyphasor_times_s=kp,
                    clearance_um=clearance,
                    speed_range_rpm=None if speed_range is None else parse_speed_range(speed_range),
                    dc_removed=dc_removed,
                    acquisitions=opts.acquisitions if opts.acquisitions is not None else info.get("acquisitions"),
                    recorded_at=info.get("recorded_at"))
    return ReadResult(recording=rec, format=fmt, notes=notes, truth=info.get("truth"))


def json_value_limit(limits: ReadLimits) -> int:
    """The most values a JSON recording within ``limits`` can hold (samples, keyphasor pulses, and a margin for the
    other fields): a JSON text with more is refused before it is decoded."""
    return limits.max_channels * limits.max_points + limits.max_keyphasor_pulses + 4096


def recording_from_dict(obj: Any, options: ReadOptions | None = None, limits: ReadLimits | None = None) -> ReadResult:
    """Recording from the JSON form (the ``/diagnose`` body, decoded).

    Raises
    ------
    ValueError
        Naming the missing or wrong field.
    """
    opts, limits = options or ReadOptions(), limits or ReadLimits()
    if not isinstance(obj, Mapping):
        raise ValueError("the JSON recording must be an object with sample_rate_hz and channels")
    chans = obj.get("channels")
    if not isinstance(chans, Sequence) or isinstance(chans, str) or not chans:
        raise ValueError("JSON: 'channels' must be a list of {bearing, angle_deg, units, data}")
    if len(chans) > limits.max_channels:
        raise ValueError(f"JSON: {len(chans)} channels; at most {limits.max_channels} are accepted")
    layout, rows, units = [], [], set()  # type: ignore[var-annotated]
    for k, c in enumerate(chans):
        if not isinstance(c, Mapping) or "data" not in c:
            raise ValueError(f"JSON: channels[{k}] needs 'bearing', 'angle_deg', 'units' and 'data'")
        layout.extend(parse_layout([c]))
        units.add(str(c.get("units", "um")))
        try:
            rows.append(np.asarray(c["data"], dtype=np.float64))
        except (TypeError, ValueError):
            raise ValueError(f"JSON: channels[{k}].data must be a list of numbers") from None
    if any(r.ndim != 1 for r in rows):
        raise ValueError("JSON: every channel's data must be a flat list of numbers")
    if len({r.size for r in rows}) != 1:
        detail = ", ".join(f"bearing {b} {a:g}°: {r.size}" for (b, a), r in zip(layout, rows))
        raise ValueError(f"JSON: the channels have different lengths ({detail}); all probes must be sampled "
                         "together — cut them to a common length")
    unit = units.pop() if len(units) == 1 else "um"
    if len(units) > 1 or unit not in INPUT_UNITS:
        for k, c in enumerate(chans):       # mixed units: each channel to µm (V is one unit for all)
            u = str(c.get("units", "um")).strip()
            if u not in UNITS_TO_UM:
                raise ValueError(f"channels[{k}].units {u!r} is not supported; use one of {list(INPUT_UNITS)} "
                                 "(mil = 25.4 µm; V needs the probe sensitivity)")
            rows[k] = rows[k] * UNITS_TO_UM[u]
        unit = "um"
    info: dict[str, Any] = {"layout": layout, "units": unit}
    slow: list[dict[int, tuple[float, float]] | None] = []
    for k, c in enumerate(chans):     # slow-roll (runout) vectors: [{order, amp_um_pp, phase_deg}] per channel
        sr = c.get("slow_roll")
        if not sr:
            slow.append(None)
            continue
        try:
            slow.append({int(v["order"]): (float(v["amp_um_pp"]), float(v["phase_deg"])) for v in sr})
        except (KeyError, TypeError, ValueError):
            raise ValueError(f"JSON: channels[{k}].slow_roll must be a list of {{order, amp_um_pp, phase_deg}}") from None
    if any(v is not None for v in slow):
        info["slow_roll"] = slow
    for key in ("sample_rate_hz", "speed_rpm", "clearance_um", "speed_range_rpm", "dc_removed", "acquisitions"):
        if obj.get(key) is not None:
            info[key] = obj[key]
    if isinstance(info.get("clearance_um"), Mapping):
        info["clearance_um"] = {int(k): v for k, v in info["clearance_um"].items()}
    if opts.keyphasor_times_s is None and obj.get("keyphasor_times_s") is not None:
        opts = replace(opts, keyphasor_times_s=obj["keyphasor_times_s"])
    res = _assemble(np.stack(rows), info, opts, limits, "json", [])
    res.asset_id, res.plant = obj.get("asset_id"), obj.get("plant")
    return res


def read_recording(source: str | Path | bytes, *, filename: str = "", options: ReadOptions | None = None,
                   limits: ReadLimits | None = None) -> ReadResult:
    """Read one recording from a file path or from a file's bytes.

    Parameters
    ----------
    source : str, Path or bytes
        A path, or the file's content (an upload).
    filename : str
        The upload's name when ``source`` is bytes (its ending picks the format when the
        content has no signature).
    options : ReadOptions, optional
        What the caller knows beyond the file; wins over the file.
    limits : ReadLimits, optional

    Returns
    -------
    ReadResult

    Raises
    ------
    ValueError
        (``UnsafeFileError`` for refused constructs) with a message that says what to fix.
    """
    opts, limits = options or ReadOptions(), limits or ReadLimits()
    if isinstance(source, (bytes, bytearray, memoryview)):
        data: bytes | None = bytes(source)
        path = None
        name = filename
    else:
        path = Path(source)
        if not path.is_file():
            raise ValueError(f"{path}: no such file")
        name = path.name
        data = None
        with path.open("rb") as fh:
            head = fh.read(16)
    if data is not None:
        head = data[:16]
        if not data:
            raise ValueError(f"{name or 'the upload'} is empty; send a CSV, NPY, HDF5 or JSON recording")
    fmt = _detect_format(name, head)
    if fmt != "hdf5" or path is None:
        size = path.stat().st_size if path is not None else len(data or b"")
        if size > limits.max_file_bytes:
            raise ValueError(f"{name}: {size} bytes; at most {limits.max_file_bytes} are accepted for a {fmt} file")
        if data is None and path is not None:
            data = path.read_bytes()
    notes: list[str] = []
    if isinstance(opts.channels, Mapping) and fmt not in ("csv", "uff"):
        raise ValueError("channels: a name mapping works for CSV and UFF files only; give the layout in file order "
                         "('1@45,1@135,...') for NPY and HDF5")
    if fmt == "json":
        return recording_from_dict(loads_json_finite(data or b"", max_values=json_value_limit(limits)), opts, limits)
    if fmt == "hdf5":
        arr, info = _read_hdf5(data if data is not None else path, opts, limits)  # type: ignore[arg-type]
    elif fmt == "npy":
        arr, info = _read_npy(data or b"", limits), {}

    else:
        arr, info = None, {}
    rows = keyphasor_channels(opts.keyphasor_channel)
    if arr is not None and rows:
        if not all(isinstance(k, int) for k in rows):
            raise ValueError(f"keyphasor channel {opts.keyphasor_channel!r}: a {fmt.upper()} file's channels have no "
                             "names; give the keyphasor channel's index (row, from 0)")
        index = [int(k) for k in rows]
        bad = [k for k in index if not 0 <= k < arr.shape[0]]
        if bad:
            raise ValueError(f"keyphasor channel {bad[0]} is outside the file's channels 0..{arr.shape[0] - 1}")
        info["keyphasor_signal"] = arr[index[0]] if len(index) == 1 else [arr[k] for k in index]
        arr = np.delete(arr, index, axis=0)
    if arr is None:  # named channels: the keyphasor is picked by name or index there
        try:
            arr, info = (_read_uff if fmt == "uff" else _read_csv)(data or b"", opts, limits, notes)
        except _CsvSyntaxError as exc:
            raise ValueError(f"{name or 'the upload'}: {exc}") from None
    if info.get("units") is not None and input_unit(str(info["units"])) is None:
        raise ValueError(f"the file's units attribute {info['units']!r} is not one of {list(INPUT_UNITS)}")
    if info.get("sample_rate_hz") is not None and not (isinstance(info["sample_rate_hz"], (int, float))
                                                       and math.isfinite(info["sample_rate_hz"])):
        raise ValueError(f"the file's sample_rate_hz attribute {info['sample_rate_hz']!r} is not a number")
    return _assemble(arr, info, opts, limits, fmt, notes)
