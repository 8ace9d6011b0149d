"""Input containers: one probe channel and one recording, validated on construction."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from rotordiag.core.input_bounds import (
    CLEARANCE_RANGE_UM,
    MAX_DISPLACEMENT_UM,
    SAMPLE_RATE_RANGE_HZ,
    SPEED_RANGE_RPM,
    check_range,
)

from ._acquisitions import acquisitions_in_order, format_acquisitions, parse_acquisitions, parse_keyphasor_takes
from ._config import ALLOWED_UNITS, PROBE_BEARINGS, UNITS_TO_UM

__all__ = ["ProbeChannel", "Recording", "parse_speed_range"]




def parse_speed_range(value: object, name: str = "speed_range_rpm") -> tuple[float, float]:
    """``(min, max)`` running speed in r/min from two numbers or a ``"min,max"`` string.

    Raises
    ------
    ValueError
        Naming ``name``: not two finite numbers, min <= 0, or min >= max.
    """
    hint = "give the running speed's range as two numbers min,max in r/min, e.g. 2900,3100"
    if isinstance(value, str):
        value = [v.strip() for v in value.replace(";", ",").split(",")]
    if isinstance(value, (bytes, Mapping)) or not isinstance(value, Sequence) and not isinstance(value, np.ndarray):
        raise ValueError(f"{name} must be two numbers (min, max), got {value!r}; {hint}")
    if len(value) != 2:
        raise ValueError(f"{name} must be two numbers (min, max), got {len(value)}; {hint}")
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be two numbers (min, max), got {list(value)!r}; {hint}") from None
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ValueError(f"{name} must be finite, got {lo:g}, {hi:g}; {hint}")
    lo_min, hi_max = SPEED_RANGE_RPM
    if not (lo_min <= lo and hi <= hi_max):
        raise ValueError(f"{name} must lie between {lo_min:g} and {hi_max:g} r/min, got {lo:g}, {hi:g}: check the "
                         f"units; {hint}")
    if lo >= hi:
        raise ValueError(f"{name}: the minimum ({lo:g}) must be below the maximum ({hi:g}); {hint}")
    return lo, hi


def _slow_roll(value: object, bearing: int, angle: float) -> dict[int, tuple[float, float]]:
    where = f"ProbeChannel.slow_roll_um_pp (bearing {bearing}, {angle:g}°)"
    if not isinstance(value, Mapping):
        raise ValueError(f"{where} must map an order (1 or 2) to (amplitude µm pk-pk, phase lag deg)")
    out: dict[int, tuple[float, float]] = {}
    for k, v in value.items():
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or int(k) not in (1, 2):
            raise ValueError(f"{where}: order {k!r} is not 1 or 2")
        try:
            a, ph = (float(x) for x in v)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            raise ValueError(f"{where}: order {k} needs (amplitude µm pk-pk, phase lag deg), got {v!r}") from None
        if not (np.isfinite(a) and np.isfinite(ph) and a >= 0):
            raise ValueError(f"{where}: order {k} amplitude must be finite and >= 0 and the phase finite, got {v!r}")
        out[int(k)] = (a, ph)
    return out


@dataclass(frozen=True)
class ProbeChannel:
    """One proximity-probe waveform.

    Parameters
    ----------
    bearing : int
        Bearing number along the train, 1 … ``MAX_BEARING`` (8): the paper model's 1 generator far end,
        2 generator coupling end, 3 exciter coupling end, 4 exciter far end; a shaft train with more bearings
        goes on numbering (their features are in :attr:`FeatureResult.bearings`, not in the vector of 1–4).
    angle_deg : float
        Mounting angle of the probe, degrees from horizontal +x toward vertical +y
        (counter-clockwise, the direction the shaft turns). A probe reads the shaft
        displacement ``d`` projected on its axis: ``d · (cos θ, sin θ)``.
    units : str
        ``"um"``, ``"mm"``, ``"m"`` or ``"mil"`` (1 mil = 25.4 µm); ``"µm"`` is accepted for ``"um"``.
    data : array_like, shape (n_points,)
        Samples at the recording's sample rate, first sample at t = 0.
    slow_roll_um_pp : mapping {order: (amplitude µm pk-pk, phase lag deg)}, optional
        Slow-roll (runout) vectors of this probe for orders 1 and/or 2, measured at slow roll
        with the same keyphasor reference (phase lag φ: the kX component is
        ``A/2 · cos(kθ − φ)``). They are subtracted as vectors from the fitted orders
        (needs ``Recording.keyphasor_times_s``).
    declared_as : str, optional
        How the file stated the values before the reader converted them to ``units`` (e.g.
        ``"V at 7.87 V/mm, gap -10 V"``), so that a units check names what the user declared.
    """

    bearing: int
    angle_deg: float
    units: str
    data: np.ndarray = field(repr=False)
    slow_roll_um_pp: Mapping[int, tuple[float, float]] | None = None
    declared_as: str | None = None

    def __post_init__(self) -> None:
        b = self.bearing
        if isinstance(b, bool) or not isinstance(b, (int, np.integer)) or int(b) not in PROBE_BEARINGS:
            raise ValueError(f"ProbeChannel.bearing must be a bearing number 1–{PROBE_BEARINGS[-1]} along the train "
                             f"(1 generator far end, 4 exciter far end on a generator–exciter pair), got {b!r}")
        object.__setattr__(self, "bearing", int(b))
        try:
            angle = float(self.angle_deg)
        except (TypeError, ValueError):
            raise ValueError(f"ProbeChannel.angle_deg must be a number of degrees, got {self.angle_deg!r}") from None
        if not np.isfinite(angle):
            raise ValueError(f"ProbeChannel.angle_deg must be finite, got {self.angle_deg!r}")
        object.__setattr__(self, "angle_deg", angle)
        if not isinstance(self.units, str) or self.units.strip() not in UNITS_TO_UM:
            raise ValueError(f"ProbeChannel.units {self.units!r} (bearing {b}) is not supported; "
                             f"use one of {list(ALLOWED_UNITS)} (mil = 25.4 µm)")
        object.__setattr__(self, "units", self.units.strip())
        try:
            data = np.asarray(self.data, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"ProbeChannel.data (bearing {b}, {angle:g}°) must be a numeric 1-D array") from None
        if data.ndim != 1:
            raise ValueError(f"ProbeChannel.data (bearing {b}, {angle:g}°) must be 1-D, got shape {data.shape}")
        if data.size < 2:
            raise ValueError(f"ProbeChannel.data (bearing {b}, {angle:g}°) has {data.size} samples; "
                             "record at least 8 shaft revolutions")
        bad = ~np.isfinite(data)
        if bad.any():
            first = int(np.argmax(bad))
            raise ValueError(f"ProbeChannel.data (bearing {b}, {angle:g}°) has {int(bad.sum())} non-finite "
                             f"sample(s) (NaN/inf), first at index {first}; remove dropouts or cut the record")
        peak_um = float(np.max(np.abs(data))) * UNITS_TO_UM[self.units]
        if peak_um > MAX_DISPLACEMENT_UM:
            raise ValueError(f"ProbeChannel.data (bearing {b}, {angle:g}°) reaches {peak_um:.3g} µm; displacements "
                             f"beyond {MAX_DISPLACEMENT_UM:g} µm are no shaft motion: check the units "
                             f"({self.units!r} was given)")
        object.__setattr__(self, "data", data)
        if self.slow_roll_um_pp is not None:
            object.__setattr__(self, "slow_roll_um_pp", _slow_roll(self.slow_roll_um_pp, b, angle))

    def slow_roll_coeffs_um(self) -> dict[int, complex]:
        """The slow-roll vectors as complex zero-to-peak coefficients ``C_k = A/2 · e^{−jφ}`` (µm)."""
        return {k: 0.5 * a * np.exp(-1j * np.deg2rad(ph)) for k, (a, ph) in (self.slow_roll_um_pp or {}).items()}

    @property
    def data_um(self) -> np.ndarray:
        """The samples in µm."""
        return self.data * UNITS_TO_UM[self.units]


@dataclass(frozen=True)
class Recording:
    """Probe waveforms of one or more bearings, sampled together (or in the takes ``acquisitions`` states).

    Parameters
    ----------
    sample_rate_hz : float
        Sampling rate of every channel.
    channels : sequence of ProbeChannel
        Two probes (an x/y pair at distinct angles) per bearing present; all the same length.
    speed_rpm : float, optional
        Running speed. Used when no keyphasor is given; otherwise the speed is estimated
        from the signal.
    keyphasor_times_s : array_like or sequence of array_like, optional
        Once-per-revolution pulse times (s, same clock as the samples: the first sample is
        at t = 0). Gives the speed revolution by revolution and the phase reference. With
        ``acquisitions``, one train per acquisition (in the order listed, each on its own take's clock): every
        take's orders are then referenced to the same notch, so the phases across takes are measured
        (``features._takes``).
    clearance_um : float or mapping {bearing: float}, optional
        Radial bearing clearance; enables the ``*_per_c`` features.
    speed_range_rpm : (float, float), optional
        What the operator knows of the running speed without measuring it (the machine's nominal
        speed: a grid-synchronous generator runs at 1500/1800/3000/3600 r/min): when the speed is
        estimated from the signal, only candidates in [min, max] are considered. A given
        ``speed_rpm`` must lie inside it; a keyphasor's speed is not restricted.
    dc_removed : bool, default False
        The channels carry no DC part that is a shaft position: AC-coupled acquisition, or each
        channel's mean removed (the reader sets it for a V recording without its gap voltage). The
        shaft-centreline features are then missing. Channels whose means are all zero (within
        ``DC_REMOVED_MAX_REL`` of the largest peak-to-peak) are read so without it.
    acquisitions : str or sequence of sequences of int, optional
        Groups of bearings sampled together when the channels come from separate acquisitions (takes), e.g.
        ``"1,2;3,4"`` or ``[[1, 2], [3, 4]]``: the phase differences between bearings of different groups are
        then not measured (``features._acquisitions``). Bearings listed but not recorded are ignored; every
        recorded bearing must be in a group. None (default), or one group: all channels sampled together.
        With more than one group, ``keyphasor_times_s`` takes one pulse train per acquisition: one train cannot
        reference two takes.
    recorded_at : str, optional
        When the recording was made (ISO 8601; no offset means UTC), as the file's header gives it: orders an
        asset's trend. Not used by the diagnosis.
    """

    sample_rate_hz: float
    channels: Sequence[ProbeChannel]
    speed_rpm: float | None = None
    keyphasor_times_s: np.ndarray | tuple[np.ndarray, ...] | None = None
    clearance_um: float | Mapping[int, float] | None = None
    speed_range_rpm: tuple[float, float] | None = None
    dc_removed: bool = False
    acquisitions: Sequence[Sequence[int]] | str | None = None
    recorded_at: str | None = None

    def __post_init__(self) -> None:
        fs = check_range(self.sample_rate_hz, "Recording.sample_rate_hz", SAMPLE_RATE_RANGE_HZ, "Hz",
                         "give the sampling rate in Hz")
        object.__setattr__(self, "sample_rate_hz", fs)
        if not isinstance(self.dc_removed, (bool, np.bool_)):
            raise ValueError(f"Recording.dc_removed must be true or false, got {self.dc_removed!r}")
        object.__setattr__(self, "dc_removed", bool(self.dc_removed))
        chans = tuple(self.channels) if not isinstance(self.channels, ProbeChannel) else (self.channels,)
        if not chans:
            raise ValueError("Recording.channels is empty; give an x/y probe pair for at least one bearing")
        for i, c in enumerate(chans):
            if not isinstance(c, ProbeChannel):
                raise ValueError(f"Recording.channels[{i}] must be a ProbeChannel, got {type(c).__name__}")
        lengths = {c.data.size for c in chans}
        if len(lengths) > 1:
            detail = ", ".join(f"bearing {c.bearing} {c.angle_deg:g}°: {c.data.size}" for c in chans)
            raise ValueError(f"Recording.channels have different lengths ({detail}); "
                             "all probes must be sampled together — cut them to a common length")
        by_bearing: dict[int, list[ProbeChannel]] = {}
        for c in chans:
            by_bearing.setdefault(c.bearing, []).append(c)
        for b, cs in sorted(by_bearing.items()):
            if len(cs) != 2:
                raise ValueError(f"bearing {b} has {len(cs)} probe(s); each bearing needs exactly two "
                                 "(an x/y pair, e.g. at 45° and 135°) — add the missing probe or drop the bearing")
            gap = np.deg2rad(cs[1].angle_deg - cs[0].angle_deg)
            if abs(np.sin(gap)) < np.sin(np.deg2rad(30.0)):
                raise ValueError(f"bearing {b}: probes at {cs[0].angle_deg:g}° and {cs[1].angle_deg:g}° are "
                                 "(nearly) parallel; the pair must be at least 30° from parallel "
                                 "(typically 90° apart) to resolve x and y")
        object.__setattr__(self, "channels", chans)
        raw_acquisitions = self.acquisitions
        acquisitions = self._acquisitions(sorted(by_bearing))
        object.__setattr__(self, "acquisitions", acquisitions)
        if self.speed_rpm is not None:
            object.__setattr__(self, "speed_rpm", check_range(
                self.speed_rpm, "Recording.speed_rpm", SPEED_RANGE_RPM, "r/min",
                "give the running speed in r/min or leave it None"))
        if self.speed_range_rpm is not None:
            rng = parse_speed_range(self.speed_range_rpm, "Recording.speed_range_rpm")
            object.__setattr__(self, "speed_range_rpm", rng)
            if self.speed_rpm is not None and not rng[0] <= self.speed_rpm <= rng[1]:
                raise ValueError(f"Recording.speed_rpm {self.speed_rpm:g} lies outside speed_range_rpm "
                                 f"{rng[0]:g}–{rng[1]:g} r/min; correct one of them (or leave the range out)")
        if self.keyphasor_times_s is not None:
            kp = parse_keyphasor_takes(self.keyphasor_times_s, "Recording.keyphasor_times_s")
            if isinstance(kp, tuple):
                kp = self._keyphasor_by_take(kp, raw_acquisitions, sorted(by_bearing))
            elif acquisitions is not None:
                raise ValueError(
                    f"Recording.keyphasor_times_s with bearings in {len(acquisitions)} acquisitions "
                    f"({format_acquisitions(acquisitions)}): one pulse train cannot reference takes whose start times are not "
                    "related. Give one pulse train per acquisition (each on its take's clock, in the order the "
                    "acquisitions are listed), or leave the keyphasor out (the speed is then given or estimated)")
            object.__setattr__(self, "keyphasor_times_s", kp)
            if isinstance(kp, tuple) and any(c.slow_roll_um_pp for c in chans):
                raise ValueError("slow_roll_um_pp with one keyphasor per acquisition is not supported; send each "
                                 "acquisition as its own recording with its slow-roll vectors")
        if any(c.slow_roll_um_pp for c in chans) and self.keyphasor_times_s is None:
            raise ValueError("slow_roll_um_pp: slow-roll vectors are phase-referenced to the keyphasor; give "
                             "keyphasor_times_s with them (without a keyphasor the phase of the orders is arbitrary "
                             "and a vector subtraction would add runout instead of removing it)")
        cl = self.clearance_um
        if cl is not None:
            if isinstance(cl, Mapping):
                clean = {}
                for b, v in cl.items():
                    if isinstance(b, bool) or not isinstance(b, (int, np.integer)) or int(b) not in PROBE_BEARINGS:
                        raise ValueError(f"Recording.clearance_um: key {b!r} is not a bearing number "
                                         f"1–{PROBE_BEARINGS[-1]}")
                    clean[int(b)] = check_range(v, f"Recording.clearance_um[{b}]", CLEARANCE_RANGE_UM, "µm",
                                           "radial clearance in µm")
                object.__setattr__(self, "clearance_um", clean)
            else:
                object.__setattr__(self, "clearance_um", check_range(
                    cl, "Recording.clearance_um", CLEARANCE_RANGE_UM, "µm", "radial bearing clearance in µm, or None"))

    def _acquisitions(self, bearings: list[int]) -> tuple[tuple[int, ...], ...] | None:
        if self.acquisitions is None:
            return None
        groups = parse_acquisitions(self.acquisitions, "Recording.acquisitions")
        kept = tuple(g for g in (tuple(b for b in grp if b in bearings) for grp in groups) if g)
        missing = sorted(set(bearings) - {b for g in kept for b in g})
        if missing:
            raise ValueError(f"Recording.acquisitions {format_acquisitions(groups)!r}: bearing {missing[0]} is recorded "
                             "but in no acquisition; add it to the group it was sampled with (or leave acquisitions out "
                             "when every channel was sampled together)")
        return kept if len(kept) > 1 else None

    @staticmethod
    def _keyphasor_by_take(trains: tuple[np.ndarray, ...], raw_acquisitions: object,
                           bearings: list[int]) -> np.ndarray | tuple[np.ndarray, ...]:
        """Pulse trains given one per acquisition (in the order listed) → one per recorded group, in
        :attr:`acquisition_groups` order (a single array when one group is recorded)."""
        if raw_acquisitions is None:
            raise ValueError(f"Recording.keyphasor_times_s: {len(trains)} pulse train(s), one per acquisition, but no "
                             "acquisitions; they go with Recording.acquisitions (e.g. \"1,2;3,4\"), and channels "
                             "sampled together take one train: a 1-D array of pulse times")
        groups = acquisitions_in_order(raw_acquisitions, "Recording.acquisitions")
        if len(groups) != len(trains):
            raise ValueError(f"Recording.keyphasor_times_s: {len(trains)} pulse trains for {len(groups)} acquisitions "
                             f"({format_acquisitions(groups)}); give one per acquisition, in the order they are listed")
        kept = [(g, k) for g, k in sorted(zip(groups, trains), key=lambda p: p[0]) if set(g) & set(bearings)]
        return kept[0][1] if len(kept) == 1 else tuple(k for _, k in kept)

    @property
    def keyphasor_takes(self) -> tuple[np.ndarray, ...] | None:
        """One keyphasor pulse train per acquisition (:attr:`acquisition_groups` order, each on its take's clock)
        when given so; None for one train or none."""
        kp = self.keyphasor_times_s
        return kp if isinstance(kp, tuple) else None

    @property
    def acquisition_groups(self) -> tuple[tuple[int, ...], ...]:
        """The validated :attr:`acquisitions`: groups of bearings sampled together, ``()`` when every channel was."""
        return cast("tuple[tuple[int, ...], ...]", self.acquisitions or ())

    @property
    def n_points(self) -> int:
        """Samples per channel."""
        return int(self.channels[0].data.size)

    @property
    def bearings(self) -> tuple[int, ...]:
        """Bearings present, ascending."""
        return tuple(sorted({c.bearing for c in self.channels}))

    def clearance_for(self, bearing: int) -> float:
        """Radial clearance of ``bearing`` in µm, NaN when unknown."""
        cl = self.clearance_um
        if cl is None:
            return float("nan")
        if isinstance(cl, Mapping):
            return float(cl.get(bearing, float("nan")))
        return float(cl)

    def xy_um(self, bearing: int, out: np.ndarray | None = None) -> np.ndarray:
        """Horizontal and vertical displacement (µm) of ``bearing`` from its probe pair.

        Solves ``p_i = x cos θ_i + y sin θ_i`` for the two probes. Returns shape (2, n_points)
        (rows x, y), written into ``out`` when given.
        """
        pair = [c for c in self.channels if c.bearing == bearing]
        if len(pair) != 2:
            raise ValueError(f"bearing {bearing} is not in this recording (bearings: {list(self.bearings)})")
        th1, th2 = np.deg2rad(pair[0].angle_deg), np.deg2rad(pair[1].angle_deg)
        det = np.sin(th2 - th1)              # of [[cos θ1, sin θ1], [cos θ2, sin θ2]]
        u1, u2 = UNITS_TO_UM[pair[0].units], UNITS_TO_UM[pair[1].units]
        # inverse projection with the unit factors folded in
        a11, a12 = np.sin(th2) / det * u1, -np.sin(th1) / det * u2
        a21, a22 = -np.cos(th2) / det * u1, np.cos(th1) / det * u2
        if out is None:
            out = np.empty((2, self.n_points))
        p1, p2 = pair[0].data, pair[1].data
        np.multiply(p1, a11, out=out[0])
        out[0] += a12 * p2
        np.multiply(p1, a21, out=out[1])
        out[1] += a22 * p2
        return out

    def xy_all_um(self) -> np.ndarray:
        """x and y displacement (µm) of every bearing present, shape (2 × n_bearings, n_points): rows x, y of
        each bearing in :attr:`bearings` order (:meth:`xy_um`)."""
        data = np.empty((2 * len(self.bearings), self.n_points))
        for i, b in enumerate(self.bearings):
            self.xy_um(b, out=data[2 * i:2 * i + 2])
        return data
