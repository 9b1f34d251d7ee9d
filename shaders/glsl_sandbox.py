"""The GLSL editor's sandbox: what a person's ``sdf``/``color`` source must look like before the app compiles it.

An editor source is untrusted text. :func:`check_source` refuses what could stall or escape the programs it is
pasted into (loops, preprocessor lines, uniforms, ``discard``, ``main``, sources too large once every call is
inlined); :class:`ShaderCompileError` carries the reason and the 1-based line of that source; :func:`user_glsl` is
what the renderer appends to a template. Distances are in metres, colours linear RGB.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import ArrayLike, NDArray

from shaders.glsl_library import SHADER_DIR, sdf_library

MAX_SOURCE_CHARS = 8000
"""Longest editor source accepted (characters)."""
DEFAULT_COLOR_GLSL = "vec3 color(vec3 p) {\n    return vec3(0.85, 0.55, 0.35);\n}\n"
"""The colour an editor source gets when it defines no ``color``."""
_FORBIDDEN = {
    "for": "loops are not allowed (a loop could run forever and stall every viewer); use op_repeat_finite",
    "while": "loops are not allowed (a loop could run forever and stall every viewer)",
    "do": "loops are not allowed (a loop could run forever and stall every viewer)",
    "discard": "discard is not allowed in sdf() or color()",
    "uniform": "declaring uniforms is not allowed",
    "main": "main() is the app's; write float sdf(vec3 p) and optionally vec3 color(vec3 p)",
}


MAX_INLINED_TOKENS = 20000
"""Largest ``sdf`` + ``color`` accepted once every call is inlined (tokens, the library's functions counted too).
GLSL compilers inline every call, so a chain of functions each calling the one before twice doubles the code at
each link: ten links of 679 characters took Mesa 76 s to compile. The examples count at most about 1600."""
_DEFINITION = re.compile(r"\b([A-Za-z_]\w*)\s+([A-Za-z_]\w*)\s*\(([^()]*)\)\s*\{")
_TOKEN = re.compile(r"\w+|[^\w\s]")
_NOT_NAMES = frozenset({"if", "else", "return", "for", "while", "do", "switch"})


def inlined_sizes(code: str, known: dict[str, int] | None = None) -> dict[str, int]:
    """Tokens of each function defined in ``code`` (comments already removed) with every call to a function
    defined before it (or in ``known``) replaced by that function's own inlined size, by name.

    A call to a function not yet defined counts nothing (GLSL needs a declaration first and forbids recursion, so
    the compiler refuses such a source anyway)."""
    sizes = dict(known or {})
    for match in _DEFINITION.finditer(code):
        name = match.group(2)
        if match.group(1) in _NOT_NAMES or name in _NOT_NAMES:
            continue
        depth, end = 1, match.end()
        while end < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[end], 0)
            end += 1
        tokens = _TOKEN.findall(code[match.end() : end])
        size = len(tokens)
        for i, token in enumerate(tokens[:-1]):
            if token != name and tokens[i + 1] == "(" and token in sizes:
                size += sizes[token]
        sizes[name] = size
    return sizes


_library_sizes: dict[str, int] = {}


def _without_comments(source: str) -> str:
    return "\n".join(line.split("//", 1)[0] for line in source.split("\n"))


class ShaderCompileError(ValueError):
    """An editor source the checks or the GLSL compiler reject; ``line`` is 1-based in that source (or None)."""

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message if line is None else f"line {line}: {message}")
        self.line = line
        self.reason = message

    @classmethod
    def from_compiler(cls, log: str, source: str) -> ShaderCompileError:
        """The first error of a compiler log (Mesa "0:LINE(COL): error: …"; NVIDIA "0(LINE) : error …")."""
        lines = source.count("\n") + 1
        for match in re.finditer(
            r"^\s*\d+[:(](\d+)\)?(?:\(\d+\))?\s*:\s*error\s*:?\s*(.+)$", log, re.M
        ):
            line, message = int(match.group(1)), match.group(2).strip()
            return cls(message, line if 1 <= line <= lines else None)
        text = (
            " ".join(log.replace("GLSL Compiler failed", "").split())
            or "the shader did not compile"
        )
        return cls(text, None)


def check_source(source: object) -> str:
    """The editor source if the app will compile it, else :class:`ShaderCompileError` saying why and where.

    Untrusted text: at most :data:`MAX_SOURCE_CHARS` printable ASCII characters (tabs and newlines too; no
    backslash, which would join lines, and no carriage return, which Mesa takes as a line end); no ``#``, so no
    preprocessor lines (no ``#include``, ``#extension``, macros); no loops (``for``, ``while``, ``do``): without
    them, and without recursion (which GLSL forbids), every call of ``sdf`` ends, and its cost grows with the
    source's length, which :data:`MAX_INLINED_TOKENS` bounds once calls are inlined; no ``uniform`` declarations,
    ``discard`` or ``main``. It must define
    ``float sdf(vec3 p)``; ``vec3 color(vec3 p)`` is optional.
    """
    if not isinstance(source, str):
        raise ShaderCompileError("the source must be text", None)
    if len(source) > MAX_SOURCE_CHARS:
        raise ShaderCompileError(
            f"the source is {len(source)} characters; the limit is {MAX_SOURCE_CHARS}", None
        )
    # Check the text the compiler will see. A backslash before a newline splices two lines into one (so
    # "fo\<newline>r" is the word for) and Mesa ends a // comment at a lone carriage return (so a loop after one is
    # code): neither has a use in sdf() text, so both are refused outright, and every line below is a line the
    # compiler reads as one.
    for number, line in enumerate(source.split("\n"), start=1):
        bad = next((c for c in line if not (" " <= c <= "~" or c == "\t")), None)
        if bad == "\r":
            raise ShaderCompileError(
                "carriage returns are not allowed (end lines with a plain newline)", number
            )
        if bad is not None:
            raise ShaderCompileError(
                f"character {bad!r} is not allowed (printable ASCII only)", number
            )
        if "\\" in line:
            raise ShaderCompileError(
                "backslashes are not allowed (a backslash at a line's end joins it to the next)",
                number,
            )
        code = line.split("//", 1)[0]
        if "#" in code:
            raise ShaderCompileError("preprocessor lines (#…) are not allowed", number)
        for word in re.findall(r"[A-Za-z_]\w*", code):
            if word in _FORBIDDEN:
                raise ShaderCompileError(_FORBIDDEN[word], number)
            if word.startswith("gl_"):
                raise ShaderCompileError(f"{word} is not available here", number)
    if "/*" in source:
        raise ShaderCompileError("block comments (/* */) are not allowed; use //", None)
    if not re.search(r"\bfloat\s+sdf\s*\(\s*vec3\s+\w+\s*\)", source):
        raise ShaderCompileError("define float sdf(vec3 p), the signed distance (m)", None)
    if not _library_sizes:
        _library_sizes.update(inlined_sizes(_without_comments(sdf_library())))
    sizes = inlined_sizes(_without_comments(source), _library_sizes)
    inlined = sizes.get("sdf", 0) + sizes.get("color", 0)
    if inlined > MAX_INLINED_TOKENS:
        raise ShaderCompileError(
            f"sdf() and color() come to about {inlined} tokens once every call is inlined (a function that "
            f"calls another several times multiplies its size); the limit is {MAX_INLINED_TOKENS}",
            None,
        )
    return source


def user_glsl(source: str) -> str:
    """What a template gets appended: ``#line 1`` so compiler lines count from the source's first line, the
    source, and the default ``color`` if it defines none."""
    has_color = re.search(r"\bvec3\s+color\s*\(\s*vec3\s+\w+\s*\)", source) is not None
    return "\n#line 1\n" + source + "\n" + ("" if has_color else DEFAULT_COLOR_GLSL)


def check_field_bounds(bounds: ArrayLike) -> NDArray[np.float64]:
    """An editor field's (2, 3) min and max corners (m) as float64, within ±1000 m, else ``ValueError``."""
    box = np.asarray(bounds, dtype=np.float64)
    if box.shape != (2, 3) or not np.all(np.isfinite(box)) or np.any(box[1] <= box[0]):
        raise ValueError(
            f"bounds must be finite (2, 3) min and max corners with max > min, got {box.tolist()}"
        )
    if np.any(np.abs(box) > 1e3):
        raise ValueError("bounds must lie within ±1000 m")
    return box


def examples() -> dict[str, str]:
    """The editor's example sources (``shaders/example_*.glsl``) by title (each file's first comment line)."""
    out: dict[str, str] = {}
    for path in sorted(SHADER_DIR.glob("example_*.glsl")):
        source = path.read_text(encoding="utf-8")
        title = source.split("\n", 1)[0].removeprefix("//").strip()
        out[title] = source
    return out
