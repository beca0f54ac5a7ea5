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
    names = ast.literal_eval(declared[0].value)
    defined = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    defined |= {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
    defined |= {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names}
    submodules = {p.stem for p in path.parent.glob("*.py")} | {p.name for p in path.parent.iterdir() if p.is_dir()}
    missing = [n for n in names if n not in defined and not (path.name == "__init__.py" and n in submodules)]
    assert not missing, f"__all__ names what the module does not define: {missing}"


def test_the_api_reference_lists_every_module_once():
    listed = re.findall(r"^::: (gyrocal[\w.]*)$", "".join(p.read_text() for p in (ROOT / "docs" / "api").glob("*.md")),
                        flags=re.MULTILINE)
    modules = {dotted(p) for p in MODULES} - {"gyrocal"} - {dotted(p) for p in MODULES if p.name == "__init__.py"
                                                          and dotted(p) != "gyrocal.pipeline.steps"}
    assert sorted(set(listed)) == sorted(listed), "a module is listed twice"
    assert not modules - set(listed), f"missing from docs/api: {sorted(modules - set(listed))}"
