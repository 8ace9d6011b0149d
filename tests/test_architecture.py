"""Architecture rules, checked on the source text (no imports executed).

* Layers: ``rotordiag.core`` < ``rotordiag.simulator`` < ``rotordiag.features`` <
  ``rotordiag.models`` < ``rotordiag.service`` < ``rotordiag.cli``. A module may import
  its own layer and any lower one, never a higher one (also not inside a function or a
  ``try``). ``rotordiag.core`` imports nothing of the project's other layers.
* No package module (nor example) imports another package's private (``_name``) module
  or object. Unit tests and benchmarks may test and time a package's internals directly.
* No bare ``simulator`` / ``features`` / ``models`` / ``service`` imports anywhere
  (modules, tests, benchmarks, examples), and no ``"models.x"``-style strings in code.
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: folder in the repository → import name of the package it holds
PACKAGE_DIRS = {
    "rotordiag": "rotordiag",
    "simulator": "rotordiag.simulator",
    "features": "rotordiag.features",
    "models": "rotordiag.models",
    "service": "rotordiag.service",
}
#: lowest first; a module may import only its own layer or lower ones
LAYERS = (
    "rotordiag.core",
    "rotordiag.simulator",
    "rotordiag.features",
    "rotordiag.models",
    "rotordiag.service",
    "rotordiag.cli",
)
BARE = ("simulator", "features", "models", "service")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT)
    parts = list(rel.with_suffix("").parts)
    parts[0] = PACKAGE_DIRS[parts[0]]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _package_sources() -> list[Path]:
    return sorted(p for d in PACKAGE_DIRS for p in (ROOT / d).rglob("*.py") if "__pycache__" not in p.parts)


def _all_sources() -> list[Path]:
    extra = [p for d in ("tests", "benchmarks", "examples") for p in (ROOT / d).rglob("*.py")]
    return _package_sources() + sorted(p for p in extra if "__pycache__" not in p.parts)


def _user_sources() -> list[Path]:
    """Package modules and the code that uses the packages as a user would (examples)."""
    extra = [p for d in ("examples",) for p in (ROOT / d).rglob("*.py")]
    return _package_sources() + sorted(p for p in extra if "__pycache__" not in p.parts)


def _imports(path: Path, module: str) -> list[tuple[int, str, tuple[str, ...]]]:
    """(line, absolute imported module, imported names) for every import in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_pkg = path.name == "__init__.py"
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, ()) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base[: len(base) - node.level + (1 if is_pkg else 0)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target == "rotordiag":  # ``from rotordiag import features`` imports rotordiag.features
                out += [(node.lineno, f"rotordiag.{a.name}", ()) for a in node.names]
            else:
                out.append((node.lineno, target, tuple(a.name for a in node.names)))
    return out


def _layer(module: str) -> int | None:
    for i, layer in enumerate(LAYERS):
        if module == layer or module.startswith(layer + "."):
            return i
    return None


def _package(module: str) -> str:
    """The top-level project package a module belongs to (e.g. ``rotordiag.features``)."""
    parts = module.split(".")
    return ".".join(parts[:2]) if parts[0] == "rotordiag" and len(parts) > 1 else parts[0]


def test_layers_are_respected():
    bad = []
    for path in _package_sources():
        module = _module_name(path)
        own = _layer(module)
        for line, target, _ in _imports(path, module):
            other = _layer(target)
            if own is not None and other is not None and other > own:
                bad.append(f"{path.relative_to(ROOT)}:{line}: {module} imports higher layer {target}")
            if target == "rotordiag" and module != "rotordiag" and own is not None and own < len(LAYERS) - 1:
                bad.append(f"{path.relative_to(ROOT)}:{line}: {module} imports the top package 'rotordiag'"
                           " (import what it needs from rotordiag.core)")
    assert not bad, "layer violations:\n" + "\n".join(bad)


def test_core_depends_on_nothing_of_the_project():
    for path in (ROOT / "rotordiag" / "core").rglob("*.py"):
        module = _module_name(path)
        for line, target, _ in _imports(path, module):
            assert not target.startswith("rotordiag") or target.startswith("rotordiag.core"), \
                f"{path.relative_to(ROOT)}:{line} imports {target}"


def test_no_private_imports_across_packages():
    bad = []
    for path in _user_sources():
        in_pkg = path.parts[len(ROOT.parts)] in PACKAGE_DIRS
        module = _module_name(path) if in_pkg else f"_outside.{path.stem}"
        for line, target, names in _imports(path, module):
            if not target.startswith("rotordiag"):
                continue
            same_package = in_pkg and _package(target) == _package(module)
            if same_package:
                continue
            private_parts = [p for p in target.split(".") if p.startswith("_") and not p.startswith("__")]
            private_names = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private_parts or private_names:
                bad.append(f"{path.relative_to(ROOT)}:{line}: imports private {target} {private_names or ''}")
    assert not bad, "private imports across packages:\n" + "\n".join(bad)


_BARE_IMPORT = re.compile(rf"^\s*(from|import)\s+({'|'.join(BARE)})(\.|\s|$)", re.M)
_BARE_STRING = re.compile(rf"[\"']({'|'.join(BARE)})\.(\w+)[.:]")


@pytest.mark.parametrize("pattern", ["*.py", "*.md"])
def test_no_bare_package_names(pattern):
    files = [p for p in ROOT.rglob(pattern)
             if not any(part in {".venv", ".git", "build", "__pycache__", "node_modules"} or part.startswith(".venv")
                        for part in p.relative_to(ROOT).parts)]
    bad = [f"{p.relative_to(ROOT)}:{s.count(chr(10), 0, m.start()) + 1}: {m.group(0).strip()}"
           for p in files for s in [p.read_text(encoding="utf-8", errors="replace")]
           for m in _BARE_IMPORT.finditer(s)]
    if pattern == "*.py":
        # legacy.py maps the pre-rename names on purpose (and its test checks that)
        exempt = {"test_architecture.py", "legacy.py", "test_models_legacy.py"}
        bad += [f"{p.relative_to(ROOT)}: string {m.group(0)}" for p in files if p.name not in exempt
                for m in _BARE_STRING.finditer(p.read_text(encoding="utf-8"))
                if (ROOT / m.group(1) / f"{m.group(2)}.py").exists() or (ROOT / m.group(1) / m.group(2)).is_dir()]
    assert not bad, "bare imports (use rotordiag.<package>):\n" + "\n".join(bad)


#: service modules below the API layer: they raise ``service.errors`` domain exceptions and
#: never touch the web framework (issue 11, item 5); HTTP statuses are chosen in service/api only
SERVICE_DOMAIN_MODULES = ("errors", "parsing", "work", "pool", "inference", "jobs", "store", "state", "schemas",
                          "trains")


@pytest.mark.parametrize("name", SERVICE_DOMAIN_MODULES)
def test_service_domain_modules_do_not_use_the_web_framework(name):
    tree = ast.parse((ROOT / "service" / f"{name}.py").read_text())
    used = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            used |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            used.add(node.module.split(".")[0])
    assert not used & {"fastapi", "starlette"}, (
        f"service/{name}.py imports {sorted(used & {'fastapi', 'starlette'})}: raise service.errors exceptions "
        "and let service/api/errors.py give them HTTP statuses")


def test_every_collected_test_has_its_own_node_id(request):
    """Two items with one node id run once under pytest-xdist (it schedules by node id) and are
    indistinguishable in reports; ``make test`` runs on two workers."""
    from collections import Counter

    shared = sorted(i for i, n in Counter(item.nodeid for item in request.session.items).items() if n > 1)
    assert not shared, f"tests that share a node id: {shared[:5]}"


def _runtime_imports(path: Path, module: str) -> list[tuple[int, str]]:
    """(line, imported project module) for every import in the file that runs (those under ``if TYPE_CHECKING:``
    left out); ``from package import name`` counts as an import of the submodule when ``name`` is one."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    typing_only = {id(n) for node in ast.walk(tree)
                   if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
                   for stmt in node.body for n in ast.walk(stmt)}
    known = {_module_name(p) for p in _package_sources()}
    out = []
    for line, target, names in _imports(path, module):
        if not target.startswith("rotordiag"):
            continue
        out += [(line, f"{target}.{n}") for n in names if f"{target}.{n}" in known]
        if target in known and not any(f"{target}.{n}" in known for n in names):
            out.append((line, target))
    lines_typing = {n.lineno for n in ast.walk(tree) if id(n) in typing_only and hasattr(n, "lineno")}
    return [(line, t) for line, t in out if line not in lines_typing]


def _import_graph() -> dict[str, set[str]]:
    """Project module → the project modules it imports at run time (also inside functions), packages' own
    ``__init__`` re-exports left out (importing a package's API is not a circle with its parts)."""
    graph: dict[str, set[str]] = {}
    for path in _package_sources():
        module = _module_name(path)
        if path.name == "__init__.py":
            continue
        graph[module] = {t for _, t in _runtime_imports(path, module) if t != module}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circles_between_modules():
    """No two modules of the project import each other, directly or through others, at run time — not even from
    inside a function (issue 43, item 3): a circle means neither can be read or changed alone."""
    found = _cycles(_import_graph())
    assert not found, "import circles:\n" + "\n".join(" ↔ ".join(c) for c in found)


def test_the_circle_finder_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_climbs_inside_the_service():
    """The domain modules below the API (the worker pool, inference, …) never import the API or the web page's
    modules, and the web page reads requests through ``service.api.recordings`` and the API's dependencies, not
    through another route module (issue 43, item 3)."""
    bad = []
    for path in _package_sources():
        module = _module_name(path)
        targets = [(line, t) for line, t in _runtime_imports(path, module)]
        if module.split(".")[-1] in SERVICE_DOMAIN_MODULES and module.count(".") == 2:
            bad += [f"{module}:{line} imports {t}" for line, t in targets
                    if t.startswith(("rotordiag.service.api", "rotordiag.service.web"))]
        if module.startswith("rotordiag.service.web"):
            bad += [f"{module}:{line} imports {t}" for line, t in targets if t.startswith("rotordiag.service.api.routes")]
    assert not bad, "climbs:\n" + "\n".join(bad)


#: what a check (``models/checks/``) must not import: the predictor and the modules that call the checks
CHECKS_MUST_NOT_IMPORT = ("rotordiag.models.predict", "rotordiag.models.pipeline", "rotordiag.models.estimators",
                          "rotordiag.models.compiled", "rotordiag.models.registry")


def _check_climbs() -> list[str]:
    bad = []
    for path in _package_sources():
        module = _module_name(path)
        if module.startswith("rotordiag.models.checks"):
            bad += [f"{module}:{line} imports {t}" for line, t in _runtime_imports(path, module)
                    if t.startswith(CHECKS_MUST_NOT_IMPORT)]
    return bad


def test_the_checks_do_not_import_the_predictor():
    """A check (``models/checks/*``) is given what it needs (features, the verdict, a scorer callable) and never
    imports the predictor or the pipeline that calls it (issue 43, item 1), not even from inside a function."""
    names = {_module_name(p) for p in _package_sources()}
    assert {"rotordiag.models.checks.common_mode", "rotordiag.models.checks.numbering"} <= names
    bad = _check_climbs()
    assert not bad, "checks importing the predictor:\n" + "\n".join(bad)


def test_features_classify_motion_without_the_analysis_sweeps():
    """``rotordiag.features`` uses the simulator's motion classifier, which loads no analysis sweeps."""
    import subprocess
    import sys

    code = ("import sys, rotordiag.features; "
            "print(any(m.startswith('rotordiag.simulator.analysis') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "False", out.stdout + out.stderr


def test_the_modules_docs_architecture_names_exist():
    """docs/architecture.md stays true to the code: every file or folder it names in backticks (``models/x.py``)
    and every dotted module (``rotordiag.models.x``) exists (issue 43, item 4)."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    paths = set(re.findall(r"`((?:rotordiag|simulator|features|models|service|tests|benchmarks|docs|examples)/[\w./-]*)`",
                           text))
    dotted = {m.split(":")[0] for m in re.findall(r"`(rotordiag(?:\.\w+)+(?::\w+)?)", text)}
    dotted |= {f"rotordiag.{m}" for m in re.findall(r"`((?:simulator|features|models|service)(?:\.\w+)+)", text)}
    sources = {_module_name(p): p for p in _package_sources()}
    assert len(paths) >= 15 and len(dotted) >= 10          # the page names modules (the test can fail)
    missing = [p for p in sorted(paths) if not (ROOT / p).exists()]

    def exists(name: str) -> bool:
        """A module, or a name a module defines or imports (``rotordiag.models.status.DecisionPolicy``)."""
        if name in sources:
            return True
        module, attr = name.rsplit(".", 1)
        return module in sources and re.search(rf"\b{attr}\b", sources[module].read_text(encoding="utf-8")) is not None

    missing += [m for m in sorted(dotted) if not exists(m)]
    assert not missing, f"docs/architecture.md names what does not exist: {missing}"
