// Signed distance functions: mirrors kernels/sdf/ name for name (float32 here, float64 there).
// Included with moderngl's ctx.includes by raymarch.frag, probe.frag and mesh.frag; it has no #version of its own.
// The scene arrives as uniforms, so changing it never recompiles a program.

#define MAX_PRIMITIVES 4
// The kinds' codes, KIND_<NAME>, and FIRST_CATALOGUE_KIND: written from kernels/sdf/primitives.py's registry
// (shaders/glsl_library.py) in place of the next line.
// @KIND_DEFINES
// kernels/sdf ROUND_BOX_ROUNDING: a scene's round box is rounded by this fraction of its smallest half size.
#define ROUND_BOX_ROUNDING 0.25
#define OP_UNION 0
#define OP_SUBTRACT 1
#define OP_INTERSECT 2
#define BLEND_POLY 0
#define BLEND_EXP 1
// kernels/sdf EXP_SHARPNESS_PER_WIDTH = 4 ln 2: both blends dip by k/4 where two surfaces meet.
#define EXP_SHARPNESS_PER_WIDTH 2.772588722239781

uniform int u_count;                              // primitives in use, 1..4
uniform int u_kind[MAX_PRIMITIVES];               // KIND_*
uniform int u_op[MAX_PRIMITIVES];                 // OP_*; the first primitive's op is not used
uniform vec3 u_center[MAX_PRIMITIVES];            // world position of each local origin (m)
uniform vec3 u_size[MAX_PRIMITIVES];              // the kind's parameters (m), unused slots zero
uniform mat3 u_world_to_local[MAX_PRIMITIVES];    // R transposed
uniform vec3 u_color[MAX_PRIMITIVES];             // linear RGB
uniform float u_k;                                // blend width (m); 0 is hard
uniform int u_blend;                              // BLEND_*

// ------------------------------------------------------------------------------ primitives
float sd_sphere(vec3 p, float radius) {
    return length(p) - radius;
}

float sd_box(vec3 p, vec3 half_size) {
    vec3 q = abs(p) - half_size;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

// The ring lies in the local xz plane.
float sd_torus(vec3 p, float major_radius, float minor_radius) {
    vec2 q = vec2(length(p.xz) - major_radius, p.y);
    return length(q) - minor_radius;
}

float sd_capsule(vec3 p, vec3 a, vec3 b, float radius) {
    vec3 pa = p - a;
    vec3 ba = b - a;
    float length_sq = dot(ba, ba);
    float h = length_sq == 0.0 ? 0.0 : clamp(dot(pa, ba) / length_sq, 0.0, 1.0);
    return length(pa - ba * h) - radius;
}

// ------------------------------------------------------------------------------ blends
// Each *_weighted form returns (distance, weight of b), the weight that blends colours. Both are finite for every
// finite width k >= 0 and tend to the hard minimum as k -> 0 (kernels/sdf holds the same property).
// kernels/sdf MIN_BLEND_WIDTH, float32's smallest normal: a width below it (0, or a subnormal that a GPU may flush
// to 0) is the hard minimum, its dip k/4 being below any distance's rounding; above it 0.5 / k stays finite.
#define MIN_BLEND_WIDTH 1.17549435e-38

// Distances may be infinite (a float32 length overflows past ~1.8e19 m): the gap is 0 where a = b, the same infinity
// included (not inf - inf), and where h is 0 or 1 the result is b or a outright (not 0 * inf), as in kernels/sdf.
#define FLOAT32_MAX 3.40282347e38
vec2 smin_poly_weighted(float a, float b, float k) {
    bool hard = !(k >= MIN_BLEND_WIDTH);
    float width = hard ? 1.0 : min(k, FLOAT32_MAX);
    float gap = a == b ? 0.0 : b - a;
    // (0.5 * gap) / width may overflow to +-inf, which the clamp maps to 0 or 1. Not gap * (0.5 / width): past
    // width 4e37 that factor is subnormal, a GPU flushes it to 0, and inf * 0 is NaN.
    float h = clamp(0.5 + (0.5 * gap) / width, 0.0, 1.0);
    float blended = h * a + (1.0 - h) * b - width * h * (1.0 - h);
    vec2 smooth_min = vec2(h == 0.0 ? b : (h == 1.0 ? a : blended), 1.0 - h);
    return hard ? vec2(min(a, b), b < a ? 1.0 : 0.0) : smooth_min;
}

// k is the sharpness (1/m); min(a, b) - log(1 + exp(-k|a - b|))/k cannot overflow, and the weight of b,
// exp(-kb)/(exp(-ka) + exp(-kb)), reuses the same exponential. Where a = b (the same infinity included) the
// exponential is 1 outright, so an infinite sharpness (the hard minimum) never meets inf * 0. A sharpness below
// float32's smallest normal (a huge width; a GPU may flush it to 0) is that normal, so log(2)/k stays finite.
vec2 smin_exp_weighted(float a, float b, float k) {
    float sharpness = max(k, MIN_BLEND_WIDTH);
    float gap = a == b ? 0.0 : abs(a - b);
    float e = gap == 0.0 ? 1.0 : exp(-sharpness * gap);
    float d = min(a, b) - log(1.0 + e) / sharpness;
    return vec2(d, a > b ? 1.0 / (1.0 + e) : e / (1.0 + e));
}

float smin_poly(float a, float b, float k) {
    return smin_poly_weighted(a, b, k).x;
}

float smin_exp(float a, float b, float k) {
    return smin_exp_weighted(a, b, k).x;
}

float op_union(float a, float b) {
    return min(a, b);
}

float op_subtract(float a, float b) {
    return max(a, -b);
}

float op_intersect(float a, float b) {
    return max(a, b);
}

// llvmpipe (Mesa's CPU driver) runs every side of a branch under a lane mask, even when the condition is a
// uniform, so the choices below are written as selects between values computed once. A program that defines
// POLY_BLEND_ONLY 1 (the renderer's ray-march variant for polynomial and hard blends) leaves the exponential blend
// out: its exp and log would otherwise cost as much as the rest of the scene.
#ifndef POLY_BLEND_ONLY
#define POLY_BLEND_ONLY 0
#endif
vec2 smin_blend(float a, float b, float k, int blend) {
    vec2 poly = smin_poly_weighted(a, b, k);  // the hard minimum for k below MIN_BLEND_WIDTH
#if POLY_BLEND_ONLY
    return poly;
#else
    // The width is at least MIN_BLEND_WIDTH here, so the sharpness stays below 2.4e38: finite in float32.
    vec2 expo = smin_exp_weighted(a, b, EXP_SHARPNESS_PER_WIDTH / max(k, MIN_BLEND_WIDTH));
    return (blend == BLEND_EXP && k >= MIN_BLEND_WIDTH) ? expo : poly;
#endif
}

// Distance of (a op b) and the weight of b; k is the blend width (m). Union smin(a, b), subtraction
// -smin(-a, b), intersection -smin(-a, -b): one blend with signs, not three.
vec2 combine(float a, float b, int op, float k, int blend) {
    float sign_a = op == OP_UNION ? 1.0 : -1.0;
    float sign_b = op == OP_INTERSECT ? -1.0 : 1.0;
    vec2 r = smin_blend(sign_a * a, sign_b * b, k, blend);
    return vec2(sign_a * r.x, r.y);
}

float smooth_union(float a, float b, float k, int blend) {
    return combine(a, b, OP_UNION, k, blend).x;
}

float smooth_subtract(float a, float b, float k, int blend) {
    return combine(a, b, OP_SUBTRACT, k, blend).x;
}

float smooth_intersect(float a, float b, float k, int blend) {
    return combine(a, b, OP_INTERSECT, k, blend).x;
}

// Without a blend, the polynomial one: kernels/sdf's default, so a call written for either reads the same.
float smooth_union(float a, float b, float k) { return smooth_union(a, b, k, BLEND_POLY); }
float smooth_subtract(float a, float b, float k) { return smooth_subtract(a, b, k, BLEND_POLY); }
float smooth_intersect(float a, float b, float k) { return smooth_intersect(a, b, k, BLEND_POLY); }

// ------------------------------------------------------------------------------ more primitives
// After I. Quilez, "distance functions" (iquilezles.org/articles/distfunctions); kernels/sdf has the same names,
// arguments and frames, and says which are exact and which only bounds.
float sd_cylinder(vec3 p, float half_height, float radius) {  // exact; capped, along y
    vec2 d = vec2(length(p.xz) - radius, abs(p.y) - half_height);
    return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}

float sd_round_box(vec3 p, vec3 half_size, float radius) {  // exact; outer half extents, edges rounded
    vec3 q = abs(p) - half_size + radius;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0) - radius;
}

float sd_octahedron(vec3 p, float size) {  // exact; |x| + |y| + |z| = size
    p = abs(p);
    float m = p.x + p.y + p.z - size;
    vec3 q;
    if (3.0 * p.x < m) {
        q = p.xyz;
    } else if (3.0 * p.y < m) {
        q = p.yzx;
    } else if (3.0 * p.z < m) {
        q = p.zxy;
    } else {
        return m * 0.57735026918962576;
    }
    float k = clamp(0.5 * (q.z - q.y + size), 0.0, size);
    return length(vec3(q.x, q.y - size + k, q.z - k));
}

float sd_cone(vec3 p, float radius, float height) {  // exact; along y, base at y = -height/2, apex at +height/2
    vec2 q = vec2(radius, -height);
    vec2 w = vec2(length(p.xz), p.y - 0.5 * height);
    vec2 a = w - q * clamp(dot(w, q) / dot(q, q), 0.0, 1.0);
    vec2 b = w - q * vec2(clamp(w.x / q.x, 0.0, 1.0), 1.0);
    float d = min(dot(a, a), dot(b, b));
    float s = max(-(w.x * q.y - w.y * q.x), -(w.y - q.y));
    return sqrt(d) * sign(s);
}

float sd_hex_prism(vec3 p, float apothem, float half_height) {  // exact; along z
    const vec3 k = vec3(-0.86602540378443865, 0.5, 0.57735026918962576);
    p = abs(p);
    p.xy -= 2.0 * min(dot(k.xy, p.xy), 0.0) * k.xy;
    vec2 d = vec2(length(p.xy - vec2(clamp(p.x, -k.z * apothem, k.z * apothem), apothem)) * sign(p.y - apothem),
                  p.z - half_height);
    return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}

float sd_ellipsoid(vec3 p, vec3 radii) {  // a bound, not exact; -min(radii) at the centre
    float k0 = length(p / radii);
    float k1 = length(p / (radii * radii));
    return k1 > 0.0 ? k0 * (k0 - 1.0) / k1 : -min(radii.x, min(radii.y, radii.z));
}

float sd_ellipsoid_lipschitz(vec3 p, vec3 radii) {  // a 1-Lipschitz bound: max((|p/r| - 1)·min(r), |p| - max(r))
    return max((length(p / radii) - 1.0) * min(radii.x, min(radii.y, radii.z)),
               length(p) - max(radii.x, max(radii.y, radii.z)));
}

float sd_plane(vec3 p, vec3 normal, float offset) {  // exact; n·p + offset, n normalised here
    return dot(p, normalize(normal)) + offset;
}

// ------------------------------------------------------------------------------ operators
// Rounding and onion act on a distance; the rest map the query point (GLSL has no function arguments), as in
// kernels/sdf.
float op_round(float d, float radius) {
    return d - radius;
}

float op_onion(float d, float thickness) {
    return abs(d) - thickness;
}

// xyz: the point to evaluate the shape at; w: the term to add to its distance.
vec4 op_elongate(vec3 p, vec3 half_length) {
    vec3 q = abs(p) - half_length;
    return vec4(p - clamp(p, -half_length, half_length), min(max(q.x, max(q.y, q.z)), 0.0));
}

vec3 op_twist(vec3 p, float rate) {  // rotate (x, z) by rate·y
    float c = cos(rate * p.y);
    float s = sin(rate * p.y);
    return vec3(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
}

vec3 op_bend(vec3 p, float rate) {  // rotate (x, y) by rate·x
    float c = cos(rate * p.x);
    float s = sin(rate * p.x);
    return vec3(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
}

vec3 op_repeat_finite(vec3 p, vec3 spacing, vec3 limit) {  // floor(x + 0.5): round() leaves halves to the driver
    return p - spacing * clamp(floor(p / spacing + 0.5), -limit, limit);
}

vec3 op_symmetry(vec3 p, vec3 axes) {  // axes: 1 mirrors that coordinate, 0 leaves it
    return mix(p, abs(p), axes);
}

// ------------------------------------------------------------------------------ scene
// Every kind is one rounded box |max(q, 0)| + min(max(q.x, q.y, q.z), 0) - r, q = |p'| - e (sphere: p' = p, e = 0;
// box: p' = p, e = half sizes, r = 0; capsule: p' = p, e = (0, half length, 0)). The torus is the same formula with
// p' = (|p.xz| - major radius, p.y, 0) and e = 0: then q = |p'| has no negative part and the formula is
// |p'| - minor radius, sd_torus. One formula with selected inputs, not two formulas and a select (see smin_blend on
// why); the values equal sd_sphere, sd_box, sd_capsule and sd_torus.
// The catalogue's kinds cost every one of their formulas under llvmpipe's masking, so only programs that define
// EXTRA_KINDS 1 (the renderer compiles those for scenes that use them) include them.
#ifndef EXTRA_KINDS
#define EXTRA_KINDS 0
#endif
#if EXTRA_KINDS
// catalogue_distance(kind, p, s): written from the registry in place of the next line, calling each kind's
// sd_* function with its arguments (and preceded by the formulas of kinds registered with a .glsl file).
// @CATALOGUE_DISTANCE
#endif

float primitive_distance(int i, vec3 p_world) {
    vec3 p = u_world_to_local[i] * (p_world - u_center[i]);
    vec3 s = u_size[i];
    int kind = u_kind[i];
    bool torus = kind == KIND_TORUS;
    vec3 shape_point = torus ? vec3(length(p.xz) - s.x, p.y, 0.0) : p;
    vec3 e = kind == KIND_BOX ? s : (kind == KIND_CAPSULE ? vec3(0.0, s.x, 0.0) : vec3(0.0));
    float r = kind == KIND_BOX ? 0.0 : (kind == KIND_CAPSULE || torus ? s.y : s.x);
#if EXTRA_KINDS
    if (kind >= FIRST_CATALOGUE_KIND) {
        return catalogue_distance(kind, p, s);
    }
#endif
    return sd_box(shape_point, e) - r;
}

float scene_distance(vec3 p) {
    float d = primitive_distance(0, p);
    if (u_count > 1) d = combine(d, primitive_distance(1, p), u_op[1], u_k, u_blend).x;
    if (u_count > 2) d = combine(d, primitive_distance(2, p), u_op[2], u_k, u_blend).x;
    if (u_count > 3) d = combine(d, primitive_distance(3, p), u_op[3], u_k, u_blend).x;
    return d;
}

vec3 scene_color(vec3 p) {
    float d = primitive_distance(0, p);
    vec3 color = u_color[0];
    for (int i = 1; i < u_count; ++i) {
        vec2 r = combine(d, primitive_distance(i, p), u_op[i], u_k, u_blend);
        d = r.x;
        color = mix(color, u_color[i], r.y);
    }
    return color;
}
