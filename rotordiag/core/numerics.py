"""Tunables of the compiled kernels, in one place (STUMPY's pattern).

``cache=True`` writes the compiled machine code next to the sources so a second
process does not recompile; ``error_model="numpy"`` makes a division by zero in
a trial Runge–Kutta stage give inf/NaN (which the step control rejects) instead
of raising; ``fastmath`` stays off so results are bit-reproducible and IEEE
semantics (NaN checks) hold.
"""
NUMBA_OPTIONS: dict = dict(cache=True, error_model="numpy", fastmath=False, nogil=True)

#: Default absolute tolerance on the non-dimensional state (MODEL.md section 5).
DEFAULT_ATOL: float = 1e-8
#: Default relative tolerance (the paper's 1e-6).
DEFAULT_RTOL: float = 1e-6
#: Safety cap on integrator steps per revolution before a run is declared diverged.
MAX_STEPS_PER_REV: int = 200_000
