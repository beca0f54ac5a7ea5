"""The house rules of the source tree: documented modules, a declared public API, and an API reference
that lists every module (docs/architecture.md). One concern per module is a review rule, not a line count."""

import ast
import re
from pathlib import Path

import pytest

from conftest import ROOT

SRC = ROOT / "src" / "gyrocal"
MODULES = sorted(SRC.rglob("*.py"))


def dotted(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@pytest.mark.parametrize("path", MODULES, ids=dotted)
def test_every_module_is_documented_and_declares_its_public_names(path):
    text = path.read_text()
    tree = ast.parse(text)
    assert ast.get_docstring(tree), "no module docstring"
    declared = [n for n in tree.body if isinstance(n, ast.Assign) and any(
        isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)]
    assert declared, "no __all__"
    entry_points = _entry_points(tree)
    names = list(entry_points) if entry_points else ast.literal_eval(declared[0].value)
    defined = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    defined |= {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
    defined |= {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names}
    submodules = {p.stem for p in path.parent.glob("*.py")} | {p.name for p in path.parent.iterdir() if p.is_dir()}
    missing = [n for n in names if n not in defined and n not in entry_points
               and not (path.name == "__init__.py" and n in submodules)]
    assert not missing, f"__all__ names what the module does not define: {missing}"
    for name, module in entry_points.items():  # a package's entry points (`gyrocal.exports.lazy`)
        assert name not in submodules, f"entry point {name} hides the module of that name"
        source = ast.parse((path.parent / f"{module}.py").read_text())
        assert name in ast.literal_eval(next(n.value for n in source.body if isinstance(n, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets))), f"{module} does not export {name}"


def _entry_points(tree) -> dict:
    """A package's ``_ENTRY_POINTS`` (name: module), {} where it has none."""
    found = [n.value for n in tree.body if isinstance(n, ast.Assign) and any(
        isinstance(t, ast.Name) and t.id == "_ENTRY_POINTS" for t in n.targets)]
    return ast.literal_eval(found[0]) if found else {}


def test_the_api_reference_lists_every_module_once():
    listed = re.findall(r"^::: (gyrocal[\w.]*)$", "".join(p.read_text() for p in (ROOT / "docs" / "api").glob("*.md")),
                        flags=re.MULTILINE)
    modules = {dotted(p) for p in MODULES} - {"gyrocal"} - {dotted(p) for p in MODULES if p.name == "__init__.py"
                                                          and dotted(p) != "gyrocal.pipeline.steps"}
    assert sorted(set(listed)) == sorted(listed), "a module is listed twice"
    assert not modules - set(listed), f"missing from docs/api: {sorted(modules - set(listed))}"
