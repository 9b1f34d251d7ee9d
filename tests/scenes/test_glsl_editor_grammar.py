"""The GLSL editor reads ``sdf``/``color`` as GLSL's grammar has them, and its errors name the person's own lines.

Definitions with any of the parameter qualifiers GLSL allows (``in``, ``const in``, precision), spaces, newlines and
comments between tokens are accepted and give the plain form's field; a source with one error on a line gets a
message naming that line, in words (no parser token names such as ``BASIC_TYPE_TOK``)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import viser
from helpers.meshing import CUBE_BOUNDS
from helpers.properties import examples
from helpers.scenes import apply_glsl, scene_fixture
from helpers.waiting import wait_until
from helpers.wsclient import BrowserClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenes.sdf_gallery import SdfGalleryScene
from shaders import gl_service
from shaders.glsl_sandbox import (
    APPENDED_FIRST_LINE,
    DEFAULT_COLOR_GLSL,
    ShaderCompileError,
    check_source,
    defines_color,
    user_glsl,
)
from shaders.renderer import Camera, Shading, mesh_glsl

PLAIN_SDF = "float sdf(vec3 p) {\n    return sd_torus(p - vec3(0.1, 0.0, 0.05), 0.6, 0.2);\n}\n"
PLAIN_COLOR = "vec3 color(vec3 p) {\n    return vec3(0.2, 0.5, 0.8) + 0.1 * p;\n}\n"
MESA_TOKEN_NAME = re.compile(
    r"\$end|\b(?:[A-Z][A-Z0-9]*_)+[A-Z0-9]+\b"
    r"|\b(?:IDENTIFIER|FLOATCONSTANT|INTCONSTANT|UINTCONSTANT|BOOLCONSTANT|STRUCT|IF|ELSE|RETURN)\b"
)
"""Words of Mesa's parser (BASIC_TYPE_TOK, NEW_IDENTIFIER, FLOATCONSTANT, $end, …) that a message must not show."""
POINTS = np.array([[0.0, 0.0, 0.0], [0.7, 0.0, 0.05], [0.3, -0.4, 0.2], [-0.9, 0.5, -0.3], [0.1, 0.65, 0.0]])


def probe(source: str) -> tuple[np.ndarray, np.ndarray]:
    return gl_service.run(lambda gl: gl.probe_field(source, POINTS))


# ------------------------------------------------------------------------------------------ generated definitions
_SPACE = st.sampled_from(
    [
        " ",
        "  ",
        "\t",
        "\n",
        "\n\n    ",
        " // a comment with { and ( in it\n",
        "// float sdf(vec3 p) { return 1.0; }\n",
        "  // vec3 color(vec3 p) {\n",
    ]
)
gaps = st.lists(_SPACE, min_size=1, max_size=3).map("".join)
"""Whitespace or comments where GLSL needs some (between two names)."""
optional_gaps = st.one_of(st.just(""), gaps)
"""Whitespace or comments, or nothing (beside punctuation)."""
qualifier_lists = st.tuples(
    st.sampled_from([(), ("const",)]),
    st.sampled_from([(), ("in",)]),
    st.sampled_from([(), ("highp",), ("mediump",), ("lowp",)]),
).map(lambda parts: parts[0] + parts[1] + parts[2])
"""The qualifiers GLSL allows before an input parameter's type, in the grammar's order."""


@st.composite
def header(draw: st.DrawFn, returns: str, name: str) -> tuple[str, str]:
    """``[precision] returns name ( qualifiers vec3 point ) {`` with random gaps; and the point's name."""
    point = draw(st.sampled_from(["p", "q", "pos", "point_1"]))
    words: list[str] = []
    precision = draw(st.sampled_from([None, "highp", "mediump", "lowp"]))
    if precision is not None:
        words += [precision, draw(gaps)]
    words += [returns, draw(gaps), name, draw(optional_gaps), "(", draw(optional_gaps)]
    for qualifier in draw(qualifier_lists):
        words += [qualifier, draw(gaps)]
    words += ["vec3", draw(gaps), point, draw(optional_gaps), ")", draw(optional_gaps), "{"]
    return "".join(words), point


@st.composite
def definitions(draw: st.DrawFn) -> tuple[str, bool]:
    """A source defining PLAIN_SDF's sdf, and maybe PLAIN_COLOR's color, in a random legal spelling; and whether
    it defines color."""
    sdf_header, p = draw(header("float", "sdf"))
    source = (
        draw(optional_gaps)
        + sdf_header
        + draw(optional_gaps)
        + f"return sd_torus({p} - vec3(0.1, 0.0, 0.05), 0.6, 0.2);"
        + draw(optional_gaps)
        + "}\n"
    )
    has_color = draw(st.booleans())
    if has_color:
        color_header, q = draw(header("vec3", "color"))
        source += (
            draw(optional_gaps)
            + color_header
            + f" return vec3(0.2, 0.5, 0.8) + 0.1 * {q}; "
            + draw(optional_gaps)
            + "}\n"
        )
    return source, has_color


@given(definitions())
def test_every_legal_spelling_of_the_definitions_is_accepted(definition: tuple[str, bool]) -> None:
    source, has_color = definition
    assert check_source(source) == source
    assert defines_color(source) == has_color
    wrapped = user_glsl(source)
    appended = wrapped.split(f"#line {APPENDED_FIRST_LINE}\n", 1)[1]
    assert appended == ("" if has_color else DEFAULT_COLOR_GLSL)
    # Lines and columns stay: only a parameter's `const` is blanked, to match the app's prototype.
    body = wrapped.removeprefix("\n#line 1\n").split(f"\n#line {APPENDED_FIRST_LINE}\n")[0]
    assert body.count("\n") == source.count("\n") and len(body) == len(source)


@pytest.mark.gl
@settings(max_examples=examples(12), suppress_health_check=[HealthCheck.too_slow])
@given(definitions())
def test_every_legal_spelling_samples_as_the_plain_form(definition: tuple[str, bool]) -> None:
    source, has_color = definition
    distances, colors = probe(source)
    plain_distances, plain_colors = probe(PLAIN_SDF + (PLAIN_COLOR if has_color else ""))
    np.testing.assert_allclose(distances, plain_distances, atol=1e-6)
    np.testing.assert_allclose(colors, plain_colors, atol=1e-6)


# ------------------------------------------------------------------------------------------ the public inputs
QUILEZ_STYLE = [
    "float sdf(in vec3 p) {\n    return sd_torus(p - vec3(0.1, 0.0, 0.05), 0.6, 0.2);\n}\n",
    "float sdf(const in vec3 p) {\n    return sd_torus(p - vec3(0.1, 0.0, 0.05), 0.6, 0.2);\n}\n",
    "float sdf( in vec3 p ) {\n    return sd_torus(p - vec3(0.1, 0.0, 0.05), 0.6, 0.2);\n}\n",
]


@pytest.mark.parametrize("source", QUILEZ_STYLE)
def test_quilez_and_shadertoy_style_signatures_pass_the_checks(source: str) -> None:
    assert check_source(source) == source


@pytest.mark.gl
@pytest.mark.parametrize("source", QUILEZ_STYLE)
def test_quilez_and_shadertoy_style_signatures_mesh_as_the_plain_form(source: str) -> None:
    plain = mesh_glsl(PLAIN_SDF, 48, CUBE_BOUNDS)
    tri = mesh_glsl(source, 48, CUBE_BOUNDS)
    assert len(tri.faces) == len(plain.faces) > 1000
    np.testing.assert_allclose(tri.vertices, plain.vertices, atol=1e-6)


@pytest.mark.gl
def test_a_const_in_signature_ray_marches_as_the_plain_form() -> None:
    camera = Camera((2.0, -1.5, 1.0), (0.0, 0.0, 0.0), fov_y_rad=math.radians(40))
    shading = Shading(shadows=False, occlusion=False)

    def depth(source: str) -> np.ndarray:
        return gl_service.run(lambda gl: gl.render_field(source, CUBE_BOUNDS, camera, 64, 40, shading))[1]

    plain, quilez = depth(PLAIN_SDF), depth(QUILEZ_STYLE[1])
    assert np.isfinite(plain).sum() > 300
    np.testing.assert_array_equal(quilez, plain)


@pytest.mark.gl
def test_a_color_with_in_is_the_persons_not_redefined() -> None:
    source = PLAIN_SDF + "vec3 color(in vec3 p) {\n    return vec3(0.1, 0.9, 0.3);\n}\n"
    assert defines_color(source)
    _, colors = probe(source)
    np.testing.assert_allclose(colors, np.tile([0.1, 0.9, 0.3], (len(POINTS), 1)), atol=1e-6)


def test_a_missing_closing_brace_names_the_persons_line() -> None:
    source = "float sdf(vec3 p) {\n    return length(p) - 0.5;\n"
    with pytest.raises(ShaderCompileError) as info:
        check_source(source)
    assert info.value.line == 1
    assert str(info.value).startswith("line 1: '{' is never closed")
    assert "unexpected" not in str(info.value)


@pytest.mark.gl
def test_a_missing_semicolon_says_so_in_words() -> None:
    source = (
        "float sdf(vec3 p) {\n    float r = 0.5;\n    float s = 0.2\n    float t = r + s;\n"
        "    return length(p) - t;\n}\n"
    )
    with pytest.raises(ShaderCompileError) as info:
        gl_service.run(lambda gl: gl.compile_field(source))
    assert str(info.value) == ("line 4: syntax error, missing ';' before 'float'? (line 3 ends without one)")


@pytest.mark.parametrize(
    ("log", "source", "message"),
    [
        (
            "0:3(5): error: syntax error, unexpected BASIC_TYPE_TOK, expecting ',' or ';'",
            "float sdf(vec3 p) {\n  float a = 1.0\n    float b = a;\n  return b;\n}",
            "line 3: syntax error, missing ';' before 'float'? (line 2 ends without one)",
        ),
        (
            "0:2(13): error: syntax error, unexpected NEW_IDENTIFIER, expecting ',' or ';'",
            "float sdf(vec3 p) {\n  float a b;\n  return 1.0;\n}",
            "line 2: syntax error, missing ';' before 'b'?",
        ),
        (
            "0:2(9): error: syntax error, unexpected ADD_ASSIGN",
            "float sdf(vec3 p) {\n  a = += 1.0;\n  return 1.0;\n}",
            "line 2: syntax error, unexpected '+=' here",
        ),
        (
            "0:2(2): error: syntax error, unexpected IF",
            "float sdf(vec3 p) {\n  a = if;\n  return 1.0;\n}",
            "line 2: syntax error, unexpected 'if' here",
        ),
        (
            "0:2(9): error: `foo' undeclared\n0:2(2): error: `return' with wrong type error",
            "float sdf(vec3 p) {\n  return foo;\n}",
            "line 2: 'foo' undeclared",
        ),
        (
            "0:100001(1): error: syntax error, unexpected BASIC_TYPE_TOK, expecting ',' or ';'",
            "float sdf(vec3 p) {\n  return 1.0;\n}\nfloat",
            "line 4: syntax error, the text ends too early, after 'float' (expected ',' or ';')",
        ),
        (
            "0(2) : error C0000: syntax error, unexpected '}' at token \"}\"",
            "float sdf(vec3 p) {\n}",
            "line 2: syntax error, unexpected '}' here",
        ),
    ],
)
def test_compiler_logs_read_in_words_on_the_persons_line(log: str, source: str, message: str) -> None:
    error = ShaderCompileError.from_compiler(log, source)
    assert str(error) == message
    assert not MESA_TOKEN_NAME.search(str(error))


# ------------------------------------------------------------------------------------------ one error, one line
STATEMENT = "    float a{i} = a{j} * 0.9 + 0.01;"


@st.composite
def programs(draw: st.DrawFn) -> tuple[list[str], list[int]]:
    """A valid sdf of a few statement lines, with blank and comment lines between; and the statements' indices."""
    lines = ["float sdf(vec3 p) {", "    float a0 = 0.5;"]
    statements: list[int] = []
    for i in range(1, draw(st.integers(2, 6)) + 1):
        lines += draw(st.lists(st.sampled_from(["", "    // the next one", "  "]), max_size=2))
        statements.append(len(lines))
        lines.append(STATEMENT.format(i=i, j=i - 1))
    lines += [f"    return length(p) - a{len(statements)};", "}"]
    lines = draw(st.lists(st.sampled_from(["", "// my shape"]), max_size=2)) + lines
    first = lines.index("float sdf(vec3 p) {")
    return lines, [first + k for k in statements]


COMPILE_ERRORS = {
    "missing semicolon": lambda line: line.removesuffix(";"),
    "undeclared name": lambda line: line.replace("* 0.9", "* undefined_scale"),
    "wrong call": lambda line: line.split("=")[0] + "= sd_sphere(p);",
    "wrong type": lambda line: line.split("=")[0] + "= p;",
    "missing parenthesis": lambda line: line.replace("= ", "= (", 1),
    "extra number": lambda line: line.replace("0.9", "0.9 2.0"),
    "extra operator": lambda line: line.replace("* 0.9", "* * 0.9"),
}
BRACE_ERRORS = {"unclosed if": lambda line: "    if (p.x > 0.0) {", "extra close": lambda line: "    }"}


def _inject(program: tuple[list[str], list[int]], choice: int, kind: str) -> tuple[str, int]:
    lines, statements = program
    index = statements[choice % len(statements)]
    errors = {**COMPILE_ERRORS, **BRACE_ERRORS}
    broken = [*lines[:index], errors[kind](lines[index]), *lines[index + 1 :]]
    return "\n".join(broken) + "\n", index + 1


def _assert_names_the_line(error: ShaderCompileError, line: int) -> None:
    text = str(error)
    assert re.search(rf"\bline {line}\b", text), text
    assert not MESA_TOKEN_NAME.search(text), text
    assert error.line is not None and abs(error.line - line) <= 3  # the compiler's line, or the one after


@given(programs())
def test_the_generated_programs_are_valid(program: tuple[list[str], list[int]]) -> None:
    check_source("\n".join(program[0]))


@given(programs(), st.integers(0, 10), st.sampled_from(sorted(BRACE_ERRORS)))
def test_a_brace_error_names_its_line(program: tuple[list[str], list[int]], choice: int, kind: str) -> None:
    source, line = _inject(program, choice, kind)
    with pytest.raises(ShaderCompileError) as info:
        check_source(source)
    assert info.value.line == line
    _assert_names_the_line(info.value, line)


@pytest.mark.gl
@settings(max_examples=examples(60), suppress_health_check=[HealthCheck.too_slow])
@given(programs(), st.integers(0, 10), st.sampled_from(sorted(COMPILE_ERRORS)))
def test_a_compile_error_names_its_line_in_words(program: tuple[list[str], list[int]], choice: int, kind: str) -> None:
    source, line = _inject(program, choice, kind)
    check_source(source)  # the checks pass: the compiler finds it
    with pytest.raises(ShaderCompileError) as info:
        gl_service.run(lambda gl: gl.compile_field(source))
    _assert_names_the_line(info.value, line)


# ------------------------------------------------------------------------------------------ through the scene
scene = scene_fixture(SdfGalleryScene)


@pytest.mark.gl
def test_the_editor_applies_a_const_in_source_and_names_an_unclosed_brace(
    server: viser.ViserServer, scene: SdfGalleryScene
) -> None:
    with BrowserClient(server.get_port()) as client:
        apply_glsl(client, QUILEZ_STYLE[1])
        wait_until(lambda: scene.editor_serial == 1, "the source applied", timeout_s=60)
        assert scene.editor_error is None and len(scene.mesh_faces) > 1000
        apply_glsl(client, "float sdf(in vec3 p) {\n    return length(p) - 0.5;\n")
        wait_until(lambda: scene.editor_error is not None, "the error", timeout_s=60)
        assert scene.editor_error is not None
        assert scene.editor_error.startswith("line 1: '{' is never closed")
        assert "Line 1: " in scene.editor_status.content
