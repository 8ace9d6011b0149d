"""A verdict in the engineer's length units (µm or mils), the same for the CLI and the API.

The verdict is computed in µm (:func:`rotordiag.models.pipeline.diagnose_recording`); this turns a
finished verdict dict into ``units`` without recomputing anything: every µm-named field is
renamed and converted (:func:`rotordiag.core.units.lengths_in`: ``offset_um`` →
``offset_mil``, ``b2_1x_major_um_pp`` → ``b2_1x_major_mil_pp``), the top features' values
and references follow their renamed feature, the baseline comparison's quantities are converted by their
stated unit, and the evidence texts and warnings are rendered again from their typed values
(:class:`rotordiag.core.notes.Measured`, :class:`~rotordiag.core.notes.Note`: lengths carried as numbers in µm) —
never by reading a number out of a sentence. The headline (:mod:`rotordiag.models.headline`) is made here too, in
the same units, so that every door opens its answer with it. Peak-to-peak vs 0-peak stays in the names (``_pp``).
"""
from __future__ import annotations

import copy
from typing import Any

from rotordiag.core.notes import Measured, Note
from rotordiag.core.units import UM_PER_MIL, lengths_in, um_to

from .headline import headline_dict

__all__ = ["verdict_in_units", "with_typed_texts", "revive_typed_texts", "TYPED_TEXTS_KEY"]

#: the key of a stored verdict that keeps its texts' typed values (:func:`with_typed_texts`)
TYPED_TEXTS_KEY = "typed_texts"


def _typed_places(verdict: dict[str, Any]):
    """(section, index, field, value) of every text that carries typed values: evidence values, reason
    messages, warnings."""
    for i, ev in enumerate(verdict.get("evidence") or []):
        if isinstance(ev, dict) and isinstance(ev.get("value"), Measured):
            yield "evidence", i, "value", ev["value"]
    for i, r in enumerate(verdict.get("reasons") or []):
        if isinstance(r, dict) and isinstance(r.get("message"), Measured):
            yield "reasons", i, "message", r["message"]
    for i, w in enumerate(verdict.get("warnings") or []):
        if isinstance(w, Note | Measured):
            yield "warnings", i, None, w


def with_typed_texts(verdict: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``verdict`` (µm) for storage as JSON: its texts stay as they are (µm), and ``typed_texts`` keeps
    the typed values of each (:func:`rotordiag.core.notes.typed_to_json`), so a stored verdict can be given in
    mils later (:func:`revive_typed_texts`, then :func:`verdict_in_units`) without reading numbers out of
    sentences."""
    from rotordiag.core.notes import typed_to_json

    typed: dict[str, dict[str, Any]] = {}
    for section, i, _, value in _typed_places(verdict):
        typed.setdefault(section, {})[str(i)] = typed_to_json(value)
    return {**verdict, TYPED_TEXTS_KEY: typed} if typed else dict(verdict)


def revive_typed_texts(stored: dict[str, Any]) -> dict[str, Any]:
    """A stored verdict with its texts typed again (the inverse of :func:`with_typed_texts`; a verdict stored
    before typed texts were kept comes back as it is, its texts in µm). A typed entry whose text no longer
    matches the stored text is left as stored."""
    from rotordiag.core.notes import typed_from_json

    typed = stored.get(TYPED_TEXTS_KEY)
    out = {k: v for k, v in stored.items() if k != TYPED_TEXTS_KEY}
    if not isinstance(typed, dict):
        return out
    for section, field_ in (("evidence", "value"), ("reasons", "message"), ("warnings", None)):
        items = list(out.get(section) or [])
        for key, data in (typed.get(section) or {}).items():
            try:
                i = int(key)
                obj = typed_from_json(data)
            except (TypeError, ValueError):
                continue
            if not 0 <= i < len(items):
                continue
            if field_ is None:
                if items[i] == str(obj):
                    items[i] = obj
            elif isinstance(items[i], dict) and items[i].get(field_) == str(obj):
                items[i] = {**items[i], field_: obj}
        if items:
            out[section] = items
    return out


def verdict_in_units(verdict: dict[str, Any], units: str) -> dict[str, Any]:
    """``verdict`` with its lengths in ``units`` and ``output_units`` set.

    Parameters
    ----------
    verdict : dict
        A verdict as returned by ``diagnose(...)`` / the API (lengths in µm).
    units : {"um", "mil"}

    Returns
    -------
    dict
        A new dict (``verdict`` is not changed).

    Raises
    ------
    ValueError
        For units other than µm or mil.
    """
    um_to(None, units)
    key_units = "mil" if units.strip().lower().startswith("mil") else "um"
    head = headline_dict(verdict, units=key_units) if "status" in verdict else None
    if key_units == "um":
        return {**verdict, "output_units": "um", **({"headline": head} if head else {})}
    out = lengths_in(copy.deepcopy(verdict), "mil")
    for item in out.get("top_features") or []:
        name = item.get("name")
        if isinstance(name, str):
            renamed = lengths_in({name: [item.get("value"), item.get("reference")]}, "mil")
            (new_name, (value, reference)), = renamed.items()
            item.update(name=new_name, value=value, reference=reference)
    for ev in out.get("evidence") or []:
        text = ev.get("value")
        if isinstance(text, Measured):
            if ev.get("number") is not None and text.leads_with_length:
                ev["number"] = ev["number"] / UM_PER_MIL
            ev["value"] = text.render("mil")
    for r in out.get("reasons") or []:
        if isinstance(r, dict) and isinstance(r.get("message"), Measured):
            r["message"] = r["message"].render("mil")
    if out.get("warnings"):
        out["warnings"] = [w.render("mil") if isinstance(w, Note) else w for w in out["warnings"]]
    base = out.get("baseline")
    if isinstance(base, dict):
        for q in (base.get("quantities") or {}).values():
            if isinstance(q, dict) and str(q.get("unit", "")).startswith("µm"):
                for k in ("value", "threshold", "alert", "danger"):
                    if isinstance(q.get(k), int | float):
                        q[k] = q[k] / UM_PER_MIL
                q["unit"] = "mil" + str(q["unit"])[2:]
    d = out.get("direction")
    if isinstance(d, dict) and d.get("estimated") and d.get("unit") == "um":
        from .direction import direction_text

        d["text"] = direction_text(d, "mil")
        for comp in (d["horizontal"], d["vertical"]):
            comp["value"] = comp["value"] / UM_PER_MIL
            comp["interval"] = [x / UM_PER_MIL for x in comp["interval"]]
        d["unit"] = "mil"
    if head:
        out["headline"] = head
    out["output_units"] = "mil"
    return out
