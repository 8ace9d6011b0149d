"""A verdict in the engineer's length units (µm or mils), the same for the CLI and the API.

The verdict is computed in µm (:func:`rotordiag.models.predict.diagnose`); this turns a
finished verdict dict into ``units`` without recomputing anything: every µm-named field is
renamed and converted (:func:`rotordiag.core.units.lengths_in`: ``offset_um`` →
``offset_mil``, ``b2_1x_major_um_pp`` → ``b2_1x_major_mil_pp``), the top features' values
and references follow their renamed feature, and the evidence texts and warnings are rendered
again from their typed values (:class:`rotordiag.core.notes.Measured`, :class:`~rotordiag.core.notes.Note`:
lengths carried as numbers in µm). Peak-to-peak vs 0-peak stays in the names (``_pp``).

A text that has lost its types (an answer validated by the API schema before conversion, as the batch route
does, or one read back as JSON) is converted by :func:`_mils_text`, the one place a µm amount is read from a
sentence; it goes when the API schema carries the typed values.
"""
from __future__ import annotations

import copy
import re
from typing import Any

from rotordiag.core.notes import Measured, Note
from rotordiag.core.units import UM_PER_MIL, lengths_in, um_to

__all__ = ["verdict_in_units"]

#: a number followed by µm in an evidence text ("42.1 µm pk-pk", "mean x 3.2 µm")
_UM_AMOUNT = re.compile(r"(-?\d+(?:\.\d+)?(?:e[-+]?\d+)?) µm")


def _mils_text(text: str) -> str:
    return _UM_AMOUNT.sub(lambda m: f"{float(m.group(1)) / UM_PER_MIL:.3g} mil", text)


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
    if key_units == "um":
        return {**verdict, "output_units": "um"}
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
        elif isinstance(text, str) and _UM_AMOUNT.search(text):        # untyped (see the module's docstring)
            if ev.get("number") is not None and re.match(r"\s*-?[\d.]+(?:e[-+]?\d+)? µm", text):
                ev["number"] = ev["number"] / UM_PER_MIL
            ev["value"] = _mils_text(text)
    if out.get("warnings"):
        out["warnings"] = [w.render("mil") if isinstance(w, Note) else w for w in out["warnings"]]
    out["output_units"] = "mil"
    return out
