"""rotordiag: coupling-misalignment diagnosis for generator-exciter rotors.

This small package holds the command-line entry point and the code version;
the work lives in the top-level packages ``simulator``, ``features``,
``models`` and ``service``.
"""
from __future__ import annotations

import functools
import subprocess
from pathlib import Path

__version__ = "0.1.0"


@functools.cache
def code_version() -> str:
    """Package version plus the git commit when run from a checkout.

    Returns
    -------
    str
        ``"0.1.0"`` or ``"0.1.0+g<short-sha>"`` (``"+dirty"`` appended when the
        work tree has uncommitted changes). Recorded in datasets and model cards.
    """
    root = Path(__file__).resolve().parent.parent
    try:
        sha = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--short=10", "HEAD"],
            capture_output=True, text=True, timeout=5, check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True, text=True, timeout=5, check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return __version__
    return f"{__version__}+g{sha}" + (".dirty" if dirty else "")
