"""The method registry (app.predict.methods): every name resolves to one record, and no module outside
it branches on a method's name by comparing it to a string literal."""
import ast
from pathlib import Path

import pytest

from app.predict.config import PredictConfig
from app.predict.methods import REGISTRY, Family, canonical, choices, method

ROOT = Path(__file__).resolve().parents[1]
REGISTRY_MODULE = ROOT / "app" / "predict" / "methods.py"
NAMES = {n for m in REGISTRY for n in m.names}


def test_every_name_and_alias_resolves_to_its_own_record():
    assert canonical("nift") == "ibs-nif" and canonical("teacher") == "oracle" == canonical("oracle")
    assert method("nift") is method("ibs-nif")
    assert len(NAMES) == sum(len(m.names) for m in REGISTRY)  # no name is given twice
    for m in REGISTRY:
        assert m.template == (m.query is not None and m.feature is not None)
        assert m.template + m.true_poses + (m.family is Family.REGISTRATION) == 1
    assert [m.name for m in REGISTRY if m.true_poses] == ["oracle"]
    assert "oracle" in choices() and "teacher" in choices() and not {"oracle", "teacher"} & set(choices(False))


def test_an_unknown_method_is_refused_in_one_line_naming_the_choices():
    with pytest.raises(ValueError, match=r"^unknown method 'ndf'; choose one of .*ibs-nif.*cpd") as raised:
        method("ndf")
    assert "\n" not in str(raised.value)
    with pytest.raises(ValueError, match="unknown method"):
        PredictConfig(method="ndf")


def literal_method_comparisons(source: str) -> list[int]:
    """Lines where a comparison (==, !=, in, not in) has a method's name or alias as a string literal
    on either side, alone or in a tuple, list or set."""
    def names_in(node: ast.AST) -> bool:
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return node.value in NAMES
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return any(names_in(e) for e in node.elts)
        return False

    return [node.lineno for node in ast.walk(ast.parse(source)) if isinstance(node, ast.Compare)
            and any(isinstance(op, (ast.Eq, ast.NotEq, ast.In, ast.NotIn)) for op in node.ops)
            and any(names_in(side) for side in (node.left, *node.comparators))]


def test_the_check_finds_a_planted_comparison():
    planted = 'if config.method == "cpd":\n    pass\nok = m in ("nift", "teacher")\nfine = name == "mug"\n'
    assert literal_method_comparisons(planted) == [1, 3]


def test_no_module_outside_the_registry_compares_a_method_name_to_a_string_literal():
    found = []
    for root in ("app", "hardware", "calibration", "scripts"):
        for path in sorted((ROOT / root).rglob("*.py")):
            if path != REGISTRY_MODULE:
                found += [f"{path.relative_to(ROOT)}:{line}" for line in literal_method_comparisons(path.read_text())]
    assert not found, f"branch on a method through app.predict.methods, not its name: {found}"
