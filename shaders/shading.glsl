// Phong shading, shared by raymarch.frag and mesh.frag so the two images light the same way.
// I = k_a·I_a·albedo·AO + (k_d·I_d·albedo·max(n·L, 0) + k_s·I_s·max(r·v, 0)^α)·shadow, with white lights.

uniform float u_ambient;        // k_a
uniform float u_diffuse;        // k_d
uniform float u_specular;       // k_s
uniform float u_shininess;      // α
uniform vec3 u_light_direction; // unit vector toward the light (world)

vec3 phong(vec3 albedo, vec3 n, vec3 view_dir, float shadow, float occlusion) {
    vec3 l = u_light_direction;
    vec3 r = reflect(-l, n);
    float diffuse = max(dot(n, l), 0.0);
    float specular = diffuse > 0.0 ? pow(max(dot(r, view_dir), 0.0), u_shininess) : 0.0;
    return u_ambient * albedo * occlusion + (u_diffuse * albedo * diffuse + vec3(u_specular * specular)) * shadow;
}
