"""The machine families a model was trained on, and the family of the machine a recording comes from.

A family is a plant and the way it was simulated: ``lumped:default`` (MODEL.md's 11-DOF plant),
``lumped:preset:gen600_2pole`` (a preset's shaft line reduced to the 11-DOF model), ``train:preset:gen600_2pole``
(the preset's finite-element shaft train), ``lumped:shaftline:<fingerprint>`` (a user's shaft-line tables). The
card records them at training time (:func:`families_of_specs`, ``training_families``); a card made before that
has them derived from its training specs (:func:`training_families`), which the card keeps.

A machine's family (:func:`machine_family`) is what the asset or the request declares: ``default``, a preset's name,
or a shaft line; it may name the simulation too (``train:gen600_2pole``: a finite-element train of that preset,
what ``benchmarks/train_verdict.py`` diagnoses). A declared machine is matched by its plant, and by the simulation
only when it names one (:func:`trained_on`): a real machine of a preset is neither simulation, and a model retrained
for that plant from its reduced shaft line is the best the product has for it.
"""
from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

__all__ = ["SIMULATIONS", "DECLARED_BY", "shaftline_key", "plant_key", "specs_of_meta", "families_of_specs",
           "training_families", "machine_family", "trained_on", "describe_family", "answered_by"]

#: how a training plant was simulated (``simulator.dataset.spec.PlantSpec.model``)
SIMULATIONS = ("lumped", "train")
#: who declared a machine's plant model (:func:`answered_by`): its asset's stored plant model, the request
#: (``?plant_model=``, a JSON body's or a batch record's ``plant_model``), ``rotordiag diagnose --plant-model``, or a
#: caller that does not say (``given``)
DECLARED_BY = ("asset", "request", "command line", "given")
_WHO = {"asset": "the asset's stored plant model", "request": "the request", "command line": "--plant-model",
        "given": "the caller"}


def shaftline_key(tables: Mapping[str, Any]) -> str:
    """``preset:NAME`` when the shaft-line tables are a preset's, else ``shaftline:`` and 12 hex digits of their
    canonical JSON's SHA-256 (the same tables give the same key whatever their key order).

    Raises
    ------
    ValueError
        Tables ``simulator.shaftline.ShaftLine.from_dict`` refuses.
    """
    from rotordiag.simulator.shaftline import PRESETS, ShaftLine, preset

    try:
        canon = ShaftLine.from_dict(dict(tables)).to_dict()
    except (TypeError, ValueError, KeyError) as exc:
        raise ValueError(f"shaft line: {exc}") from None
    text = json.dumps(canon, sort_keys=True, default=str)
    for name in PRESETS:
        if json.dumps(preset(name).to_dict(), sort_keys=True, default=str) == text:
            return f"preset:{name}"
    return "shaftline:" + hashlib.sha256(text.encode()).hexdigest()[:12]


def plant_key(plant_model: str | None = None, shaftline: Mapping[str, Any] | None = None) -> str | None:
    """The plant part of a family: ``default``, ``preset:NAME`` or ``shaftline:<fingerprint>``; None when neither
    is given. ``plant_model`` is ``default`` or a preset's name (``preset:`` in front is accepted).

    Raises
    ------
    ValueError
        Both given, an unknown preset, or shaft-line tables that cannot be read.
    """
    from rotordiag.simulator.shaftline import PRESETS

    if plant_model is not None and shaftline is not None:
        raise ValueError("plant_model and plant_shaftline: give the machine's plant one way")
    if shaftline is not None:
        return shaftline_key(shaftline)
    if plant_model is None:
        return None
    name = plant_model.strip().removeprefix("preset:")
    if name == "default":
        return "default"
    if name not in PRESETS:
        raise ValueError(f"plant_model {plant_model!r}: use default or a preset: {', '.join(sorted(PRESETS))} "
                         f"({' or '.join(f'{s}:NAME' for s in SIMULATIONS)} for a preset simulated that way)")
    return f"preset:{name}"


def _spec_families(spec: Mapping[str, Any]) -> list[str]:
    plant = dict(spec.get("plant") or {})
    sim = str(plant.get("model") or "lumped")
    keys: list[str] = []
    if plant.get("preset"):
        keys.append(f"preset:{plant['preset']}")
    presets = plant.get("presets")
    if presets:
        keys += [f"preset:{p}" for p in (presets.keys() if isinstance(presets, Mapping) else presets)]
    for sl in [plant.get("shaftline")] + list(plant.get("shaftlines") or []):
        if isinstance(sl, Mapping):
            try:
                keys.append(shaftline_key(sl))
            except ValueError:
                keys.append("shaftline:unreadable")
        elif isinstance(sl, str):
            keys.append(f"shaftline:file:{sl.rsplit('/', 1)[-1]}")
    if plant.get("file"):
        keys.append(f"file:{str(plant['file']).rsplit('/', 1)[-1]}")
    if not keys:
        keys.append("default")
    return [f"{sim}:{k}" for k in keys]


def specs_of_meta(meta: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    """The dataset specs of a feature table's ``meta``: its ``dataset_spec`` (one spec or a list), else those of the
    tables it was concatenated from (``meta["sources"]``, ``FeatureTable.concat``)."""
    found: list[Mapping[str, Any]] = []
    for m in [meta] if meta.get("dataset_spec") else list(meta.get("sources") or []):
        spec = m.get("dataset_spec") if isinstance(m, Mapping) else None
        found += [x for x in (spec if isinstance(spec, list) else [spec]) if isinstance(x, Mapping)]
    return found


def families_of_specs(specs: Mapping[str, Any] | Sequence[Mapping[str, Any]] | None) -> list[str]:
    """Every family the dataset specs (one spec or a list, as a card's ``training_data.spec``) simulate, sorted."""
    if not specs:
        return []
    items = [specs] if isinstance(specs, Mapping) else list(specs)
    return sorted({f for s in items if isinstance(s, Mapping) for f in _spec_families(s)})


def training_families(card: Mapping[str, Any] | None) -> list[str]:
    """The families a model's card says it was trained on: its ``training_families``, else derived from its training
    specs (``training_data.spec``); empty when the card says neither (the guard is then not applied)."""
    card = card or {}
    recorded = card.get("training_families")
    if isinstance(recorded, list) and recorded:
        return [str(f) for f in recorded]
    return families_of_specs((card.get("training_data") or {}).get("spec"))


def machine_family(plant_model: str | None = None, shaftline: Mapping[str, Any] | None = None) -> str | None:
    """The declared family of a machine: ``[SIMULATION:]PLANT`` (:func:`plant_key`; ``train:gen600_2pole`` names a
    finite-element train of that preset), or None when nothing is declared.

    Raises
    ------
    ValueError
        A plant that is not ``default``, a preset or readable shaft-line tables, or an unknown simulation.
    """
    sim = None
    given = plant_model
    if plant_model is not None:
        head, sep, rest = plant_model.strip().partition(":")
        if sep and head in SIMULATIONS:
            sim, plant_model = head, rest
    try:
        key = plant_key(plant_model, shaftline)
    except ValueError as exc:       # the name as the user gave it, simulation included
        raise ValueError(str(exc).replace(repr(plant_model), repr(given), 1)) from None
    if key is None:
        return None
    return f"{sim}:{key}" if sim else key


def trained_on(machine: str, families: Iterable[str]) -> bool:
    """Whether ``machine`` (:func:`machine_family`) is among ``families`` (:func:`training_families`): the same plant,
    and the same simulation when the machine names one."""
    head, sep, rest = machine.partition(":")
    sim, plant = (head, rest) if sep and head in SIMULATIONS else (None, machine)
    for fam in families:
        fsim, _, fplant = fam.partition(":")
        if fplant == plant and (sim is None or fsim == sim):
            return True
    return False


def describe_family(family: str) -> str:
    """A family in words: ``gen600_2pole (finite-element train)``, ``MODEL.md's plant (lumped 11-DOF)``."""
    head, sep, rest = family.partition(":")
    sim, plant = (head, rest) if sep and head in SIMULATIONS else (None, family)
    name = "MODEL.md's plant" if plant == "default" else plant.removeprefix("preset:")
    how = {"lumped": " (lumped 11-DOF)", "train": " (finite-element train)", None: ""}[sim]
    return name + how


def answered_by(version: str | None, card: Mapping[str, Any] | None, machine: str | None,
                declared_by: str | None = None) -> dict[str, Any]:
    """Which model answered and what the recording was judged as, for the verdict (``Verdict.answered_by``).

    Parameters
    ----------
    version : str or None
        The model's registered version.
    card : mapping or None
        Its card: the families it was trained on (:func:`training_families`) and, for a model retrained for one
        plant, that plant (``plant.name``).
    machine : str or None
        The machine's declared family (:func:`machine_family`); None when nothing was declared.
    declared_by : str, optional
        Who declared it, one of :data:`DECLARED_BY` (default ``given``); ignored when nothing was declared.

    Returns
    -------
    dict
        ``model_version``, ``training_families`` (keys) and ``training_families_text`` (in words),
        ``retrained_for`` (the plant of a per-plant model, else None), ``plant_model`` (the declared family or None),
        ``plant_model_text``, ``declared_by``, ``plant_model_trained`` (whether the model was trained on it; None
        when nothing was declared or the card records no families) and ``text``, one sentence of it all.
    """
    if declared_by is not None and declared_by not in DECLARED_BY:
        raise ValueError(f"declared_by {declared_by!r}: one of {', '.join(DECLARED_BY)}")
    families = training_families(card)
    plant = (card or {}).get("plant")
    retrained = str(plant["name"]) if isinstance(plant, Mapping) and plant.get("name") else None
    trained = None if machine is None or not families else trained_on(machine, families)
    who = (declared_by or "given") if machine is not None else None
    model = f"model {version or '(unregistered)'}" + (f", retrained for {retrained}" if retrained else "")
    model += (", trained on " + ", ".join(describe_family(f) for f in families) if families
              else ", its training families not recorded")
    if machine is None:
        judged = "no plant model declared (the asset's, ?plant_model= or --plant-model): no family check"
    else:
        judged = (f"judged as {describe_family(machine)}, declared by {_WHO[declared_by or 'given']}"
                  + {True: ", a family it was trained on", False: ", a family it was NOT trained on (never confident)",
                     None: ""}[trained])
    return {"model_version": version, "training_families": families,
            "training_families_text": [describe_family(f) for f in families], "retrained_for": retrained,
            "plant_model": machine, "plant_model_text": None if machine is None else describe_family(machine),
            "declared_by": who, "plant_model_trained": trained, "text": f"{model}; {judged}"}
