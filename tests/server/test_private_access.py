"""One module reaches into viser's internals; no other production file touches another object's private attribute
(ours included) or imports a private module of viser."""

from __future__ import annotations

import ast
import subprocess

from helpers.paths import ROOT

COMPAT = "server/viser_compat.py"


def _production_files() -> list[str]:
    listed = subprocess.run(["git", "ls-files", "*.py"], cwd=ROOT, capture_output=True, text=True, check=True)
    return [name for name in listed.stdout.split() if not name.startswith(("tests/", "bench/", "scripts/"))]


def _private_reaches(source: str) -> list[str]:
    """Each ``x._name`` (not a dunder) whose ``x`` is not ``self``, ``cls`` or ``super()``, and each import of a
    private viser module, as its source text."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
            owner = node.value
            if isinstance(owner, ast.Name) and owner.id in ("self", "cls"):
                continue
            if isinstance(owner, ast.Call) and isinstance(owner.func, ast.Name) and owner.func.id == "super":
                continue
            found.append(ast.unparse(node))
        names = []
        if isinstance(node, ast.ImportFrom) and node.module is not None:
            names = [node.module, *(f"{node.module}.{alias.name}" for alias in node.names)]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        found += [
            name
            for name in names
            if name.split(".")[0] == "viser" and any(part.startswith("_") for part in name.split(".")[1:])
        ]
    return found


def test_the_finder_sees_a_reach_into_another_objects_private_attribute() -> None:
    assert _private_reaches("with self.scene._lock:\n    pass\n") == ["self.scene._lock"]
    assert _private_reaches("import viser._messages as m\n") == ["viser._messages"]
    assert _private_reaches("from viser import _messages\n") == ["viser._messages"]
    assert _private_reaches("self._lock = 1\ncls._x\nsuper()._y\nobj.__class__\nfrom viser import uplot\n") == []


def test_only_the_compat_module_reaches_into_private_names() -> None:
    reaches = {name: _private_reaches((ROOT / name).read_text()) for name in _production_files()}
    assert reaches[COMPAT], "the compat module is where viser's private names are read"
    offenders = {name: found for name, found in reaches.items() if found and name != COMPAT}
    assert offenders == {}
