#version 460
// The TIR table (ALGORITHMS.md §6.3): the fraction of a single-scattering GGX reflection lobe
// (incidence cosine μ, roughness α, separable Smith G2) whose directions leave the escape cone
// of relative IOR η < 1, i.e. sin θ_o > η:
//   TIR(μ, α, η) = ∫_{sin θ_o > η} D G2 / (4μ) dω_o  /  ∫_{H²} D G2 / (4μ) dω_o.
// Visible-normal sampling of h, ω_o = reflect(ω_i, h), weight G1(ω_o) (the separable G2 over the
// VNDF pdf). Vertex-centred grid: texel (i, j, k) holds μ = i/(n−1), α = j/(n−1), η = k/(n−1);
// μ = 0 is evaluated at the smallest cosine the sampler resolves (1e-3).
#include "shared/kernel.glsl"
#include "lib/sampling.glsl"

layout(set = 0, binding = 0, std430) writeonly buffer Table {
    float texels[];
} table;

// One dispatch fills the η slices z0 .. z0 + depth (the host splits the table to report progress).
layout(push_constant) uniform Push {
    uint size;
    uint sample_count;
    uint z0;
} push;

float smith_g1_separable(float cos_t, float alpha) {
    float c2 = cos_t * cos_t;
    float tan2 = (1.0 - c2) / c2;
    float lambda = 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
    return 1.0 / (1.0 + lambda);
}

void main() {
    uvec3 id = gl_GlobalInvocationID + uvec3(0u, 0u, push.z0);
    uint n = push.size;
    if (id.x >= n || id.y >= n || id.z >= n) {
        return;
    }
    float step = 1.0 / float(n - 1u);
    float mu = max(float(id.x) * step, 1e-3);
    float alpha = float(id.y) * step;
    float eta = float(id.z) * step;
    vec3 v = vec3(sqrt(1.0 - mu * mu), 0.0, mu);

    float trapped = 0.0;
    float total = 0.0;
    for (uint i = 0u; i < push.sample_count; ++i) {
        vec3 h = sample_ggx_vndf(v, hammersley(i, push.sample_count), alpha);
        vec3 o = reflect(-v, h);
        if (o.z <= 0.0) {
            continue;
        }
        float w = alpha > 0.0 ? smith_g1_separable(o.z, alpha) : 1.0;
        total += w;
        // sin θ_o > η  ⟺  cos² θ_o < 1 − η²
        if (o.z * o.z < 1.0 - eta * eta) {
            trapped += w;
        }
    }
    table.texels[(id.z * n + id.y) * n + id.x] = total > 0.0 ? trapped / total : 0.0;
}
