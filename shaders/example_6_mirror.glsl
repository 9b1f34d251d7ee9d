// Mirror symmetry: one cone, four copies
// op_symmetry mirrors the point across the chosen planes: one shape at (+x, +y) appears in all four quadrants.
float sdf(vec3 p) {
    vec3 q = op_symmetry(p, vec3(1.0, 1.0, 0.0)) - vec3(0.5, 0.5, 0.0);
    float cones = sd_cone(q.xzy, 0.3, 0.9);
    float base = sd_cylinder(p.xzy + vec3(0.0, 0.5, 0.0), 0.06, 1.0);
    return smooth_union(cones, base, 0.1, BLEND_POLY);
}

vec3 color(vec3 p) {
    return vec3(0.5 + 0.4 * sign(p.x), 0.55, 0.5 + 0.4 * sign(p.y));
}
