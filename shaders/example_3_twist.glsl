// Twist: a hexagonal prism turning
// op_twist maps the point, which stretches distances: dividing by the map's Lipschitz factor keeps a safe bound.
float sdf(vec3 p) {
    float rate = 2.0;                     // rad/m
    vec3 q = op_twist(p.xzy, rate);       // twist about world z
    float stretch = sqrt(1.0 + rate * rate * 0.36);  // rate x the prism's reach (0.6 m)
    return sd_hex_prism(q.xzy, 0.45, 0.9) / stretch;
}

vec3 color(vec3 p) {
    return vec3(0.35, 0.7, 0.5) + 0.25 * vec3(sin(6.0 * p.z), 0.0, cos(6.0 * p.z));
}
