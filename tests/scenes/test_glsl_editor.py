"""The editor's GLSL path without a browser: source checks, compiler errors with lines, the GL-sampled grid against
numpy, ``mesh_glsl`` against analytic shapes, and the ray-march of a typed field."""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from helpers.meshing import CUBE_BOUNDS
from helpers.properties import examples
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from kernels import sdf
from shaders import gl_service
from shaders import renderer as gl_renderer
from shaders.renderer import MAX_SOURCE_CHARS, Camera, ShaderCompileError, check_source, mesh_glsl

SPHERE = "float sdf(vec3 p) {\n    return sd_sphere(p - vec3(0.1, -0.2, 0.05), 0.55);\n}\n"


# ------------------------------------------------------------------------------------------ source checks
@pytest.mark.parametrize(
    ("source", "line", "words"),
    [
        ("float sdf(vec3 p) {\n  for (int i = 0; i < 9; i++) {}\n  return 1.0;\n}", 2, "loops"),
        ("float sdf(vec3 p) {\n  while (true) {}\n  return 1.0;\n}", 2, "loops"),
        ("#define X 1\nfloat sdf(vec3 p) { return 1.0; }", 1, "preprocessor"),
        ("float sdf(vec3 p) {\n\n  return gl_FragCoord.x;\n}", 3, "gl_FragCoord"),
        ("uniform float u;\nfloat sdf(vec3 p) { return u; }", 1, "uniform"),
        ("float sdf(vec3 p) {\n  return 1.0; // é\n}", 2, "ASCII"),
        ("void main() {}\nfloat sdf(vec3 p) { return 1.0; }", 1, "main"),
        ("float sdf(vec3 p) { /* x */ return 1.0; }", None, "block comments"),
        ("float distance_to_it(vec3 p) { return 1.0; }", None, "define float sdf"),
        ("float sdf(vec3 p) { return 1.0; }" + " " * MAX_SOURCE_CHARS, None, "limit"),
    ],
)
def test_refused_sources_say_why_and_where(source: str, line: int | None, words: str) -> None:
    with pytest.raises(ShaderCompileError, match=words) as info:
        check_source(source)
    assert info.value.line == line


def test_a_loop_word_in_a_comment_or_name_is_fine() -> None:
    check_source("float sdf(vec3 p) {\n    float format = 1.0; // for each\n    return format;\n}")


@given(st.text(max_size=300))
def test_any_text_is_either_accepted_or_refused_cleanly(text: str) -> None:
    try:
        check_source("float sdf(vec3 p) { return 1.0; }\n" + text)
    except ShaderCompileError as exc:
        assert str(exc)


# Loops in disguise: a backslash-newline splices lines for the compiler, and Mesa ends a //
# comment at a lone carriage return, so a check line by line saw other words than the compiler.
@pytest.mark.parametrize(
    ("source", "words"),
    [
        ("float sdf(vec3 p){ float s=0.0; fo\\\nr(int i=0;i<3;i++){s+=0.1;} return s; }\n", "backslash"),
        ("float sdf(vec3 p){ disc\\\nard; return 1.0; }\n", "backslash"),
        ("unif\\\norm float u;\nfloat sdf(vec3 p){ return u; }\n", "backslash"),
        ("float sdf(vec3 p){ return 1.0; } // hi\rfloat g(){ for(int i=0;i<3;i++){} return 0.0; }\n", "carriage"),
        ("float sdf(vec3 p){ return length(p)-F; }\r#define F 1.0\r", "carriage"),
        ("float sdf(vec3 p){ return length(p)-1.0; } // x \\\n\n", "backslash"),
        ("float sdf(vec3 p){ return 1.0; } # define X\n", "preprocessor"),
    ],
)
def test_line_splices_and_carriage_returns_are_refused(source: str, words: str) -> None:
    with pytest.raises(ShaderCompileError, match=words):
        check_source(source)


_CONSTRUCTS = [
    "for(int i=0;i<3;i++){}",
    "while(true){}",
    "do{}while(true);",
    "discard;",
    "uniform float u;",
    "#define X 1",
    "void main(){}",
]


def _compiler_view(source: str) -> str:
    """What a GLSL compiler reads: continuations spliced, a carriage return as a line end, // comments gone."""
    spliced = re.sub(r"\\\r?\n", "", source).replace("\r", "\n")
    return "\n".join(line.split("//", 1)[0] for line in spliced.split("\n"))


@given(
    st.sampled_from(_CONSTRUCTS),
    st.lists(st.integers(0, 40), max_size=3),
    st.sampled_from(["\\\n", "\\\r\n", "\r", "// c\r", "// c\\\n"]),
)
def test_no_disguise_of_a_forbidden_construct_gets_through(construct: str, cuts: list[int], disguise: str) -> None:
    # The construct cut anywhere by a continuation, or hidden after a comment a carriage return ends: the
    # compiler would see it, so the check must refuse the text.
    text = construct
    for cut in sorted({c % (len(construct) + 1) for c in cuts}, reverse=True):
        text = text[:cut] + disguise + text[cut:]
    if not cuts:
        text = disguise + text
    source = "float sdf(vec3 p) { return 1.0; }\n" + text + "\n"
    with pytest.raises(ShaderCompileError):
        check_source(source)


@given(st.text(alphabet=st.sampled_from(list("for wdiscaueUnm#/\\\r\n\t(){};x")), max_size=80))
def test_accepted_text_shows_the_compiler_no_forbidden_word(text: str) -> None:
    source = "float sdf(vec3 p) { return 1.0; }\n" + text
    try:
        check_source(source)
    except ShaderCompileError:
        return
    seen = _compiler_view(source)
    assert "#" not in seen
    words = set(re.findall(r"[A-Za-z_]\w*", seen))
    assert not words & {"for", "while", "do", "discard", "uniform", "main"}


def _chain(links: int, calls: int = 2) -> str:
    lines = ["float f0(vec3 p){ return length(p)-1.0; }"]
    for i in range(1, links + 1):
        args = ", ".join(f"f{i - 1}(p*{1 + j / 100:.2f})" for j in range(calls))
        lines.append(
            f"float f{i}(vec3 p){{ return min(0.0, min({args}, 1.0)); }}"
            if calls > 1
            else f"float f{i}(vec3 p){{ return f{i - 1}(p*1.01); }}"
        )
    lines.append(f"float sdf(vec3 p){{ return f{links}(p); }}")
    return "\n".join(lines) + "\n"


def test_a_ten_link_call_chain_is_refused_for_its_inlined_size() -> None:
    source = (
        "float f0(vec3 p){ return length(p)-1.0; }\n"
        + "".join(
            f"float f{i}(vec3 p){{ return min(f{i - 1}(p*1.01), f{i - 1}(p.yzx+0.01)); }}\n" for i in range(1, 11)
        )
        + "float sdf(vec3 p){ return f10(p); }\n"
    )
    assert len(source) == 679
    with pytest.raises(ShaderCompileError, match=r"36846 tokens.*limit is 20000"):
        check_source(source)


@given(st.integers(1, 12), st.integers(1, 3))
def test_inlined_size_multiplies_by_the_calls_at_each_link(links: int, calls: int) -> None:
    sizes = gl_renderer.inlined_sizes(_chain(links, calls))
    for i in range(1, links + 1):
        own = sizes[f"f{i}"] - calls * sizes[f"f{i - 1}"]
        assert own == sizes["f1"] - calls * sizes["f0"]  # every link's own tokens are the same
    expected_ok = sizes["sdf"] <= gl_renderer.MAX_INLINED_TOKENS
    try:
        check_source(_chain(links, calls))
        assert expected_ok
    except ShaderCompileError as exc:
        assert not expected_ok and "inlined" in str(exc)


def test_compiler_logs_of_both_vendors_give_the_line() -> None:
    mesa = "GLSL Compiler failed\n\nfragment_shader\n===\n0:3(16): error: syntax error, unexpected ';'\n"
    nvidia = "0(2) : error C0000: syntax error, unexpected '}' at token \"}\"\n"
    assert ShaderCompileError.from_compiler(mesa, "a\nb\nc").line == 3
    assert ShaderCompileError.from_compiler(nvidia, "a\nb\nc").line == 2
    # An error outside the person's text (in the app's own code) has no line of theirs.
    assert ShaderCompileError.from_compiler(mesa.replace("0:3", "0:90"), "a\nb").line is None


@pytest.mark.gl
def test_compile_error_is_a_value_error_with_the_compilers_message_and_line() -> None:
    bad = "float sdf(vec3 p) {\n    float r = 0.5;\n    return sd_sphere(p, r) +;\n}\n"
    with pytest.raises(ValueError, match=r"^line 3: .*syntax error") as info:
        mesh_glsl(bad, 32, CUBE_BOUNDS)
    assert isinstance(info.value, ShaderCompileError) and info.value.line == 3
    with pytest.raises(ValueError, match="line 2"):
        mesh_glsl("float sdf(vec3 p) {\n    return sd_sphere(p, 1.0, 2.0);\n}", 32, CUBE_BOUNDS)


@pytest.mark.gl
@pytest.mark.parametrize(
    ("source", "line"),
    [
        # An outside tester: "function 'float sdf(vec3)' has static recursion", with no line (Mesa's linker names
        # none); the line is the recursive call's.
        ("float sdf(vec3 p){ return p.x > 0.0 ? sdf(-p) : length(p)-0.5; }\n", 1),
        (
            "float f(vec3 p) {\n  return length(p) - 0.5;\n}\n"
            "float sdf(vec3 p)\n{\n  float d = f(p);\n  return d + sdf(p);\n}\n",
            7,
        ),
        ("float g(vec3 p) {\n  return 1.0 + g(p * 0.5);\n}\nfloat sdf(vec3 p) { return g(p); }\n", 2),
    ],
)
def test_a_function_that_calls_itself_is_refused_on_the_line_of_the_call(source: str, line: int) -> None:
    with pytest.raises(ShaderCompileError) as refused:
        mesh_glsl(source, 32, CUBE_BOUNDS)
    assert refused.value.line == line and "calls itself, and GLSL has no recursion" in str(refused.value)
    # Through a prototype (a re-tester's): b() calls a(), declared above b() and defined below it, which calls b().
    mutual = (
        "float a(vec3 p);\nfloat b(vec3 p){\n  return a(p);\n}\n"
        "float a(vec3 p){ return b(p*0.5); }\nfloat sdf(vec3 p){ return a(p); }\n"
    )
    with pytest.raises(ShaderCompileError) as refused:
        mesh_glsl(mutual, 32, CUBE_BOUNDS)
    # (Mesa names either function of the cycle; the words name the call that closes it from the one named.)
    assert str(refused.value) in (
        "line 3: b() calls a(), which calls back into b(): GLSL has no recursion",
        "line 5: a() calls b(), which calls back into a(): GLSL has no recursion",
    )
    # An overload calling another of its name is no recursion: it compiles.
    overload = (
        "float g(float x) { return x - 0.5; }\nfloat g(vec3 p) { return g(length(p)); }\n"
        "float sdf(vec3 p) { return g(p); }\n"
    )
    assert len(mesh_glsl(overload, 32, CUBE_BOUNDS).faces) > 0


@pytest.mark.gl
def test_a_function_used_above_its_definition_is_named_with_where_it_is() -> None:
    # A re-tester: "line 1: no function with name 'g'", with g defined on the next line (GLSL wants it above).
    source = (
        "float f(vec3 p){ return g(p); }\nfloat g(vec3 p) { return length(p) - 0.5; }\n"
        "float sdf(vec3 p){ return f(p); }\n"
    )
    with pytest.raises(ShaderCompileError) as refused:
        mesh_glsl(source, 32, CUBE_BOUNDS)
    assert str(refused.value) == "line 1: g() is used before it is defined (line 2): define it above its first use"
    # A function defined nowhere keeps the compiler's words.
    with pytest.raises(ShaderCompileError, match=r"^line 1: no function with name 'h'$"):
        mesh_glsl("float sdf(vec3 p){ return h(p); }\n", 32, CUBE_BOUNDS)


@pytest.mark.gl
@pytest.mark.parametrize(
    ("resolution", "bounds", "words"),
    [
        (8, CUBE_BOUNDS, "resolution"),
        (64, [[0, 0, 0], [0, 1, 1]], "bounds"),
        (64, [[0, 0, 0], [np.nan, 1, 1]], "bounds"),
    ],
)
def test_bad_resolution_or_bounds_raise(resolution: int, bounds: object, words: str) -> None:
    with pytest.raises(ValueError, match=words):
        mesh_glsl(SPHERE, resolution, bounds)  # type: ignore[arg-type]


@pytest.mark.gl
def test_nan_field_is_refused() -> None:
    with pytest.raises(ValueError, match="NaN"):
        mesh_glsl("float sdf(vec3 p) {\n    return sqrt(-1.0 - p.x * p.x);\n}", 32, CUBE_BOUNDS)


# ------------------------------------------------------------------------------------------ sampling and mesh
@pytest.mark.gl
def test_gl_sampled_grid_equals_numpy_at_every_sample() -> None:
    source = (
        "float sdf(vec3 p) {\n    return smooth_union(sd_cylinder(p, 0.5, 0.3), "
        "sd_octahedron(p - vec3(0.3, 0.2, 0.1), 0.4), 0.2, BLEND_POLY);\n}\n"
    )
    grid = sdf.make_grid(sdf.default_scene(), 48, CUBE_BOUNDS)
    field = gl_service.run(lambda gl: gl.sample_field(source, grid))
    axes = [grid.origin[i] + grid.spacing * np.arange(grid.shape[i]) for i in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    expected = sdf.smooth_union(
        sdf.sd_cylinder(points, 0.5, 0.3), sdf.sd_octahedron(points - [0.3, 0.2, 0.1], 0.4), 0.2
    ).reshape(grid.shape)
    assert field.shape == grid.shape
    np.testing.assert_allclose(field, expected, atol=1e-5, rtol=0)


@pytest.mark.gl
@pytest.mark.parametrize("name", ["smooth_union", "smooth_subtract", "smooth_intersect"])
def test_a_blend_called_without_its_form_is_the_polynomial_one_as_in_python(name: str) -> None:
    # An outside tester: `smooth_union(d, x, .1)` works in Python (the blend defaults to "poly") but was refused in
    # the editor, "no matching function for call to 'smooth_union(float, float, float)'".
    call = f"{name}(sd_sphere(p, 0.6), sd_box(p - vec3(0.4, 0.1, 0.0), vec3(0.3)), 0.15"
    grid = sdf.make_grid(sdf.default_scene(), 32, CUBE_BOUNDS)
    three = gl_service.run(lambda gl: gl.sample_field(f"float sdf(vec3 p) {{ return {call}); }}", grid))
    four = gl_service.run(lambda gl: gl.sample_field(f"float sdf(vec3 p) {{ return {call}, BLEND_POLY); }}", grid))
    np.testing.assert_array_equal(three, four)
    axes = [grid.origin[i] + grid.spacing * np.arange(grid.shape[i]) for i in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    a, b = sdf.sd_sphere(points, 0.6), sdf.sd_box(points - [0.4, 0.1, 0.0], [0.3, 0.3, 0.3])
    expected = getattr(sdf, name)(a, b, 0.15).reshape(grid.shape)  # Python's default form
    np.testing.assert_allclose(three, expected, atol=1e-5, rtol=0)


@pytest.mark.gl
def test_a_grid_sampled_a_slab_at_a_time_is_the_grid_sampled_whole() -> None:
    grid = sdf.make_grid(sdf.default_scene(), 160, CUBE_BOUNDS)  # 51 planes a draw: four slabs, the last of 7
    assert gl_renderer.slab_planes(grid) == 51 and grid.shape[2] == 160
    whole = gl_service.run(lambda gl: gl.sample_field(SPHERE, grid))
    np.testing.assert_array_equal(gl_renderer.sample_glsl(SPHERE, grid), whole)
    middle = gl_service.run(lambda gl: gl.sample_field(SPHERE, grid, (51, 102)))
    np.testing.assert_array_equal(middle, whole[:, :, 51:102])
    for planes in [(0, 0), (-1, 5), (100, 161), (5, 3)]:
        with pytest.raises(ValueError, match="planes"):
            gl_service.run(lambda gl, planes=planes: gl.sample_field(SPHERE, grid, planes))


@pytest.mark.gl
def test_another_callers_gl_work_runs_between_the_slabs_of_a_costly_field(monkeypatch: pytest.MonkeyPatch) -> None:
    # Kind: one caller holding the process's one GL thread. A nine-level field meshed at 256³ took 6 s as one GL job,
    # and another gallery tab's light slider waited 4.6 s for its frame. Its samples are now drawn a slab at a time,
    # and marching cubes runs on the caller's thread: a job that arrives meanwhile waits for one slab at most.
    real_run = gl_service.run
    slabs: list[int] = []
    seen_by_the_other: list[int] = []

    def run(job: Any) -> Any:
        def slab(gl: gl_renderer.Renderer) -> Any:
            out = job(gl)
            slabs.append(1)
            if len(slabs) == 1:  # another tab's frame, asked for while the first slab is drawn
                gl_service.submit(lambda _gl: seen_by_the_other.append(len(slabs)))
            return out

        return real_run(slab)

    monkeypatch.setattr(gl_service, "run", run)
    tri = mesh_glsl(SPHERE, 160, CUBE_BOUNDS)
    assert len(tri.faces) > 0
    assert len(slabs) >= 4 + 2  # four slabs, then the gradient noted and the colours probed
    assert seen_by_the_other == [1]


@pytest.mark.gl
def test_gl_sampled_grid_in_several_draws_is_the_same() -> None:
    grid = sdf.make_grid(sdf.default_scene(), 200, CUBE_BOUNDS)  # 200·200 rows > 8192: several draws
    field = gl_service.run(lambda gl: gl.sample_field(SPHERE, grid))
    k = np.arange(grid.shape[2])
    z = grid.origin[2] + grid.spacing * k
    column = field[grid.shape[0] // 2, grid.shape[1] // 2]
    x = grid.origin[0] + grid.spacing * (grid.shape[0] // 2)
    y = grid.origin[1] + grid.spacing * (grid.shape[1] // 2)
    expected = np.sqrt((x - 0.1) ** 2 + (y + 0.2) ** 2 + (z - 0.05) ** 2) - 0.55
    np.testing.assert_allclose(column, expected, atol=1e-5)


@pytest.mark.gl
def test_mesh_glsl_of_a_sphere_is_the_sphere_with_its_colour() -> None:
    source = SPHERE + "vec3 color(vec3 p) {\n    return vec3(0.2, 0.4, 0.8);\n}\n"
    tri = mesh_glsl(source, 64, CUBE_BOUNDS)
    radii = np.linalg.norm(tri.vertices - [0.1, -0.2, 0.05], axis=1)
    spacing = 2.0 / 63
    assert np.abs(radii - 0.55).max() < 0.1 * spacing
    assert tri.is_watertight
    assert tri.volume == pytest.approx(4 / 3 * math.pi * 0.55**3, rel=0.01)
    visual = tri.visual
    assert visual is not None
    colors = np.asarray(visual.vertex_colors)[:, :3]  # pyright: ignore[reportAttributeAccessIssue]
    assert np.all(colors == np.round(np.array([0.2, 0.4, 0.8]) * 255))


@pytest.mark.gl
def test_mesh_glsl_equals_the_numpy_mesher_on_the_same_field() -> None:
    """One algorithm: the GL-sampled field goes through the kernel's marching-cubes pass."""
    source = "float sdf(vec3 p) {\n    return sd_round_box(p, vec3(0.6, 0.4, 0.3), 0.1);\n}\n"
    tri = mesh_glsl(source, 48, CUBE_BOUNDS)
    grid = sdf.make_grid(sdf.default_scene(), 48, CUBE_BOUNDS)
    axes = [grid.origin[i] + grid.spacing * np.arange(grid.shape[i]) for i in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    field = sdf.sd_round_box(points, (0.6, 0.4, 0.3), 0.1).astype(np.float32).reshape(grid.shape)
    vertices, faces = sdf.mesh_samples(grid, field)
    assert len(tri.faces) == len(faces)
    np.testing.assert_allclose(np.sort(tri.vertices, axis=0), np.sort(vertices, axis=0), atol=1e-5)


# Kind: samples on the zero level judged by a field other than the one meshed. Which level samples hold volume was
# read from a stand-in unit sphere, not the editor's source: sd_plane(p, (0, 0, 1), 0.5), on a grid plane of a
# 64-sample ±1.5 m grid, put 112 vertices a third of a voxel under the plane, where the sphere's section lay (an
# outside tester); read from the source, the 248 vertices on the bounds' faces were still a third of a voxel off.
@pytest.mark.gl
@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_plane_on_a_grid_plane_meshes_on_it_out_to_the_bounds(axis: int, sign: float) -> None:
    normal = ", ".join(f"{sign if k == axis else 0.0:.1f}" for k in range(3))
    tri = mesh_glsl(f"float sdf(vec3 p) {{ return sd_plane(p, vec3({normal}), 0.5); }}", 64, [[-1.5] * 3, [1.5] * 3])
    spacing = 3.0 / 63.0  # the plane p·n = −0.5 lies on sample plane 21
    assert len(tri.faces) > 0
    np.testing.assert_allclose(tri.vertices[:, axis], -0.5 * sign, atol=2.0 * sdf.ISO_NUDGE_VOXELS * spacing + 1e-6)
    assert tri.vertices[:, (axis + 1) % 3].min() == pytest.approx(-1.5) and tri.vertices.max() == pytest.approx(1.5)


@pytest.mark.gl
def test_empty_field_gives_an_empty_mesh() -> None:
    tri = mesh_glsl("float sdf(vec3 p) {\n    return 1.0;\n}\n", 32, CUBE_BOUNDS)
    assert len(tri.faces) == 0


# Thin shells: the mesher's cell mask once kept only cells with a corner within a cell diagonal of zero, which assumes
# |∇d| ≤ 1; a typed field need not be a distance, and K·(length(p) − 1) lost most of its faces for K = 3, 10, 100.
WIDE = np.array([[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]])


def scaled_sphere(k: float) -> str:
    return f"float sdf(vec3 p) {{ return {k:.9g} * (length(p) - 1.0); }}"


@pytest.mark.gl
@pytest.mark.parametrize("k", [3.0, 10.0, 100.0, 1e30])
def test_a_steep_field_meshes_watertight_with_the_spheres_area(k: float) -> None:
    tri = mesh_glsl(scaled_sphere(k), 64, WIDE)
    assert tri.is_watertight
    assert tri.area == pytest.approx(4 * math.pi, rel=0.005)  # 12.57 m², not 8.05, 2.5 or 0.39


STEEPER_THAN_FLOAT32 = [
    ("3e38 * (length(p) - 1.0)", "length(p) - 1.0"),
    ("length(p) < 1.0 ? -3e38 : 3e38", "length(p) < 1.0 ? -1.0 : 1.0"),
]
"""Fields whose slope is over float32's largest number, each beside its scaled-down twin."""


@pytest.mark.gl
@pytest.mark.parametrize(("steep", "plain"), STEEPER_THAN_FLOAT32)
def test_a_field_steeper_than_float32_meshes_as_its_scaled_down_twin(steep: str, plain: str) -> None:
    # Kind: a slope over float32's largest number (an outside tester). Its cast overflowed to inf and divided the
    # field to ±0: a blocky mesh (4.36 m³ against 4.19), 2.5 s instead of 0.1 s, and a RuntimeWarning.
    bounds = np.array([[-1.2] * 3, [1.2] * 3])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = mesh_glsl(f"float sdf(vec3 p) {{ return {steep}; }}", 64, bounds)
    want = mesh_glsl(f"float sdf(vec3 p) {{ return {plain}; }}", 64, bounds)
    assert len(got.faces) == len(want.faces) and got.is_watertight
    assert got.volume == pytest.approx(want.volume, rel=1e-4)


@pytest.mark.gl
@pytest.mark.parametrize(("steep", "plain"), STEEPER_THAN_FLOAT32)
def test_a_field_steeper_than_float32_marches_as_its_scaled_down_twin(steep: str, plain: str) -> None:
    # The march divided by the slope held at float32's largest: a ±3e38 step was marched in 0.9 m strides, a
    # three-lobed blob over its sphere's mesh (IoU 0.93; an outside tester). The root of the slope fits.
    bounds = np.array([[-1.2] * 3, [1.2] * 3])
    camera = Camera((2.6, -2.0, 1.4), (0.0, 0.0, 0.0), fov_y_rad=math.radians(40))
    depths = []
    for body in (steep, plain):
        source = f"float sdf(vec3 p) {{ return {body}; }}"
        assert len(mesh_glsl(source, 64, bounds).faces) > 1000
        depths.append(gl_service.run(lambda gl, s=source: gl.render_field(s, bounds, camera, 96, 64))[1])
    got, want = depths
    hit = np.isfinite(want)
    assert hit.sum() > 500 and np.array_equal(np.isfinite(got), hit)
    np.testing.assert_allclose(got[hit], want[hit], atol=2e-3)


@pytest.mark.gl
def test_the_elongation_example_is_watertight() -> None:
    source = next(s for title, s in gl_renderer.examples().items() if title.startswith("Elongation"))
    tri = mesh_glsl(source, 64, WIDE)
    assert tri.is_watertight and len(tri.faces) == 6500


@pytest.mark.gl
@settings(max_examples=examples(25))
@given(
    st.floats(-6.0, 30.0),
    st.sampled_from(
        [
            "length(p) - 1.0",
            "sd_box(p - vec3(0.013, 0.021, 0.017), vec3(0.7, 0.5, 0.9))",
            "sd_torus(p - vec3(0.011, 0.0, 0.023), 0.8, 0.3)",
        ]
    ),
)
def test_a_positive_scale_of_the_field_changes_nothing(exponent: float, body: str) -> None:
    # Marching cubes interpolates linearly between corners, so K·sdf has sdf's mesh for every K > 0 (the shapes
    # are moved off the grid's planes: a sample exactly on the level is a tie float rounding may break either way).
    k = 10.0**exponent
    reference = mesh_glsl(f"float sdf(vec3 p) {{ return {body}; }}", 40, WIDE)
    scaled = mesh_glsl(f"float sdf(vec3 p) {{ return {k:.9g} * ({body}); }}", 40, WIDE)
    assert scaled.is_watertight and reference.is_watertight
    assert len(scaled.faces) == len(reference.faces)
    assert scaled.area == pytest.approx(reference.area, rel=1e-4)


# ------------------------------------------------------------------------------------------ ray-march
def _sphere_depth(camera: Camera) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The depth along the view axis of SPHERE (centre (0.1, −0.2, 0.05), radius 0.55) on a 96 × 64 image, and each
    ray's discriminant (< 0: a miss; near 0: a grazing ray), from the ray–sphere quadratic."""
    origins, dirs = gl_renderer.camera_rays(camera, 96, 64)
    oc = origins - [0.1, -0.2, 0.05]
    b = np.sum(oc * dirs, axis=1)
    disc = b * b - (np.sum(oc * oc, axis=1) - 0.55**2)
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    forward, _, _ = camera.basis()
    return (t * (dirs @ forward)).reshape(64, 96), disc.reshape(64, 96)


@pytest.mark.gl
@pytest.mark.parametrize(
    ("k", "meshed"),
    [(1.0, False), (1.0, True), (1e38, True), (1e30, True), (1e6, True), (3.0, True), (0.2, True), (1e-6, True)],
)
def test_the_field_raymarch_is_the_analytic_sphere_at_any_scale_once_meshed(k: float, meshed: bool) -> None:
    # Once: 1e30·sdf meshed as the sphere but ray-marched to nothing (every step overshot), and 1e-6·sdf stopped
    # short (IoU 0.07). Meshed first, as the gallery does, the march divides by the gradient the mesher measured.
    camera = Camera((2.0, -1.5, 1.0), (0.1, -0.2, 0.05), fov_y_rad=math.radians(40))
    scaled = SPHERE if k == 1.0 else SPHERE.replace("return ", f"return {k:.9g} * ")
    if meshed:
        assert len(mesh_glsl(scaled, 48, CUBE_BOUNDS).faces) > 500
    _, depth = gl_service.run(lambda gl: gl.render_field(scaled, CUBE_BOUNDS, camera, 96, 64))
    expected, disc = _sphere_depth(camera)
    hit = disc > 0.01  # away from grazing rays
    assert hit.sum() > 500
    np.testing.assert_allclose(depth[hit], expected[hit], atol=2e-3)
    clear_miss = disc < -0.01
    assert clear_miss.sum() > 500 and np.all(np.isinf(depth[clear_miss]))


# Kind: a field that is a distance bound but jumps (its value steps between neighbouring samples). The march divided
# such a field by its steepest difference quotient, which is the jump's and grows as the spacing shrinks: an outside
# tester's `p.x > 1.2 ? 0.2 : length(p) - 1.0` was drawn shrunken, its IoU with its own mesh 0.74.
JUMPS = [
    "p.x > 0.8 ? 0.12 : {d}",  # beyond x = 0.8 the sphere is at least 0.15 m away: a bound
    "min({d}, p.y > 0.5 ? 0.1 : 10.0)",  # likewise beyond y = 0.5 (0.15 m)
    "p.z < -0.7 ? 0.05 : {d}",  # below z = −0.7 (0.2 m)
]


@pytest.mark.gl
@pytest.mark.parametrize("jump", JUMPS)
def test_a_distance_bound_with_a_jump_marches_to_the_analytic_sphere_once_meshed(jump: str) -> None:
    camera = Camera((2.0, -1.5, 1.0), (0.1, -0.2, 0.05), fov_y_rad=math.radians(40))
    sphere = "sd_sphere(p - vec3(0.1, -0.2, 0.05), 0.55)"
    source = f"float sdf(vec3 p) {{\n    return {jump.format(d=sphere)};\n}}\n"
    assert len(mesh_glsl(source, 48, CUBE_BOUNDS).faces) > 500
    _, depth = gl_service.run(lambda gl: gl.render_field(source, CUBE_BOUNDS, camera, 96, 64))
    expected, disc = _sphere_depth(camera)
    hit = disc > 0.01
    np.testing.assert_allclose(depth[hit], expected[hit], atol=2e-3)
    assert np.all(np.isinf(depth[disc < -0.01]))


def _grid_field(
    n: int, field: Callable[[NDArray[np.float64]], NDArray[np.float64]]
) -> tuple[NDArray[np.float32], float]:
    x = np.linspace(-1.5, 1.5, n)
    points = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1)
    return field(points).astype(np.float32), float(x[1] - x[0])


def _radius(p: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.linalg.norm(p, axis=-1)


@pytest.mark.parametrize("n", [33, 48, 64, 97, 128])
def test_the_steepest_slope_leaves_out_jumps_at_every_spacing(n: int) -> None:
    # A jump's quotient was 19, 26 and 39 at 48, 64 and 97 samples a side: it grew as the spacing shrank. Slopes
    # are kept wherever they are, a steep one far from the surface too (the march would overshoot without it).
    fields = {
        "sphere": (lambda p: _radius(p) - 1.0, (1.0, 1.1)),
        "3 × sphere": (lambda p: 3.0 * (_radius(p) - 1.0), (3.0, 3.3)),
        "a jump": (lambda p: np.where(p[..., 0] > 1.2, 0.2, _radius(p) - 1.0), (1.0, 1.5)),
        "a jump in a min": (lambda p: np.minimum(_radius(p) - 1.0, np.where(p[..., 1] > 1.4, 0.05, 10.0)), (1.0, 1.5)),
        "steep far out": (
            lambda p: np.where(_radius(p) < 1.2, _radius(p) - 1.0, 0.2 + 3.0 * (_radius(p) - 1.2)),
            (3.0, 3.3),
        ),
        "a kink": (lambda p: np.abs(p[..., 0]) - 0.5, (1.0, 1.001)),
        # Quilez's ellipsoid bound is singular at its centre, inside: its quotient there grew from 3.8 to 12.
        "an ellipsoid bound": (
            lambda p: sdf.sd_ellipsoid(p.reshape(-1, 3), (0.6, 0.35, 0.25)).reshape(p.shape[:-1]),
            (1.0, 1.6),
        ),
    }
    for name, (field, (low, high)) in fields.items():
        samples, spacing = _grid_field(n, field)
        assert low * (1 - 1e-6) <= gl_renderer.lipschitz_estimate(samples, spacing) <= high, name


def test_examples_are_at_least_six_and_pass_the_checks() -> None:
    examples = gl_renderer.examples()
    assert len(examples) >= 6
    for title, source in examples.items():
        assert title and check_source(source) == source
