"""A 1X whirling backward at one bearing: a probe mistake, or what machines like this one do there?

The features' sanity check ``reverse_whirl`` flags a bearing whose 1X alone whirls backward (whirl index below
``features.REVERSE_WHIRL_INDEX``): more often a probe-order or polarity mistake than the machine, so the bearing is
left out of the model's probe set (``models.checks.bearing_sets``) and the verdict is uncertain. On some trains it is
the machine: a journal on strongly anisotropic supports between their split critical speeds whirls backward (on the
shipped four-pole trains, bearing 3 in 60 % of the training machines). This check asks the model's training: among
the :data:`N_NEIGHBOURS` training recordings nearest to this one (the OOD scorer's reference and columns, the
bearing's whirl left out of the distance), at least :data:`MIN_BACKWARD` whirl backward at that bearing → the
finding is answered (``reverse_whirl_as_trained``, a note) and the bearing read; else it stands. The measurements
behind the numbers: docs/checks.md, "A backward 1X at one bearing".
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotordiag.core.notes import Note
from rotordiag.features import REVERSE_WHIRL_INDEX

__all__ = ["N_NEIGHBOURS", "MIN_BACKWARD", "BackwardWhirl", "backward_as_trained", "answer_reverse_whirl"]

#: training recordings consulted (as many as the probe-frame check's, ``models.estimators.NEAREST_TRAINING``; the
#: checks do not import the estimators)
N_NEIGHBOURS = 20
#: … and how many of them must whirl backward at the bearing for it to be the machine's motion (machines the model
#: never saw, docs/checks.md: 97–100 % of four-pole trains' backward bearing 3 read; inverted probes taken for the
#: machine's on 1 % of paper-model plants' bearings, 3–5 % of two-pole trains', 21–26 % of four-pole trains')
MIN_BACKWARD = 3


@dataclass(frozen=True)
class BackwardWhirl:
    """How many of the nearest training recordings whirl backward at ``bearing``."""

    bearing: int
    n_backward: int
    n_neighbours: int

    @property
    def as_trained(self) -> bool:
        """Enough of them do (:data:`MIN_BACKWARD`): the backward 1X is read as the machine's."""
        return self.n_backward >= MIN_BACKWARD

    def note(self) -> Note:
        """``reverse_whirl_as_trained``."""
        return Note("reverse_whirl_as_trained", bearing=self.bearing, n_backward=self.n_backward,
                    n_neighbours=self.n_neighbours)


def backward_as_trained(model: Any, names: Sequence[str], row: np.ndarray, bearing: int) -> BackwardWhirl | None:
    """The nearest training recordings' 1X whirl at ``bearing`` for the model's feature ``row`` (``names`` its
    columns); None when the model cannot say (its OOD scorer keeps no reference, or the whirl index of that bearing
    is not one of its columns)."""
    feature = f"b{int(bearing)}_1x_whirl_index"
    if feature not in names or not hasattr(model, "training_neighbour_values"):
        return None
    values = model.training_neighbour_values(np.asarray(row, dtype=float), feature, N_NEIGHBOURS)
    if values is None or values.size == 0:
        return None
    return BackwardWhirl(int(bearing), int(np.sum(values < REVERSE_WHIRL_INDEX)), int(values.size))


def answer_reverse_whirl(model: Any, names: Sequence[str], row: np.ndarray, sanity: Sequence[Any]
                         ) -> tuple[tuple[Any, ...], list[Note]]:
    """``sanity`` without the ``reverse_whirl`` findings of bearings whose backward 1X the nearest training
    recordings share (:func:`backward_as_trained`), and a ``reverse_whirl_as_trained`` note for each."""
    kept: list[Any] = []
    notes: list[Note] = []
    for f in sanity:
        if f.code == "reverse_whirl" and f.bearing is not None:
            seen = backward_as_trained(model, names, row, f.bearing)
            if seen is not None and seen.as_trained:
                notes.append(seen.note())
                continue
        kept.append(f)
    return tuple(kept), notes
