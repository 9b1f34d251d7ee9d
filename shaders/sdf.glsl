// Signed distance functions: mirrors kernels/sdf.py name for name (float32 here, float64 there).
// Included with moderngl's ctx.includes by raymarch.frag, probe.frag and mesh.frag; it has no #version of its own.
// The scene arrives as uniforms, so changing it never recompiles a program.

#define MAX_PRIMITIVES 4
#define KIND_SPHERE 0
#define KIND_BOX 1
#define KIND_TORUS 2
#define KIND_CAPSULE 3
#define OP_UNION 0
#define OP_SUBTRACT 1
#define OP_INTERSECT 2
#define BLEND_POLY 0
#define BLEND_EXP 1
// kernels/sdf.py EXP_SHARPNESS_PER_WIDTH = 4 ln 2: both blends dip by k/4 where two surfaces meet.
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
// finite width k >= 0 and tend to the hard minimum as k -> 0 (kernels/sdf.py holds the same property).
// kernels/sdf.py MIN_BLEND_WIDTH, float32's smallest normal: a width below it (0, or a subnormal that a GPU may flush
// to 0) is the hard minimum, its dip k/4 being below any distance's rounding; above it 0.5 / k stays finite.
#define MIN_BLEND_WIDTH 1.17549435e-38

// Distances may be infinite (a float32 length overflows past ~1.8e19 m): the gap is 0 where a = b, the same infinity
// included (not inf - inf), and where h is 0 or 1 the result is b or a outright (not 0 * inf), as in kernels/sdf.py.
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

// ------------------------------------------------------------------------------ scene
// Every kind is one rounded box |max(q, 0)| + min(max(q.x, q.y, q.z), 0) - r, q = |p'| - e (sphere: p' = p, e = 0;
// box: p' = p, e = half sizes, r = 0; capsule: p' = p, e = (0, half length, 0)). The torus is the same formula with
// p' = (|p.xz| - major radius, p.y, 0) and e = 0: then q = |p'| has no negative part and the formula is
// |p'| - minor radius, sd_torus. One formula with selected inputs, not two formulas and a select (see smin_blend on
// why); the values equal sd_sphere, sd_box, sd_capsule and sd_torus.
float primitive_distance(int i, vec3 p_world) {
    vec3 p = u_world_to_local[i] * (p_world - u_center[i]);
    vec3 s = u_size[i];
    int kind = u_kind[i];
    bool torus = kind == KIND_TORUS;
    vec3 shape_point = torus ? vec3(length(p.xz) - s.x, p.y, 0.0) : p;
    vec3 e = kind == KIND_BOX ? s : (kind == KIND_CAPSULE ? vec3(0.0, s.x, 0.0) : vec3(0.0));
    float r = kind == KIND_BOX ? 0.0 : (kind == KIND_CAPSULE || torus ? s.y : s.x);
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
