"""The diagnostic scripts (scripts/diagnose/): each compiles, everything it imports from the project
exists (a rename that breaks one fails here, without running it), none patches a private attribute,
and the folder's index lists each one."""
import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "scripts" / "diagnose"
SCRIPTS = sorted(FOLDER.glob("*.py"))
OURS = ("app", "hardware", "calibration")


def our_imports(tree: ast.AST) -> list[tuple[str, list[str]]]:
    """(module, names) of every import of our packages, anywhere in the script."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] in OURS:
            found.append((node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            found += [(a.name, []) for a in node.names if a.name.split(".")[0] in OURS]
    return found


def test_there_are_diagnostics_to_check():
    assert len(SCRIPTS) >= 15


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_a_diagnostic_compiles_and_what_it_imports_exists(path):
    tree = ast.parse(path.read_text(), str(path))
    compile(tree, str(path), "exec")
    for module, names in our_imports(tree):
        imported = importlib.import_module(module)
        missing = [n for n in names if not hasattr(imported, n)
                   and importlib.util.find_spec(f"{module}.{n}") is None]
        assert not missing, f"{path.name}: {module} has no {', '.join(missing)}"


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: p.name)
def test_a_diagnostic_patches_no_private_attribute(path):
    """A hook the device offers (SimArm.on_stop), not a monkeypatch of its internals."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.Assign, ast.AugAssign)):
            for target in getattr(node, "targets", [getattr(node, "target", None)]):
                if isinstance(target, ast.Attribute) and target.attr.startswith("_") \
                        and not (isinstance(target.value, ast.Name) and target.value.id == "self"):
                    pytest.fail(f"{path.name}:{node.lineno} assigns {target.attr}")


def test_the_index_lists_every_diagnostic_and_nothing_else():
    index = (FOLDER / "README.md").read_text()
    listed = {line.split("`")[1] for line in index.splitlines() if line.startswith("| `")}
    assert listed == {p.name for p in SCRIPTS}
