#!/usr/bin/env python3
"""Print a pip constraints file that pins every declared dependency to its floor.

Reads ``pyproject.toml`` ([project] dependencies and the ``dev`` extra) and prints one
``name==floor`` line per requirement (``>=X`` gives ``==X``; an ``==X`` pin is kept). Extras
are dropped (constraints cannot carry them). A requirement without a floor is an error:
every dependency must state the lowest version it was checked with.

``make test-lowest`` installs ``-e '.[dev]'`` with these constraints into a separate venv and
runs the quick tests, so a floor that does not install together with the others, or with
which the tests fail, is found. Transitive dependencies resolve to their newest versions.

Usage: ``python .ci/lowest_constraints.py [pyproject.toml] > constraints.txt`` (needs ``packaging``).
"""
from __future__ import annotations

import sys
import tomllib
from pathlib import Path

from packaging.requirements import InvalidRequirement, Requirement
from packaging.utils import canonicalize_name


def floors(pyproject: Path, extras: tuple[str, ...] = ("dev",)) -> dict[str, str]:
    """``{normalised name: floor version}`` of every requirement of the project and ``extras``.

    Raises
    ------
    SystemExit
        If a requirement has neither a ``>=`` floor nor an ``==`` pin.
    """
    project = tomllib.loads(pyproject.read_text())["project"]
    reqs = list(project["dependencies"])
    for extra in extras:
        reqs += project.get("optional-dependencies", {}).get(extra, [])
    out: dict[str, str] = {}
    for req in reqs:
        try:
            parsed = Requirement(req)
        except InvalidRequirement as exc:
            raise SystemExit(f"cannot read requirement {req!r} ({exc})") from None
        name = canonicalize_name(parsed.name)
        low = [s.version for s in parsed.specifier if s.operator in (">=", "==")]
        if len(low) != 1:
            raise SystemExit(f"requirement {req!r} needs exactly one '>=' floor or '==' pin")
        if out.get(name, low[0]) != low[0]:
            raise SystemExit(f"{name} is declared twice with different floors")
        out[name] = low[0]
    return out


def main() -> None:
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "pyproject.toml"
    for name, version in sorted(floors(path).items()):
        print(f"{name}=={version}")


if __name__ == "__main__":
    main()
