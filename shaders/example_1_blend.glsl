// Smooth blend: cylinder, octahedron, cone
// smooth_union blends two distances over a width k (m); Z is up, the catalogue's shapes stand along their local y.
float sdf(vec3 p) {
    vec3 q = p.xzy;  // local y = world z
    float column = sd_cylinder(q - vec3(0.0, 0.0, 0.0), 0.5, 0.25);
    float gem = sd_octahedron(q - vec3(0.0, 0.7, 0.0), 0.45);
    float hat = sd_cone(q - vec3(0.6, 0.1, 0.0), 0.3, 0.6);
    return smooth_union(smooth_union(column, gem, 0.2, BLEND_POLY), hat, 0.15, BLEND_POLY);
}

vec3 color(vec3 p) {
    return mix(vec3(0.25, 0.55, 0.9), vec3(0.95, 0.45, 0.3), clamp(p.z + 0.3, 0.0, 1.0));
}
