"""The GLSL editor's sandbox: what a person's ``sdf``/``color`` source must look like before the app compiles it.

An editor source is untrusted text. :func:`check_source` refuses what could stall or escape the programs it is
pasted into (loops, preprocessor lines, uniforms, ``discard``, ``main``, sources too large once every call is
inlined) and reads ``sdf``/``color`` as GLSL's grammar has them, from :func:`tokenize`'s tokens (comments and
whitespace anywhere between them, the parameter qualifiers GLSL allows); :class:`ShaderCompileError` carries the
reason and the 1-based line of that source, a compiler's error put back on the person's line and in words
(:func:`plain_compiler_message`); :func:`user_glsl` is what the renderer appends to a template. Distances are in
metres, colours linear RGB.
"""

from __future__ import annotations

import dataclasses
import itertools
import re
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kernels import _checks
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


# ------------------------------------------------------------------------------------------ tokens
@dataclasses.dataclass(frozen=True)
class Token:
    """One GLSL token of an editor source: its text, 1-based line, 0-based column and offset in the source."""

    text: str
    line: int
    column: int
    offset: int

    @property
    def is_name(self) -> bool:
        return self.text[0].isalpha() or self.text[0] == "_"

    @property
    def is_number(self) -> bool:
        return self.text[0].isdigit() or (self.text[0] == "." and len(self.text) > 1)


_LEX = re.compile(
    r"(?P<skip>\s+|//[^\n]*|/\*.*?(?:\*/|\Z))"
    r"|(?P<token>0[xX][0-9A-Fa-f]+[uU]?"
    r"|(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?[fFuU]?"
    r"|[A-Za-z_]\w*"
    r"|<<=|>>=|\+\+|--|<<|>>|<=|>=|==|!=|&&|\|\||\^\^|[-+*/%&|^]="
    r"|.)",
    re.S,
)


def tokenize(source: str) -> list[Token]:
    """The GLSL tokens of ``source``: whitespace and comments (``//`` and ``/* */``) between them skipped, names,
    numbers and operators whole (maximal munch, as a GLSL lexer reads them)."""
    tokens: list[Token] = []
    line, line_start = 1, 0
    for match in _LEX.finditer(source):
        text = match.group(0)
        if match.group("token") is not None:
            tokens.append(Token(text, line, match.start() - line_start, match.start()))
        newlines = text.count("\n")
        if newlines:
            line += newlines
            line_start = match.start() + text.rindex("\n") + 1
    return tokens


# ------------------------------------------------------------------------------------------ definitions
APP_FUNCTIONS = {"sdf": "float", "color": "vec3"}
"""The functions the app calls in an editor source, by name, with their return type; each takes one ``vec3``."""
_PRECISIONS = frozenset({"highp", "mediump", "lowp"})
_QUALIFIERS = frozenset({"in", "out", "inout", "const", "precise", *_PRECISIONS})
_INPUT_QUALIFIERS = frozenset({"in", "const", *_PRECISIONS})
"""What GLSL allows before the point's type in ``float sdf(... vec3 p)``: the app's prototype reads the point as
``in``; ``const`` is dropped when the source is compiled (it only forbids assigning to the parameter)."""
_NOT_TYPES = frozenset({"return", "else", "if", "for", "while", "do", "switch", "case", "struct"})


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One formal parameter of a function header: its qualifiers, type, name (None if unnamed) and anything after
    (an array size)."""

    qualifiers: tuple[Token, ...]
    type: str | None
    name: str | None
    rest: tuple[Token, ...]


@dataclasses.dataclass(frozen=True)
class FunctionHeader:
    """A function definition or prototype at the top level of a source."""

    returns: str
    name: Token
    parameters: tuple[Parameter, ...]
    has_body: bool

    @property
    def line(self) -> int:
        return self.name.line

    @property
    def takes_one_vec3(self) -> bool:
        return len(self.parameters) == 1 and self.parameters[0].type == "vec3"

    def app_signature_problem(self) -> str | None:
        """Why this header of ``sdf`` or ``color`` taking one vec3 does not match the app's prototype (None: it
        does)."""
        returns = APP_FUNCTIONS[self.name.text]
        example = f"{returns} {self.name.text}(vec3 p)"
        if self.returns != returns:
            return f"{self.name.text}() must return {returns}, not {self.returns}: write {example}"
        parameter = self.parameters[0]
        words = [q.text for q in parameter.qualifiers]
        wrong = [w for w in words if w not in _INPUT_QUALIFIERS]
        if wrong:
            return (
                f"{self.name.text}()'s point is an input, so '{wrong[0]}' is not allowed: write {example} "
                f"(or with 'in', 'const in', 'highp')"
            )
        if len(set(words)) != len(words) or len([w for w in words if w in _PRECISIONS]) > 1:
            return f"{self.name.text}()'s parameter repeats a qualifier ({' '.join(words)}): write {example}"
        if parameter.name is None:
            return f"{self.name.text}()'s parameter needs a name: write {example}"
        if parameter.rest:
            return f"{self.name.text}() takes one vec3, not an array: write {example}"
        return None


def _split_parameters(tokens: list[Token]) -> tuple[Parameter, ...]:
    groups: list[list[Token]] = [[]]
    depth = 0
    for token in tokens:
        depth += {"(": 1, "[": 1, ")": -1, "]": -1}.get(token.text, 0)
        if token.text == "," and depth == 0:
            groups.append([])
        else:
            groups[-1].append(token)
    if groups == [[]] or [t.text for t in tokens] == ["void"]:
        return ()
    out = []
    for group in groups:
        k = 0
        while k < len(group) and group[k].text in _QUALIFIERS:
            k += 1
        kind = group[k].text if k < len(group) else None
        name = group[k + 1].text if k + 1 < len(group) and group[k + 1].is_name else None
        rest = tuple(group[k + 2 :] if name is not None else group[k + 1 :])
        out.append(Parameter(tuple(group[:k]), kind, name, rest))
    return tuple(out)


def function_headers(tokens: list[Token]) -> list[FunctionHeader]:
    """Every function definition and prototype at the top level of a tokenized source (``TYPE NAME ( … )``
    followed by ``{`` or ``;``, a precision qualifier before the type allowed), in order."""
    out: list[FunctionHeader] = []
    depth = 0
    for i, token in enumerate(tokens):
        if token.text in ("{", "}"):
            depth += 1 if token.text == "{" else -1
            continue
        if depth or token.text != "(" or i < 2:
            continue
        kind, name = tokens[i - 2], tokens[i - 1]
        if not (kind.is_name and name.is_name) or kind.text in _NOT_TYPES or kind.text in _QUALIFIERS:
            continue
        j, parens = i + 1, 1
        while j < len(tokens) and parens and tokens[j].text not in ("{", "}", ";"):
            parens += {"(": 1, ")": -1}.get(tokens[j].text, 0)
            j += 1
        if parens or j >= len(tokens) or tokens[j].text not in ("{", ";"):
            continue
        out.append(FunctionHeader(kind.text, name, _split_parameters(tokens[i + 1 : j - 1]), tokens[j].text == "{"))
    return out


def _check_definitions(headers: list[FunctionHeader]) -> None:
    """Refuse a source whose ``sdf``/``color`` taking one vec3 does not match the app's prototypes, or with no
    ``float sdf(vec3 p)`` definition (:class:`ShaderCompileError`)."""
    for header in headers:
        if header.name.text in APP_FUNCTIONS and header.takes_one_vec3:
            problem = header.app_signature_problem()
            if problem is not None:
                raise ShaderCompileError(problem, header.line)
    if not _defines(headers, "sdf"):
        other = next((h for h in headers if h.name.text == "sdf"), None)
        if other is None:
            raise ShaderCompileError("define float sdf(vec3 p), the signed distance (m)", None)
        raise ShaderCompileError(
            "define float sdf(vec3 p), the signed distance (m); this sdf() takes "
            f"({', '.join(p.type or '?' for p in other.parameters)})",
            other.line,
        )


def _defines(headers: list[FunctionHeader], name: str) -> bool:
    return any(h.name.text == name and h.takes_one_vec3 and h.has_body for h in headers)


def defines_color(source: str) -> bool:
    """Whether ``source`` defines ``vec3 color(vec3 p)`` itself (qualifiers, spaces and comments allowed)."""
    return _defines(function_headers(tokenize(source)), "color")


# ------------------------------------------------------------------------------------------ braces
def _indent(text: str) -> int:
    return len(text) - len(text.lstrip(" \t"))


def brace_problem(tokens: list[Token], source: str) -> ShaderCompileError | None:
    """A ``{`` never closed or a ``}`` that closes nothing, on the line a person would fix (None: balanced).

    Counting finds that braces do not balance; indentation says where: a ``}`` that starts a line closes the
    ``{`` whose line is indented as much, so one opened after that ``{`` and still open was never closed, and a
    ``}`` indented like no open ``{`` is the one too many. Indentation is read only once the count is wrong, so
    any layout of a balanced source is accepted."""
    lines = source.split("\n")
    first_on_line = {t.line: t for t in reversed(tokens)}
    opened: list[Token] = []
    stray: Token | None = None
    """The first ``}`` starting a line indented like no open ``{`` (the likely extra one)."""
    unclosed: tuple[Token, Token] | None = None
    """The first ``{`` a ``}`` indented like an outer ``{`` left open, and that ``}``."""
    for token in tokens:
        if token.text == "{":
            opened.append(token)
        elif token.text == "}":
            if not opened:
                extra = stray or token
                return ShaderCompileError("'}' closes no '{' (one '}' too many, or a '{' missing)", extra.line)
            if first_on_line[token.line] is token:
                indent = _indent(lines[token.line - 1])
                same = [k for k, t in enumerate(opened) if _indent(lines[t.line - 1]) == indent]
                if not same and stray is None:
                    stray = token
                elif same and same[-1] < len(opened) - 1 and unclosed is None:
                    unclosed = (opened[-1], token)
            opened.pop()
    if not opened:
        return None
    if unclosed is not None:
        brace, closer = unclosed
        return ShaderCompileError(f"'{{' is never closed: a '}}' is missing before line {closer.line}", brace.line)
    return ShaderCompileError("'{' is never closed: a '}' is missing at the end", opened[-1].line)


# ------------------------------------------------------------------------------------------ compiler messages
APPENDED_FIRST_LINE = 100001
"""The line number the code :func:`user_glsl` appends after a source starts at (past any source's last line)."""
_LOG_ERROR = re.compile(r"^\s*\d+[:(](\d+)\)?(?:\((\d+)\))?\s*:\s*error\s*:?\s*(?:[A-Z]\d{4}\s*:\s*)?(.+)$", re.M)
_OPERATORS = {
    "ADD_ASSIGN": "+=",
    "SUB_ASSIGN": "-=",
    "MUL_ASSIGN": "*=",
    "DIV_ASSIGN": "/=",
    "MOD_ASSIGN": "%=",
    "LEFT_ASSIGN": "<<=",
    "RIGHT_ASSIGN": ">>=",
    "AND_ASSIGN": "&=",
    "XOR_ASSIGN": "^=",
    "OR_ASSIGN": "|=",
    "INC_OP": "++",
    "DEC_OP": "--",
    "LE_OP": "<=",
    "GE_OP": ">=",
    "EQ_OP": "==",
    "NE_OP": "!=",
    "AND_OP": "&&",
    "OR_OP": "||",
    "XOR_OP": "^^",
    "LEFT_OP": "<<",
    "RIGHT_OP": ">>",
}
_KIND_NAMES: dict[tuple[str, str], tuple[str, ...]] = {
    ("type", "a type name"): ("BASIC_TYPE_TOK",),
    ("name", "a type name"): ("TYPE_IDENTIFIER", "TYPE_NAME"),
    ("name", "a name"): ("NEW_IDENTIFIER", "IDENTIFIER"),
    ("name", "a field name"): ("FIELD_SELECTION",),
    ("number", "a number"): ("FLOATCONSTANT", "DOUBLECONSTANT"),
    ("number", "a whole number"): ("INTCONSTANT", "UINTCONSTANT"),
    ("name", "true or false"): ("BOOLCONSTANT",),
    ("end", "the end of the text"): ("$end", "end of file"),
}
"""Mesa's (bison's) token names by what they stand for: the kind of token of the source, and in words."""
_KINDS: dict[str, tuple[str, str]] = {name: kind for kind, names in _KIND_NAMES.items() for name in names}
"""Each token name's (kind, words), from :data:`_KIND_NAMES`."""
_TYPE_WORDS = re.compile(r"(?:[biud]?vec[234]|d?mat[234](?:x[234])?|float|double|u?int|bool|void|sampler\w*)$")
_TOKEN_NAME = re.compile(r"\$end|end of file|\b(?:[A-Z][A-Z0-9]*_)*[A-Z][A-Z0-9]*(?:_[A-Z0-9]+)*\b")
_SYNTAX = re.compile(r"^syntax error, unexpected (.+?)(?:, expecting (.+?))?(?: at token .*)?$")


def _kind_words(name: str) -> tuple[str, str]:
    """(kind of source token, words) for one token as a bison message names it (``';'``, ``IDENTIFIER``, …)."""
    if len(name) >= 3 and name[0] == name[-1] == "'":
        return name[1:-1], name
    if name in _OPERATORS:
        return _OPERATORS[name], f"'{_OPERATORS[name]}'"
    if name in _KINDS:
        return _KINDS[name]
    word = name.removesuffix("_TOK").lower()
    return word, f"'{word}'"


def _is_kind(token: Token, kind: str) -> bool:
    if kind == "type":
        return _TYPE_WORDS.match(token.text) is not None
    if kind == "name":
        return token.is_name
    if kind == "number":
        return token.is_number
    return token.text == kind


def _plain_words(text: str) -> str:
    """Mesa's quoting (`x') as 'x', and any token name left (``BASIC_TYPE_TOK``) in words."""
    text = re.sub(r"`([^`']*)'", r"'\1'", text)
    text = re.sub(r";\s*candidates are:.*$", "", text)

    def words(match: re.Match[str]) -> str:
        name = match.group(0)
        if name in _OPERATORS or name in _KINDS or name.endswith("_TOK"):
            return _kind_words(name)[1]
        return name

    return _TOKEN_NAME.sub(words, text)


def plain_compiler_message(message: str, tokens: list[Token], line: int | None, column: int | None) -> str:
    """A compiler's error ``message`` about ``line`` (column ``column``, if given) of the tokenized source, in words
    a person reads: a bison syntax error names the token the source has there ("missing ';' before 'float'?")
    instead of the parser's name for it (``BASIC_TYPE_TOK``), and says which line ends without the ``;`` when the
    token starts a line; other messages keep Mesa's words with its quoting made plain. ``line`` None: the error
    was past the source's end (in code the app appended)."""
    syntax = _SYNTAX.match(message)
    undefined = _UNDEFINED.match(message)
    if undefined is not None:
        name = undefined.group(1)
        later = next((h for h in function_headers(tokens) if h.name.text == name and h.has_body), None)
        if later is not None and line is not None and later.line >= line:
            return f"{name}() is used before it is defined (line {later.line}): define it above its first use"
    if syntax is None:
        return _plain_words(message)
    kind, words = _kind_words(syntax.group(1).strip())
    expected = [_kind_words(e.strip())[1] for e in re.split(r"\s+or\s+", syntax.group(2) or "") if e.strip()]
    wanted = " or ".join(expected)
    if line is None or kind == "end":
        last = tokens[-1].text if tokens else ""
        ending = f" (expected {wanted})" if wanted else ""
        return f"syntax error, the text ends too early, after '{last}'{ending}"
    on_line = [t for t in tokens if t.line == line and _is_kind(t, kind)]
    found = min(on_line, key=lambda t: abs(t.column - (column or 0))) if on_line else None
    what = f"'{found.text}'" if found is not None else words
    previous = None
    if found is not None:
        index = tokens.index(found)
        previous = tokens[index - 1] if index and tokens[index - 1].line < found.line else None
    for closer in ("';'", "')'", "']'"):
        if closer in expected:
            after = f" (line {previous.line} ends without one)" if previous is not None else ""
            return f"syntax error, missing {closer} before {what}?{after}"
    return f"syntax error, unexpected {what}" + (f" (expected {wanted})" if wanted else " here")


class ShaderCompileError(ValueError):
    """An editor source the checks or the GLSL compiler reject; ``line`` is 1-based in that source (or None)."""

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message if line is None else f"line {line}: {message}")
        self.line = line
        self.reason = message

    @classmethod
    def from_compiler(cls, log: str, source: str) -> ShaderCompileError:
        """The first error of a compiler log (Mesa "0:LINE(COL): error: …"; NVIDIA "0(LINE) : error …"), on the
        line of ``source`` it names and in words a person reads (:func:`plain_compiler_message`).

        :func:`user_glsl` numbers the source's lines from 1 and the appended default ``color`` from
        :data:`APPENDED_FIRST_LINE`, so a line in the source is the person's own, and one in the appended code
        means the source ended in the middle of something (the error is put on its last line). Other lines are
        the app's own code: no line of theirs.
        """
        tokens = tokenize(source)
        lines = source.count("\n") + 1
        for match in _LOG_ERROR.finditer(log):
            line, message = int(match.group(1)), match.group(3).strip()
            column = None if match.group(2) is None else int(match.group(2))
            if 1 <= line <= lines:
                return cls(plain_compiler_message(message, tokens, line, column), line)
            if line >= APPENDED_FIRST_LINE and tokens:
                last = tokens[-1]
                return cls(plain_compiler_message(message, tokens, None, None), last.line)
            # Mesa's "0:0(0): error: function `float sdf(vec3)' has static recursion" names no line: the call does.
            recursion = _RECURSION.search(message)
            if recursion is not None:
                name = recursion.group(1)
                call = _recursive_call(tokens, name)
                if call is not None and call.text == name:
                    return cls(f"{name}() calls itself, and GLSL has no recursion", call.line)
                if call is not None:  # through a prototype, declared above and defined below
                    return cls(
                        f"{name}() calls {call.text}(), which calls back into {name}(): GLSL has no recursion",
                        call.line,
                    )
            return cls(plain_compiler_message(message, tokens, None, None), None)
        text = " ".join(log.replace("GLSL Compiler failed", "").split()) or "the shader did not compile"
        return cls(_plain_words(text), None)


_UNDEFINED = re.compile(r"no function with name [`'](\w+)'")
_RECURSION = re.compile(r"function [`']\w+ (\w+)\([^`']*\)' has static recursion")


def _bodies(tokens: list[Token]) -> dict[str, list[Token]]:
    """Each function defined in ``tokens``: the tokens of its body (overloads' bodies joined), by name."""
    bodies: dict[str, list[Token]] = {}
    for header in function_headers(tokens):
        if not header.has_body:
            continue
        k = next(k for k in range(tokens.index(header.name), len(tokens)) if tokens[k].text == "{")
        depth, body = 0, bodies.setdefault(header.name.text, [])
        for token in tokens[k:]:
            depth += {"{": 1, "}": -1}.get(token.text, 0)
            body.append(token)
            if depth == 0:
                break
    return bodies


def _calls(body: list[Token], names: Iterable[str]) -> list[Token]:
    """The calls in ``body`` of any of ``names``, in order."""
    wanted = set(names)
    return [t for t, after in itertools.pairwise(body) if t.text in wanted and after.text == "("]


def _recursive_call(tokens: list[Token], name: str) -> Token | None:
    """The first call in the body of ``name`` that leads back to ``name`` (itself, or a function whose calls do)."""
    bodies = _bodies(tokens)
    for call in _calls(bodies.get(name, []), bodies):
        seen, todo = set(), [call.text]
        while todo:
            current = todo.pop()
            if current == name:
                return call
            if current not in seen:
                seen.add(current)
                todo.extend(t.text for t in _calls(bodies.get(current, []), bodies))
    return None


def check_source(source: object) -> str:
    """The editor source if the app will compile it, else :class:`ShaderCompileError` saying why and where.

    Untrusted text: at most :data:`MAX_SOURCE_CHARS` printable ASCII characters (tabs and newlines too; no
    backslash, which would join lines, and no carriage return, which Mesa takes as a line end); no ``#``, so no
    preprocessor lines (no ``#include``, ``#extension``, macros); no loops (``for``, ``while``, ``do``): without
    them, and without recursion (which GLSL forbids), every call of ``sdf`` ends, and its cost grows with the
    source's length, which :data:`MAX_INLINED_TOKENS` bounds once calls are inlined; no ``uniform`` declarations,
    ``discard`` or ``main``; braces that balance (else the ``{`` never closed or the ``}`` too many is named). It
    must define ``float sdf(vec3 p)``; ``vec3 color(vec3 p)`` is optional. Both are read as GLSL's grammar has
    them: spaces, newlines and comments anywhere between tokens, and the point's qualifiers ``in``, ``const``,
    ``highp``/``mediump``/``lowp``.
    """
    if not isinstance(source, str):
        raise ShaderCompileError("the source must be text", None)
    if len(source) > MAX_SOURCE_CHARS:
        raise ShaderCompileError(f"the source is {len(source)} characters; the limit is {MAX_SOURCE_CHARS}", None)
    # Check the text the compiler will see. A backslash before a newline splices two lines into one (so
    # "fo\<newline>r" is the word for) and Mesa ends a // comment at a lone carriage return (so a loop after one is
    # code): neither has a use in sdf() text, so both are refused outright, and every line below is a line the
    # compiler reads as one.
    for number, line in enumerate(source.split("\n"), start=1):
        bad = next((c for c in line if not (" " <= c <= "~" or c == "\t")), None)
        if bad == "\r":
            raise ShaderCompileError("carriage returns are not allowed (end lines with a plain newline)", number)
        if bad is not None:
            raise ShaderCompileError(f"character {_checks.shown(bad)} is not allowed (printable ASCII only)", number)
        if "\\" in line:
            raise ShaderCompileError(
                "backslashes are not allowed (a backslash at a line's end joins it to the next)", number
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
    tokens = tokenize(source)
    braces = brace_problem(tokens, source)
    if braces is not None:
        raise braces
    _check_definitions(function_headers(tokens))
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
    """What a template gets appended: the source with its lines numbered from 1 (``#line 1``), then the default
    ``color`` if it defines none, numbered from :data:`APPENDED_FIRST_LINE`, so a compiler's line number says whose
    code it is (:meth:`ShaderCompileError.from_compiler`).

    A ``const`` before the point of ``sdf``/``color`` is blanked out (same length, so lines and columns stay):
    the app's prototypes declare the point plain ``in``, and GLSL wants a definition's qualifiers to match its
    prototype's; ``const`` only forbids assigning to the parameter."""
    tokens = tokenize(source)
    headers = function_headers(tokens)
    text = source
    for header in headers:
        if header.name.text in APP_FUNCTIONS and header.takes_one_vec3:
            for qualifier in header.parameters[0].qualifiers:
                if qualifier.text == "const":
                    text = text[: qualifier.offset] + " " * 5 + text[qualifier.offset + 5 :]
    appended = "" if _defines(headers, "color") else DEFAULT_COLOR_GLSL
    return f"\n#line 1\n{text}\n#line {APPENDED_FIRST_LINE}\n{appended}"


def check_field_bounds(bounds: ArrayLike) -> NDArray[np.float64]:
    """An editor field's (2, 3) min and max corners (m) as float64, within ±1000 m, else ``ValueError``."""
    box = _checks.finite_array("bounds", bounds)
    if box.shape != (2, 3) or np.any(box[1] <= box[0]):
        raise ValueError(f"bounds must be finite (2, 3) min and max corners with max > min, got {box.tolist()}")
    if np.any(np.abs(box) > 1e3):
        raise ValueError(f"bounds must lie within ±1000 m, got {box.tolist()}")
    return box


def examples() -> dict[str, str]:
    """The editor's example sources (``shaders/example_*.glsl``) by title (each file's first comment line)."""
    out: dict[str, str] = {}
    for path in sorted(SHADER_DIR.glob("example_*.glsl")):
        source = path.read_text(encoding="utf-8")
        title = source.split("\n", 1)[0].removeprefix("//").strip()
        out[title] = source
    return out
