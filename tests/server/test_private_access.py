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


# ------------------------------------------------------------------------------------------------------ the layers
LAYERS = ("kernels", "shaders", "scenes", "server", "app")
"""docs/development.md's layers, each using only the ones to its left."""
BASE_BRIDGE = {"scenes/_base.py", "scenes/_controls.py"}
"""The scene base, the one place scenes stand on the server: a scene is built on a session, its controls are cleaned
by the gate's rules, its callbacks take the process's turn."""
BRIDGED = {"server.clean", "server.sessions", "server.turns"}


def _our_imports(source: str) -> set[str]:
    """Every module of ours a source imports, at its top or inside a function, as a dotted name."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module is not None and node.level == 0:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {name for name in found if name.split(".")[0] in LAYERS}


def _layer(path: str) -> str:
    return path.removesuffix(".py").split("/")[0]


def test_each_layer_imports_only_the_ones_to_its_left_and_scenes_reach_the_server_through_the_base() -> None:
    wrong = {}
    for path in _production_files():
        rank = LAYERS.index(_layer(path))
        for module in sorted(_our_imports((ROOT / path).read_text())):
            target = LAYERS.index(module.split(".")[0])
            bridged = path in BASE_BRIDGE and module in BRIDGED
            if target > rank and not bridged:
                wrong.setdefault(path, []).append(module)
    assert wrong == {}


def test_the_layer_finder_sees_an_import_to_the_right() -> None:
    assert _our_imports("import numpy\nfrom scenes._base import Scene\ndef f():\n    import server.gate\n") == {
        "scenes._base",
        "server.gate",
    }
