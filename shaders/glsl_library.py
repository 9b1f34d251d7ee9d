"""The GLSL files and the one piece of GLSL written from Python: the primitive kinds' codes and dispatch.

``sdf.glsl`` holds every formula; two of its lines are placeholders filled from the kernel's registry
(:data:`kernels.sdf.PRIMITIVES`) when a renderer loads it, so the kinds are listed once:

- ``// @KIND_DEFINES``: a ``#define KIND_<NAME> <code>`` per kind, and ``FIRST_CATALOGUE_KIND``, the first code that
  ``primitive_distance`` hands to ``catalogue_distance`` rather than its one shared formula;
- ``// @CATALOGUE_DISTANCE``: the formulas of kinds registered with a ``glsl_file``, then ``catalogue_distance``,
  which calls each non-fused kind's GLSL function by its code.

The text :func:`sdf_library` returns is what programs ``#include "sdf.glsl"`` through moderngl's ``ctx.includes``.
"""

from __future__ import annotations

from pathlib import Path

from kernels import _checks, sdf

SHADER_DIR = Path(__file__).resolve().parent
"""Where the GLSL files live (installed as package data next to this module)."""
KIND_DEFINES_LINE = "// @KIND_DEFINES"
CATALOGUE_DISTANCE_LINE = "// @CATALOGUE_DISTANCE"


def read_source(name: str) -> str:
    """The text of ``shaders/<name>``."""
    return (SHADER_DIR / name).read_text(encoding="utf-8")


def with_defines(source: str, **defines: int) -> str:
    """``source`` with ``#define NAME value`` lines after its ``#version`` line."""
    version, rest = source.split("\n", 1)
    assert version.startswith("#version")
    return "\n".join([version, *(f"#define {k} {v}" for k, v in defines.items()), rest])


def _macro(spec: sdf.PrimitiveSpec) -> str:
    return f"KIND_{spec.kind.upper()}"


def kind_defines() -> str:
    """``#define KIND_<NAME> <code>`` for every registered kind, in code order, and ``FIRST_CATALOGUE_KIND``."""
    specs = list(sdf.PRIMITIVES.values())
    lines = [f"#define {_macro(spec)} {spec.code}" for spec in specs]
    first = min(spec.code for spec in specs if not spec.fused)
    if any(spec.fused and spec.code > first for spec in specs):
        raise ValueError("the fused kinds must have the lowest codes")
    lines.append(f"#define FIRST_CATALOGUE_KIND {first}")
    return "\n".join(lines)


def catalogue_distance() -> str:
    """GLSL of the registered kinds' formulas kept in files of their own, and ``catalogue_distance(kind, p, s)``,
    which calls every non-fused kind's function (the last one unconditionally)."""
    catalogue = [spec for spec in sdf.PRIMITIVES.values() if not spec.fused]
    formulas = [spec.glsl_file.read_text(encoding="utf-8") for spec in catalogue if spec.glsl_file]
    lines = ["float catalogue_distance(int kind, vec3 p, vec3 s) {"]
    for spec in catalogue[:-1]:
        call = f"{spec.glsl_function}({spec.glsl_arguments})"
        lines.append(f"    if (kind == {_macro(spec)}) return {call};")
    last = catalogue[-1]
    lines.append(f"    return {last.glsl_function}({last.glsl_arguments});")
    lines.append("}")
    return "\n".join([*(text.rstrip("\n") for text in formulas), *lines])


def sdf_library() -> str:
    """``sdf.glsl`` with its placeholders filled from the current registry (see the module docstring)."""
    text = read_source("sdf.glsl")
    for line in (KIND_DEFINES_LINE, CATALOGUE_DISTANCE_LINE):
        if text.count(line + "\n") != 1:
            raise ValueError(f"sdf.glsl must hold the line {_checks.shown(line)} once")
    text = text.replace(KIND_DEFINES_LINE + "\n", kind_defines() + "\n")
    return text.replace(CATALOGUE_DISTANCE_LINE + "\n", catalogue_distance() + "\n")
