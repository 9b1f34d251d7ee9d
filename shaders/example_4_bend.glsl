// Bend: a rounded bar curled upwards
// op_bend rotates (x, y) by rate*x; here the bar lies along x and bends in the xz plane.
float sdf(vec3 p) {
    float rate = 0.9;  // rad/m
    vec3 q = op_bend(p.xzy, rate).xzy;
    return sd_round_box(q, vec3(1.0, 0.2, 0.12), 0.06) / (1.0 + rate);
}

vec3 color(vec3 p) {
    return mix(vec3(0.9, 0.3, 0.5), vec3(0.3, 0.4, 0.95), clamp(0.5 + 0.5 * p.x, 0.0, 1.0));
}
