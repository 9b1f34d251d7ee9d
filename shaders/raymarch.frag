#version 330
// Sphere-traces the scene in sdf.glsl (Hart 1996) from a pinhole camera, one ray per pixel centre, the same loop
// as kernels/sdf sphere_trace. Normals by central differences; Phong shading; soft shadows with Quilez's improved
// technique (2018: track the previous step to find the closest approach between samples, no banding); ambient
// occlusion from five samples along the normal.

// SHADOWS and OCCLUSION (0 or 1) are defined by the renderer, which compiles the four variants once each: a
// switched-off term then costs nothing (a uniform flag would still be paid for under llvmpipe's masking).

// USER_FIELD 1 (the editor's programs): march a person's `float sdf(vec3 p)` and `vec3 color(vec3 p)`, which the
// renderer appends after this file, inside the box [u_field_lo, u_field_hi], instead of the uniforms' scene.

#include "sdf.glsl"
#include "shading.glsl"

#ifndef USER_FIELD
#define USER_FIELD 0
#endif
#if USER_FIELD
float sdf(vec3 p);
vec3 color(vec3 p);
uniform vec3 u_field_lo;  // the editor's bounds (m)
uniform vec3 u_field_hi;
uniform float u_field_root;  // √ of 1, or of the slope the mesher measured for a field far from a distance
// Divided twice by the root: a slope over float32's range (a ±3e38 step) fits as its root, and 1 / 1e38 would be
// below float32's normal range.
#define FIELD_DISTANCE(p) (sdf(p) / u_field_root / u_field_root)
#define FIELD_COLOR(p) color(p)
#else
#define FIELD_DISTANCE(p) scene_distance(p)
#define FIELD_COLOR(p) scene_color(p)
#endif

uniform vec2 u_resolution;       // pixels
uniform vec3 u_eye;              // camera position (m)
uniform vec3 u_forward;          // unit view axis
uniform vec3 u_right;            // unit, image x
uniform vec3 u_up;               // unit, image y
uniform float u_tan_half_fov;    // tan(vertical fov / 2)
uniform int u_max_steps;
uniform float u_hit_epsilon;     // m at t <= 1, relative beyond
uniform float u_max_distance;    // m
uniform float u_normal_epsilon;  // central-difference step (m)
uniform float u_shadow_sharpness;  // k of the soft shadow: larger is harder
uniform float u_occlusion_strength;
uniform float u_occlusion_step;  // m between AO samples
uniform vec4 u_bounds[MAX_PRIMITIVES];  // kernels/sdf scene_bounding_spheres: centre, radius; march inside
uniform vec3 u_box_half[MAX_PRIMITIVES];  // renderer.py _bounding_boxes: half extents in the primitive's frame (m)

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;  // along u_forward (m); -1 for a miss

vec3 scene_normal(vec3 p) {
    vec2 e = vec2(u_normal_epsilon, 0.0);
    return normalize(vec3(
        FIELD_DISTANCE(p + e.xyy) - FIELD_DISTANCE(p - e.xyy),
        FIELD_DISTANCE(p + e.yxy) - FIELD_DISTANCE(p - e.yxy),
        FIELD_DISTANCE(p + e.yyx) - FIELD_DISTANCE(p - e.yyx)));
}

// Where a unit ray first enters and last leaves the bounds: per primitive, its bounding sphere
// (kernels/sdf ray_spheres_interval) cut by its bounding box (renderer.py _bounding_boxes, a slab test in the
// primitive's frame); over the primitives, the union. (t_enter >= 0, t_exit), t_exit < t_enter where it meets none
// ahead. A sphere tracer started at any point before the first surface finds the same surface, so the image
// equals kernels/sdf sphere_trace's from the spheres alone, while fewer steps are spent beside the shape.
#if USER_FIELD
// The editor's field: the slab test against its bounds box.
vec2 bound_interval(vec3 origin, vec3 dir) {
    vec3 inverse = 1.0 / mix(dir, vec3(1e-20), lessThan(abs(dir), vec3(1e-20)));
    vec3 t_low = (u_field_lo - origin) * inverse;
    vec3 t_high = (u_field_hi - origin) * inverse;
    vec3 t_near = min(t_low, t_high);
    vec3 t_far = max(t_low, t_high);
    float enter = max(max(t_near.x, max(t_near.y, t_near.z)), 0.0);
    float exit = min(t_far.x, min(t_far.y, t_far.z));
    return exit >= enter ? vec2(enter, exit) : vec2(1e30, -1.0);
}
#else
vec2 bound_interval(vec3 origin, vec3 dir) {
    float t_enter = 1e30;
    float t_exit = -1.0;
    for (int i = 0; i < MAX_PRIMITIVES; ++i) {
        vec3 oc = origin - u_bounds[i].xyz;
        float b = dot(oc, dir);
        float disc = b * b - (dot(oc, oc) - u_bounds[i].w * u_bounds[i].w);
        float root = sqrt(max(disc, 0.0));
        vec3 o_local = u_world_to_local[i] * (origin - u_center[i]);
        vec3 d_local = u_world_to_local[i] * dir;
        // 1/d with the sign kept and no infinities (a zero component gives a huge, finite slab parameter).
        vec3 inverse = 1.0 / mix(d_local, vec3(1e-20), lessThan(abs(d_local), vec3(1e-20)));
        vec3 t_low = (-u_box_half[i] - o_local) * inverse;
        vec3 t_high = (u_box_half[i] - o_local) * inverse;
        vec3 t_near = min(t_low, t_high);
        vec3 t_far = max(t_low, t_high);
        float enter = max(-b - root, max(t_near.x, max(t_near.y, t_near.z)));
        float exit = min(-b + root, min(t_far.x, min(t_far.y, t_far.z)));
        bool ahead = i < u_count && disc >= 0.0 && exit >= max(enter, 0.0);
        t_enter = ahead ? min(t_enter, max(enter, 0.0)) : t_enter;
        t_exit = ahead ? max(t_exit, exit) : t_exit;
    }
    return vec2(t_enter, t_exit);
}
#endif

// A shadow factor this small is black to 8 bits (under half a level at the default k_d + k_s): stop marching there.
#define SHADOW_BLACK 0.002

float soft_shadow(vec3 origin, vec3 dir, float t_min, float t_max, float k) {
    float result = 1.0;
    float t = t_min;
    float previous = 1e20;
    for (int i = 0; i < 32 && t < t_max && result > SHADOW_BLACK; ++i) {
        float h = FIELD_DISTANCE(origin + dir * t);
        if (h < 1e-4) {
            return 0.0;
        }
        // The two distance spheres' overlap locates the closest approach between samples; only while the ray
        // closes in (h < previous): moving away (h = 2·previous straight off a plane) would give d = 0, a false
        // shadow, and the previous sample already holds the closest approach.
        float y = h < previous ? h * h / (2.0 * previous) : 0.0;
        float d = sqrt(max(h * h - y * y, 0.0));
        result = min(result, k * d / max(1e-6, t - y));
        previous = h;
        // Bounded steps, as Quilez does: no tiny crawls, no skipped thin parts. At least 2 cm: with 1 cm, rays in
        // creases crawled to the 32-step cap; 2 cm takes an eighth fewer steps, the image the same to a few levels.
        t += clamp(h, 0.02, 0.3);
    }
    return clamp(result, 0.0, 1.0);
}

float ambient_occlusion(vec3 p, vec3 n) {
    float occlusion = 0.0;
    float weight = 1.0;
    for (int i = 1; i <= 5; ++i) {
        float h = u_occlusion_step * float(i);
        occlusion += (h - FIELD_DISTANCE(p + n * h)) * weight;
        weight *= 0.75;
    }
    return clamp(1.0 - u_occlusion_strength * occlusion, 0.0, 1.0);
}

void main() {
    vec2 ndc = gl_FragCoord.xy / u_resolution * 2.0 - 1.0;
    float aspect = u_resolution.x / u_resolution.y;
    vec3 dir = normalize(u_forward + ndc.x * u_tan_half_fov * aspect * u_right + ndc.y * u_tan_half_fov * u_up);

    vec2 span = bound_interval(u_eye, dir);
    if (span.y < span.x) {
        discard;  // meets no bounding sphere: a block of such pixels exits here (see the discard below)
    }
    float t = span.x;
    float t_exit = min(span.y, u_max_distance);
    bool hit = false;
    for (int i = 0; i < u_max_steps && t_exit >= t; ++i) {
        float d = FIELD_DISTANCE(u_eye + dir * t);
        if (d < u_hit_epsilon * max(1.0, t)) {
            hit = true;
            break;
        }
        t += d;
        if (t > t_exit) {
            break;
        }
    }
    if (!hit) {
        // Misses keep the cleared target (depth -1). On llvmpipe a discard is also what lets a block of pixels
        // that all missed skip the shading below: it runs both sides of an if, masked, but exits dead blocks.
        discard;
    }
    vec3 p = u_eye + dir * t;
    vec3 n = scene_normal(p);
    float shadow = 1.0;
#if SHADOWS
    vec3 start = p + n * (4.0 * u_hit_epsilon * max(1.0, t));
    // A surface facing away from the light gets no direct light, which is all the shadow scales: march nothing
    // there (t_max = 0), so blocks of such pixels skip the loop.
    float t_max = dot(n, u_light_direction) > 0.0 ? bound_interval(start, u_light_direction).y : 0.0;
    shadow = soft_shadow(start, u_light_direction, 0.01, t_max, u_shadow_sharpness);
#endif
    float occlusion = 1.0;
#if OCCLUSION
    occlusion = ambient_occlusion(p, n);
#endif
    vec3 shaded = phong(FIELD_COLOR(p), n, -dir, shadow, occlusion);
    out_color = vec4(clamp(shaded, 0.0, 1.0), 1.0);
    out_depth = t * dot(dir, u_forward);
}
