// Elongation: a torus stretched into a track
// op_elongate splits a shape at its centre planes and moves the halves apart (exact for an exact shape); an
// ellipsoid sits inside the running track.
float sdf(vec3 p) {
    vec4 e = op_elongate(p.xzy, vec3(0.5, 0.0, 0.2));
    float track = sd_torus(e.xyz, 0.45, 0.1) + e.w;
    float egg = sd_ellipsoid(p - vec3(0.0, 0.0, 0.1), vec3(0.6, 0.35, 0.25));
    return op_union(track, egg);
}

vec3 color(vec3 p) {
    return length(p.xy) < 0.65 ? vec3(0.95, 0.6, 0.25) : vec3(0.3, 0.6, 0.9);
}
