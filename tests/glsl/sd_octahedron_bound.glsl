// Test formula for tests/kernels/test_sdf_registry.py: Quilez's "Octahedron - bound (not exact)", registered as an extra
// kind to show that a new primitive is one registry entry plus its numpy and GLSL formulas.
float sd_octahedron_bound(vec3 p, float size) {
    p = abs(p);
    return (p.x + p.y + p.z - size) * 0.57735027;
}
