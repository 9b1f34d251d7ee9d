// Repetition: a 5 x 3 grid of octahedra
// op_repeat_finite folds space into cells; limit says how many copies on each side of the middle one.
float sdf(vec3 p) {
    vec3 q = op_repeat_finite(p - vec3(0.0, 0.0, 0.2), vec3(0.45, 0.5, 1.0), vec3(2.0, 1.0, 0.0));
    float gems = op_round(sd_octahedron(q, 0.16), 0.03);
    float slab = sd_round_box(p - vec3(0.0, 0.0, -0.1), vec3(1.2, 0.8, 0.08), 0.04);
    return smooth_union(gems, slab, 0.1, BLEND_POLY);
}

vec3 color(vec3 p) {
    return p.z > 0.02 ? vec3(0.95, 0.8, 0.3) : vec3(0.3, 0.3, 0.35);
}
