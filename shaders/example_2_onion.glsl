// Onion: a hollow shell, cut open
// op_onion(d, t) = |d| - t turns any shape into a shell of wall 2t; a plane cuts the top off.
float sdf(vec3 p) {
    float shell = op_onion(sd_sphere(p, 0.8), 0.04);
    float inner = op_onion(sd_sphere(p, 0.55), 0.04);
    float cut = sd_plane(p, vec3(0.3, -0.4, 1.0), -0.2);
    return op_intersect(op_union(shell, inner), cut);
}

vec3 color(vec3 p) {
    return length(p) > 0.7 ? vec3(0.9, 0.75, 0.35) : vec3(0.85, 0.3, 0.3);
}
