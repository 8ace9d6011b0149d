"""A machine of a family the model was not trained on: never confident.

When the machine's plant model is known (the asset's plant model, or one named in the request) and the active
model's card does not list it among its training families (``models.families``), the verdict is ``uncertain`` at
most (``family_untrained``), naming the model's families and the machine's. Why: on finite-element trains of a
family the shipped model never saw, healthy two-pole trains were called severe with confidence, their 2X from the
generator's slot asymmetry (docs/train-verdict.md); nothing in one recording separates that from a coupling's 2X.
"""
from __future__ import annotations

from collections.abc import Sequence

from ..families import describe_family, trained_on
from ..status import UNCERTAIN, Reason
from . import CheckContext

__all__ = ["family_reason", "family_check"]


def family_reason(machine_family: str | None, model_families: Sequence[str]) -> Reason | None:
    """``family_untrained`` (uncertain) when ``machine_family`` is declared and not among ``model_families`` (a card
    that records none is not judged); else None."""
    if machine_family is None or not model_families or trained_on(machine_family, model_families):
        return None
    trained = ", ".join(describe_family(f) for f in model_families)
    return Reason("family_untrained", UNCERTAIN, {"machine": describe_family(machine_family), "trained": trained})


def family_check(ctx: CheckContext) -> list[Reason]:
    """:func:`family_reason` of the context's declared machine family and the model's training families."""
    reason = family_reason(ctx.machine_family, ctx.model_families)
    return [reason] if reason is not None else []
