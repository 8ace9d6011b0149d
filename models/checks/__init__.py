"""The checks that doubt a verdict, one module each, every one with the same signature: a :class:`CheckContext` in,
a list of ``models.status.Reason`` out (:data:`Check`).

Why a folder: the verdict's doubts are read in one place, and a check cannot reach back into ``models.predict`` or
``models.pipeline`` (``tests/test_architecture.py`` enforces it): what a check needs of the model — the classifier's
class of other rows, their OOD score, a second reading of other features — is handed in, in the context, as
callables bound to the active model. ``bearing_sets`` (the probe set the model reads), ``acquisitions`` (bearings 2
and 3 recorded apart), ``reverse_2x`` (a coupling 2X whirling backward), ``numbering`` (bearings numbered from the
other end), ``one_position`` (a call resting on the static offset between the coupling journals), ``common_mode`` (a
1X / 2X common to every probe removed before the verdict: like ``speed_choice``, its own signature — it picks the
reading the verdict is given on and says so), ``clearance_check`` (a diametral clearance), ``family`` (a machine of a family the
model was not trained on), ``contradiction`` ("aligned" against its own 2X/1X), ``attitude`` (the journals'
attitude angles, which need no clearance, outside training when the clearance is not stated); ``speed_choice`` chooses among the
speed hypotheses a doubtful estimate allows (its own signature: it picks a reading, it gives no reason). ``startup`` (a start-up that changed since the asset's baseline start-up) has the same shape — a context in, the
reasons out — with a context of its own (``StartupContext``): it reads two stored runs and a verdict's call, not a
steady recording, and is run beside a verdict (``service.startups``, ``rotordiag report --startup``). The pipeline
that runs the others in order: ``models.pipeline``; what each was measured to do: docs/checks.md.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotordiag.features import FeatureResult, Recording

from ..status import Reason

__all__ = ["Scorer", "CheckContext", "Check"]

#: a recording's features to (OOD score, class name) with the active model: ``models.predict.ood_score_and_class``
#: bound to its bundle
Scorer = Callable[[FeatureResult], "tuple[float, str]"]


@dataclass(frozen=True)
class CheckContext:
    """What a check may read of one recording and the active model's reading of it.

    Attributes
    ----------
    fr : features.FeatureResult
        The recording's features at the speed the verdict is given at.
    names, row
        The model's feature names and this recording's row over them (bearings outside the answering probe set
        left out).
    call, aligned_band : str
        The classifier's class of ``row``, and the name of the model's aligned (lowest) band.
    band_names : sequence of str
        The classifier's classes in band order (what ``classes_of`` answers).
    ood_score : float
        The row's kNN OOD score; ``ood``: above 1, or a feature outside the training range.
    classes_of, ood_of : callable
        Rows (n, n_features) to the classifier's class names / their OOD scores, with the active model.
    score : Scorer
        Another feature result to (OOD score, class name) with the active model.
    plan : models.checks.bearing_sets.BearingPlan, optional
        How the recording's bearings are read (None: every bearing).
    recording : features.Recording, optional
        The recording itself; None when the verdict is made from given features (the checks that read the
        recording again then find nothing).
    status : str, optional
        The verdict's status before the doubts that read the recording again (``clearance_check``,
        ``attitude``); None until it is assessed.
    machine_family : str, optional
        The machine's declared family (``models.families.machine_family``: the asset's or the request's plant
        model); None when not declared.
    model_families : sequence of str
        The families the active model's card says it was trained on (``models.families.training_families``).
    envelope_of : callable, optional
        Rows (n, n_features) to the training envelope's findings per row (``MisalignmentModel.envelope_findings``).
    """

    fr: FeatureResult
    names: Sequence[str]
    row: np.ndarray
    call: str
    aligned_band: str
    ood_score: float
    ood: bool
    classes_of: Callable[[np.ndarray], list[str]]
    ood_of: Callable[[np.ndarray], np.ndarray]
    score: Scorer
    band_names: Sequence[str] = ()
    plan: Any = None
    recording: Recording | None = None
    status: str | None = None
    machine_family: str | None = None
    model_families: Sequence[str] = ()
    envelope_of: Callable[[np.ndarray], list[list[dict]]] | None = None


#: one check: a context in, the reasons it finds out (none: nothing to doubt)
Check = Callable[[CheckContext], list[Reason]]
