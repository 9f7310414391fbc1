"""The house's rules, read from the real imports (ast): every import points down or sideways, never up.

Floors, from the bottom (docs/design.md): hardware.se3 < hardware < hardware.sim < calibration <
app's plumbing < app.nift < app.objects < tasks, layout, perception < predict, motion < jobs, training
< app.simcell < app.bench, app.console < app.commands < app.cli. Every import is counted, lazy ones inside functions too.
"""
from __future__ import annotations

import ast
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OURS = ("app", "hardware", "calibration")
FLOORS = {  # module prefix -> floor; the longest matching prefix decides
    "hardware.se3": 0,
    "hardware": 1,
    "hardware.sim": 2,
    "hardware.net": 1,  # device servers and clients: the interfaces, never the simulator
    "hardware.fake": 1,  # fake devices over a kinematic world: the interfaces, never the simulator
    "calibration": 3,
    "app": 4, "app.io_utils": 4, "app.config": 4, "app.categories": 4, "app.cloud_io": 4,
    "app.nift": 5,
    "app.objects": 6,
    "app.tasks": 7, "app.layout": 7, "app.perception": 7,
    "app.predict": 8, "app.motion": 8,
    "app.jobs": 9, "app.training": 9,
    "app.simcell": 10, "app.recording": 10,
    "app.bench": 11, "app.console": 11, "app.teach": 11,
    "app.commands": 12,
    "app.cli": 13,
}
JOB_PATH = ("app.jobs", "app.motion", "app.predict")


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def our_modules() -> dict[str, Path]:
    return {module_name(p): p for root in OURS for p in sorted((ROOT / root).rglob("*.py"))}


def imports_of(source: str, modules: dict[str, Path]) -> set[str]:
    """Our modules a source imports, anywhere in it (`from a.b import c` counts a.b.c when that is a module)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules else node.module
                     for a in node.names]
        else:
            continue
        found |= {n for n in names if n.split(".")[0] in OURS}
    return found


@lru_cache(maxsize=1)
def _tree_graph() -> dict[str, frozenset[str]]:
    modules = our_modules()
    return {name: frozenset(imports_of(path.read_text(), modules)) for name, path in modules.items()}


def graph(planted: dict[str, str] | None = None) -> dict[str, set[str]]:
    """{module: our modules it imports}; `planted` adds modules from source text (to test the rules)."""
    modules = our_modules()
    edges = {name: set(targets) for name, targets in _tree_graph().items()}
    return edges | {name: imports_of(text, modules) for name, text in (planted or {}).items()}


def floor(module: str) -> int:
    prefixes = [p for p in FLOORS if module == p or module.startswith(p + ".")]
    assert prefixes, f"{module} has no floor in FLOORS: add it"
    return FLOORS[max(prefixes, key=len)]


def closure(start: str, edges: dict[str, set[str]]) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        for nxt in edges.get(todo.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def upward_imports(edges: dict[str, set[str]]) -> list[str]:
    return [f"{a} (floor {floor(a)}) imports {b} (floor {floor(b)})"
            for a, targets in edges.items() for b in targets if floor(b) > floor(a)]


def test_every_import_points_down_or_sideways():
    up = upward_imports(graph())
    assert not up, "\n".join(up)


def test_no_import_cycles():
    edges = graph()
    cycles = sorted(m for m in edges if m in closure(m, edges) and not m.startswith("app.objects"))
    # app.objects' __init__ re-exports its modules, which import siblings through it: a package face, not a loop
    assert not cycles, f"modules in an import loop: {cycles}"


def test_hardware_imports_only_hardware():
    bad = [f"{a} imports {b}" for a, targets in graph().items() if a.startswith("hardware")
           for b in targets if not b.startswith("hardware")]
    assert not bad, bad


def test_se3_imports_nothing_of_ours():
    assert graph()["hardware.se3"] == set()


def test_calibration_imports_only_hardware_interfaces_and_se3():
    allowed = {"hardware.interfaces", "hardware.se3"}
    bad = [f"{a} imports {b}" for a, targets in graph().items() if a.startswith("calibration")
           for b in targets if not (b in allowed or b.startswith("calibration"))]
    assert not bad, bad


def test_method_library_imports_no_hardware_but_se3_and_the_settings_checks():
    pure = {"hardware.se3", "hardware.settings"}  # poses and range checks: plain Python, no device
    bad = [f"{a} imports {b}" for a, targets in graph().items() if a.startswith("app.nift")
           for b in targets if b.startswith("hardware") and b not in pure or b.startswith("app.simcell")]
    assert not bad, bad


@pytest.mark.parametrize("start", JOB_PATH)
def test_job_path_never_reaches_the_simulator(start):
    edges = graph()
    starts = [m for m in edges if m == start or m.startswith(start + ".")]
    reached = {(s, m) for s in starts for m in closure(s, edges) if m.startswith(("hardware.sim", "app.simcell"))}
    assert not reached, sorted(reached)


def test_commands_are_imported_by_the_cli_only():
    bad = [f"{a} imports {b}" for a, targets in graph().items() for b in targets
           if b.startswith("app.commands") and not (a == "app.cli" or a.startswith("app.commands"))]
    assert not bad, bad


def test_importing_the_method_loads_no_simulator():
    code = "import sys, app.nift.imitate, app.predict.predict; print(sorted(m for m in sys.modules if m.split('.')[0] in ('pybullet', 'hardware')))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    loaded = eval(out)
    assert "pybullet" not in loaded and not any(m.startswith("hardware.sim") for m in loaded), loaded


def test_rules_catch_forbidden_imports():
    """The checker itself: planted upward imports, a planted loop and a sim import on the job path are found."""
    edges = graph({"hardware.planted": "from app.simcell.cell import SimCell\n"})
    assert "hardware.planted (floor 1) imports app.simcell.cell (floor 10)" in upward_imports(edges)
    loop = graph({"app.nift.planted": "import app.nift.planted_too\n", "app.nift.planted_too": "import app.nift.planted\n"})
    assert "app.nift.planted" in closure("app.nift.planted", loop)
    lazy = graph({"app.motion.planted": "def f():\n    from hardware.sim.world import SimWorld\n"})
    assert "hardware.sim.world" in closure("app.motion.planted", lazy)
