"""Test-session guards.

The four layers are imported as ``rotordiag.simulator``, ``rotordiag.features``,
``rotordiag.models`` and ``rotordiag.service``. pytest runs in ``importlib`` mode (no
``sys.path`` insertion), and this finder makes a stale bare import such as
``import models`` fail loudly instead of silently importing a second copy of the
package from the checkout's top-level folder. The checkout root is appended (last) to
``sys.path`` only so that worker processes (Dask, multiprocessing spawn) can import test
helpers as ``tests.<module>``; static bare imports anywhere in the tree are refused by
``tests/test_architecture.py``.
"""
from __future__ import annotations

import os
import sys
from importlib.abc import MetaPathFinder
from pathlib import Path

_BARE_NAMES = frozenset({"simulator", "features", "models", "service"})


class _BareImportBlocker(MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):  # noqa: ANN001 - importlib protocol
        if fullname.split(".", 1)[0] in _BARE_NAMES:
            raise ImportError(
                f"bare import {fullname!r}: import it as 'rotordiag.{fullname}' "
                "(the top-level folders are installed under the rotordiag package)"
            )
        return None


# One BLAS/OpenMP thread per test process: `make test` runs two xdist workers on two cores, and each worker's
# BLAS spreading its eigenvalue and solve calls over every core made the shaft-train tests about 20x slower
# (oversubscription). Set before NumPy loads its BLAS here and inherited by every server or worker a test starts;
# threadpoolctl holds the limit where a library was loaded earlier.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
from threadpoolctl import threadpool_limits  # noqa: E402

threadpool_limits(1)

_ROOT = str(Path(__file__).resolve().parents[1])
if _ROOT not in sys.path:
    sys.path.append(_ROOT)
if not any(isinstance(f, _BareImportBlocker) for f in sys.meta_path):
    sys.meta_path.insert(0, _BareImportBlocker())


# --- PostgreSQL (issue 47) ------------------------------------------------------------------------

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def postgres():
    """A throw-away PostgreSQL cluster (tests/pg_util.py) for the whole session.

    Skipped, with the reason, only where no server binary is installed; under CI (``CI`` set) a missing
    server fails instead, since .ci/run installs Debian's ``postgresql``."""
    from tests.pg_util import find_pg_bin, postgres_cluster

    if find_pg_bin() is None:
        reason = "no PostgreSQL server binary (initdb/pg_ctl) installed: `apt-get install -y postgresql`"
        if os.environ.get("CI"):
            pytest.fail(f"CI must run the PostgreSQL tests: {reason}")
        pytest.skip(reason)
    with postgres_cluster() as cluster:
        yield cluster


@pytest.fixture(params=["sqlite", "postgresql"])
def database_url(request, tmp_path) -> str:
    """A fresh, empty database of each backend: a SQLite file, or a new database on the session's cluster."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'store.sqlite3'}"
    return request.getfixturevalue("postgres").new_database()
