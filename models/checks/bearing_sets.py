"""Which instrumented bearings a verdict reads: the probe sets the model was trained on, and how it does on each.

A recording is read through its **answering set**: the largest of the model's training probe sets (card:
``[augment] bearing_sets``) that it has (ties: the larger training weight). The other bearings' features are left
out (as when those probes are absent), with a warning; the evidence still shows every bearing. A bearing whose 1X
alone whirls backward (sanity ``reverse_whirl``) is not read either. No training set within the bearings →
``bearing_set_untrained`` (inconclusive); an answering set whose held-out figures (:data:`CAPABILITY_PATH`) miss
:data:`MAX_FALSE_ALARM_ANY` or :data:`MIN_MACRO_F1` → ``bearing_set_uninformative`` (inconclusive); more than
:data:`MAX_FALSE_ALARM` false alarms → ``bearing_set_weak`` (uncertain). Models without ``bearing_sets`` in their
card read every bearing. The measurements behind it: docs/checks.md.
"""
from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from rotordiag.core.notes import Note

from .._patterns import bearing_feature
from ..status import INCONCLUSIVE, UNCERTAIN, Reason
from . import CheckContext

__all__ = ["CAPABILITY_PATH", "MAX_FALSE_ALARM", "MAX_FALSE_ALARM_ANY", "MIN_MACRO_F1", "BearingPlan", "answering_set", "bearing_plan",
           "set_key", "trained_sets", "load_capability", "leave_out_bearings", "probe_sets", "bearing_set_check", "informative"]

#: held-out figures of the shipped model per probe set (``benchmarks/bench_bearing_sets.py --write``)
CAPABILITY_PATH = Path(__file__).resolve().parent.parent / "default" / "bearing_sets.json"
#: an answering set whose held-out false-alarm rate (aligned machines called misaligned) exceeds this gives no
#: confident verdict (issue 15's bound on every condition): ``bearing_set_weak``, uncertain
MAX_FALSE_ALARM = 0.10
#: … and none at all (``bearing_set_uninformative``, inconclusive) beyond this false-alarm rate …
MAX_FALSE_ALARM_ANY = 0.25
#: … or below this held-out macro-F1 over the severity bands
MIN_MACRO_F1 = 0.5



def set_key(bearings: Iterable[int]) -> str:
    """The table's key of a probe set: ``"1-2-3-4"``."""
    return "-".join(str(b) for b in sorted(bearings))


#: why a bearing with a backward 1X at it alone is not read
_BACKWARD = "the 1X whirls backward there, more often a probe-order or polarity mistake than the machine"


def _said(bearings: Sequence[int]) -> str:
    b = [str(x) for x in sorted(bearings)]
    return f"bearing {b[0]}" if len(b) == 1 else "bearings " + ", ".join(b[:-1]) + " and " + b[-1]


def trained_sets(card: Mapping[str, Any] | None) -> tuple[tuple[tuple[int, ...], float], ...] | None:
    """The probe sets the model was trained on with their weights, from its card's training configuration
    (``train_config.augment.bearing_sets``); None when the card does not say."""
    if not isinstance(card, Mapping):
        return None
    augment = (card.get("train_config") or {}).get("augment") or {}
    sets = augment.get("bearing_sets") if isinstance(augment, Mapping) else None
    if not sets:
        return None
    return tuple((tuple(sorted(int(b) for b in s["bearings"])), float(s.get("weight", 1.0))) for s in sets)


def answering_set(present: Iterable[int], trained: Sequence[tuple[tuple[int, ...], float]]) -> tuple[int, ...] | None:
    """The largest training set within ``present`` (ties: the larger weight, then the first listed); None when
    no training set lies within it."""
    have = set(present)
    fits = [(len(s), w, -i, s) for i, (s, w) in enumerate(trained) if set(s) <= have]
    return max(fits)[3] if fits else None


@lru_cache(maxsize=4)
def _read_capability(path: str) -> dict | None:
    p = Path(path)
    if not p.is_file():
        return None
    return json.loads(p.read_text(encoding="utf-8"))


def load_capability(card: Mapping[str, Any] | None, path: Path = CAPABILITY_PATH) -> dict | None:
    """The held-out figures per probe set (``{"2-3": {"n": …, "macro_f1": …, "false_alarm": …}, …}``) when the
    table at ``path`` was measured for this model (same ``version`` and ``created`` in its card), else None."""
    table = _read_capability(str(path))
    if not table or not isinstance(card, Mapping):
        return None
    model = table.get("model", {})
    if model.get("version") != card.get("version") or model.get("created") != card.get("created"):
        return None
    return dict(table.get("figures", {}))


def informative(f: Mapping[str, Any]) -> bool:
    """Whether a probe set's measured figures (its ``false_alarm`` and ``macro_f1`` on held-out plants) let the model
    give a severity from it at all (else ``bearing_set_uninformative``: no severity)."""
    return bool(f["false_alarm"] <= MAX_FALSE_ALARM_ANY and f["macro_f1"] >= MIN_MACRO_F1)


def _passes(f: Mapping[str, Any] | None) -> bool:
    return f is not None and informative(f) and f["false_alarm"] <= MAX_FALSE_ALARM


@dataclass(frozen=True)
class BearingPlan:
    """How a recording's bearings are read (:func:`bearing_plan`).

    ``present``: the bearings with probes; ``answering``: the training set the model reads (None: none fits);
    ``trained``: the model's training sets; ``table``: the held-out figures per probe set (:func:`load_capability`;
    None: not measured for this model); ``suspect``: bearings whose probes are in doubt (a 1X whirling backward
    at them alone: more often a probe-order or polarity mistake than physics), never in ``answering``."""

    present: tuple[int, ...]
    answering: tuple[int, ...] | None
    trained: tuple[tuple[int, ...], ...]
    table: Mapping[str, dict] | None = None
    suspect: tuple[int, ...] = ()

    @property
    def figures(self) -> dict | None:
        """The held-out figures of the answering set, None when not measured."""
        if self.table is None or self.answering is None:
            return None
        return self.table.get(set_key(self.answering))

    @property
    def left_out(self) -> tuple[int, ...]:
        """Bearings with probes whose features the verdict does not read."""
        keep = set(self.answering or ())
        return tuple(b for b in self.present if b not in keep)

    def _sets(self) -> str:
        return ", ".join(set_key(s) for s in self.trained)

    def warnings(self) -> list[str]:
        """The note when bearings are left out and the answering set is usable."""
        if self.answering is None or not self.left_out or any(r.status == INCONCLUSIVE for r in self.reasons()):
            return []
        f = self.figures
        fig = (f" (on held-out plants from {set_key(self.answering)}: macro-F1 {f['macro_f1']:.2f}, "
               f"false alarms {f['false_alarm']:.1%})" if f else "")
        doubt = f" ({_said(self.suspect)}: {_BACKWARD})" if self.suspect else ""
        return [Note("bearings_not_read", detail=(
            f"{_said(self.left_out)} not read by the model{doubt}: it was trained on the probe sets "
            f"{self._sets()}, and the largest of them this recording has{' without it' if self.suspect else ''} "
            f"is {set_key(self.answering)}{fig}; the evidence still shows every bearing"))]

    def reasons(self) -> list[Reason]:
        """``bearing_set_untrained`` or ``bearing_set_uninformative`` (inconclusive), ``bearing_set_weak``
        (uncertain), else none."""
        if self.answering is None:
            usable = tuple(b for b in self.present if b not in self.suspect)
            doubt = f" ({_said(self.suspect)} left out: {_BACKWARD})" if self.suspect else ""
            return [Reason("bearing_set_untrained", INCONCLUSIVE,
                           {"usable": _said(usable) if usable else "no bearing", "left_out": doubt,
                            "trained_sets": self._sets()})]
        f = self.figures
        if f is None or _passes(f):
            return []
        good = [set_key(s) for s in self.trained if _passes((self.table or {}).get(set_key(s)))]
        sets = ", ".join(good) if good else "the model was trained on"
        if informative(f):
            return [Reason("bearing_set_weak", UNCERTAIN,
                           {"bearings": _said(self.answering), "probe_set": set_key(self.answering),
                            "false_alarm": f["false_alarm"], "macro_f1": f["macro_f1"],
                            "max_false_alarm": MAX_FALSE_ALARM, "good_sets": sets})]
        via = (f" (the largest of its training sets within {_said(self.present)}"
               + (f", {_said(self.suspect)} left out: {_BACKWARD}" if self.suspect else "") + ")"
               if self.left_out else "")
        return [Reason("bearing_set_uninformative", INCONCLUSIVE,
                       {"bearings": _said(self.answering), "via": via, "probe_set": set_key(self.answering),
                        "macro_f1": f["macro_f1"], "false_alarm": f["false_alarm"], "min_macro_f1": MIN_MACRO_F1,
                        "max_false_alarm": MAX_FALSE_ALARM_ANY, "good_sets": sets})]


def bearing_plan(bundle: Any, present: Iterable[int], suspect: Iterable[int] = ()) -> BearingPlan | None:
    """How a recording with probes at ``present`` is read by ``bundle`` (a ``models.predict.ModelBundle``), the
    ``suspect`` bearings never read; None when the bundle's card does not list its training probe sets (every
    bearing is read)."""
    card = getattr(bundle, "card", None)
    trained = trained_sets(card)
    if trained is None:
        return None
    have = tuple(sorted({int(b) for b in present}))
    doubt = tuple(b for b in have if b in {int(x) for x in suspect})
    usable = tuple(b for b in have if b not in doubt)
    return BearingPlan(have, answering_set(usable, trained), tuple(s for s, _ in trained), load_capability(card),
                       doubt)


def leave_out_bearings(names: Sequence[str], row: np.ndarray, keep: Iterable[int]) -> np.ndarray:
    """``row`` with every feature of a bearing not in ``keep`` missing (``b{n}_…``, and the phase differences
    ``…_b{m}_b{n}_…`` that involve one), as in a recording without those probes."""
    keep_set = {int(b) for b in keep}
    out = np.array(row, dtype=float, copy=True)
    for j, name in enumerate(names):
        parsed = bearing_feature(name)
        if parsed is not None and not set(parsed[1]) <= keep_set:
            out[j] = np.nan
    return out


def probe_sets(card: Mapping[str, Any] | None) -> list[dict] | None:
    """What a model's card says about the probe sets it reads, for ``GET /models``: each training set with its
    held-out figures (when measured for this model) and what a recording with exactly those probes gets —
    ``"reads"``, ``"never confident"`` (``bearing_set_weak``), ``"no severity"`` (``bearing_set_uninformative``)
    or ``"not measured"``; None when the card lists no training probe sets."""
    trained = trained_sets(card)
    if trained is None:
        return None
    table = load_capability(card) or {}
    out = []
    for s, _ in trained:
        f = table.get(set_key(s))
        verdict = ("not measured" if f is None else "reads" if _passes(f) else
                   "never confident" if informative(f) else "no severity")
        out.append({"bearings": list(s), "verdict": verdict,
                    **({"macro_f1": f["macro_f1"], "false_alarm": f["false_alarm"], "n": f["n"]} if f else {})})
    return out


def bearing_set_check(ctx: CheckContext) -> list[Reason]:
    """The probe set's reasons (:meth:`BearingPlan.reasons`) of the context's plan; none without a plan."""
    return ctx.plan.reasons() if ctx.plan is not None else []
