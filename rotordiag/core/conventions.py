"""Machine-train and probe conventions shared by the simulator, features and service.

Bearings are numbered along the train (MODEL.md): 1 generator far end, 2 generator
coupling end, 3 exciter coupling end, 4 exciter far end. A proximity probe at angle α
(degrees, from the +x axis towards +y in the simulator's frame) reads the journal
displacement projected on its axis, positive towards the probe.
"""
from __future__ import annotations

import numpy as np

#: bearings of the machine train, generator far end first: the paper model's four, which the feature vector covers
BEARINGS: tuple[int, ...] = (1, 2, 3, 4)
#: the highest bearing number a probe may carry: a shaft train numbers its bearings 1, 2, … along the train (a
#: three-rotor train has six); bearings beyond :data:`BEARINGS` are read and analysed but not in the feature vector
MAX_BEARING: int = 8
#: the two bearings next to the coupling (generator side, exciter side)
COUPLING_BEARINGS: tuple[int, int] = (2, 3)


def project_on_probe(x: np.ndarray, y: np.ndarray, angle_deg: float) -> np.ndarray:
    """Displacement a probe at ``angle_deg`` reads: ``x cos α + y sin α``.

    Parameters
    ----------
    x, y : ndarray
        Journal displacement components in the simulator's frame (any common unit).
    angle_deg : float
        Probe angle α in degrees.
    """
    a = np.deg2rad(float(angle_deg))
    return np.asarray(x) * np.cos(a) + np.asarray(y) * np.sin(a)


def wrap_deg(d: float | np.ndarray) -> np.ndarray:
    """An angle difference in degrees wrapped into (−180, 180], as phase differences are reported."""
    d = np.mod(np.asarray(d, dtype=float), 360.0)
    return np.where(d > 180.0, d - 360.0, d)
