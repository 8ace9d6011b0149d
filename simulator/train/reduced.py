"""Craig–Bampton reduction of a train: the bearing and flexible-coupling DOFs kept physical.

Boundary DOFs: x and y of every bearing station and of both nodes of every flexible coupling. The
interior is represented by its static constraint modes (the shaft's deflection when one boundary DOF
moves with the others held) and by the lowest fixed-interface modes (interior eigenvectors with every
boundary DOF held, the non-rotating mean stiffness). Every matrix of the full model — gyroscopic,
asymmetric-stiffness parts, internal damping — is projected on the same basis T: q = T p with
p = [boundary DOFs, modal coordinates].
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .fe import Assembly, TrainMatrices
from .model import TrainError

#: a reduced model keeps at most this many fixed-interface modes (the compiled kernels' budget)
MAX_MODES = 60


@dataclass(kw_only=True)
class Reduced(TrainMatrices):
    """The train on its Craig–Bampton basis ``T`` (n_dof × n_red): the :class:`Assembly`'s matrices projected."""

    assembly: Assembly
    T: np.ndarray
    boundary: np.ndarray
    n_modes: int
    #: position in p of the x DOF of each bearing (y is the next one)
    support_index: np.ndarray
    #: position in p of the x DOF of each flexible coupling's two nodes
    coupling_index: np.ndarray
    #: position in p of each unbalance node's x: unbalances act at interior nodes too, through T
    unbalance_rows: np.ndarray

    @property
    def n(self) -> int:
        return self.T.shape[1]


def reduce(asm: Assembly, n_modes: int = 12) -> Reduced:
    """Craig–Bampton model of ``asm`` with ``n_modes`` fixed-interface modes."""
    if not (0 <= n_modes <= MAX_MODES):
        raise TrainError(f"n_modes must be 0..{MAX_MODES} (got {n_modes})")
    nodes = list(asm.support_nodes)
    for a, b, *_ in asm.flexible:
        nodes += [a, b]
    bnodes = list(dict.fromkeys(int(n) for n in nodes))
    boundary = np.array([4 * n + ax for n in bnodes for ax in (0, 1)], dtype=int)
    interior = np.setdiff1d(np.arange(asm.n_dof), boundary)
    if n_modes > len(interior):
        raise TrainError(f"the train has {len(interior)} interior DOFs: ask for at most that many modes")
    Kii = asm.K[np.ix_(interior, interior)]
    Kib = asm.K[np.ix_(interior, boundary)]
    Mii = asm.M[np.ix_(interior, interior)]
    try:
        psi = -np.linalg.solve(Kii, Kib)
    except np.linalg.LinAlgError:
        raise TrainError("the shaft is not held by its bearing DOFs (a rotor floating free between couplings): "
                         "add a bearing or a coupling stiffness") from None
    nb = len(boundary)
    T = np.zeros((asm.n_dof, nb + n_modes))
    T[boundary, np.arange(nb)] = 1.0
    T[np.ix_(interior, np.arange(nb))] = psi
    if n_modes:
        w2, phi = sla.eigh(Kii, Mii, subset_by_index=[0, n_modes - 1])
        T[np.ix_(interior, np.arange(nb, nb + n_modes))] = phi

    pos = {int(n): k for k, n in enumerate(bnodes)}
    sup = np.array([2 * pos[int(n)] for n in asm.support_nodes], dtype=int)
    cpl = np.array([2 * pos[int(n)] for a, b, *_ in asm.flexible for n in (a, b)], dtype=int)
    return Reduced(**asm.projected(T), assembly=asm, T=T, boundary=boundary, n_modes=n_modes, support_index=sup,
                   coupling_index=cpl, unbalance_rows=np.array([4 * n for n in asm.unbalance_nodes], dtype=int))
