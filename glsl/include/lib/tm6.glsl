// The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021), as the reference
// implementation defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary
// forward class, (5,6) secondary backward class; components alternate interface, medium, …,
// substrate. Mirrors src/model/tm6.rs.
//
// The stack is walked in one pass, component by component, and each lobe goes to the including
// shader's tm_emit_lobe as soon as it is known: no per-component or per-lobe array. Function-local
// arrays indexed by the loop counter are what made this shader slow to compile on llvmpipe (its
// indirect accesses become branch ladders as long as the array, about 5 s of LLVM per layer of
// `max_layers`) — profiling/README.md. The energy and asymmetry matrices are dense 6×6 per RGB
// channel; the right-hand factors are multiplied in their sparse forms (an interface is
// block-diagonal, a medium has 14 non-zero entries), the terms of the dense product that are not
// products by zero, in the same order. The reflectances come from solving the three downward
// boundary conditions instead of the reference's 20-entry sparse products: the same algebra.
#ifndef LAMINA_LIB_TM6
#define LAMINA_LIB_TM6

#include "tm_common.glsl"

struct Tm6Matrix {
    real3 m[6][6];
};

Tm6Matrix tm6_identity() {
    Tm6Matrix a;
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            a.m[i][j] = real3(i == j ? 1.0 : 0.0);
        }
    }
    return a;
}

// a ← a · I for the interface matrix I: block-diagonal, primary block p, both secondary blocks
// s (§5.2).
void tm6_mul_interface(inout Tm6Matrix a, TmMatrix p, TmMatrix s) {
    for (int i = 0; i < 6; ++i) {
        real3 a0 = a.m[i][0];
        real3 a1 = a.m[i][1];
        a.m[i][0] = a0 * p.m11 + a1 * p.m21;
        a.m[i][1] = a0 * p.m12 + a1 * p.m22;
        for (int o = 2; o <= 4; o += 2) {
            real3 b0 = a.m[i][o];
            real3 b1 = a.m[i][o + 1];
            a.m[i][o] = b0 * s.m11 + b1 * s.m21;
            a.m[i][o + 1] = b0 * s.m12 + b1 * s.m22;
        }
    }
}

// a ← a · M for the homogeneous medium M of T, r_fb, t_ff (§5.4), scaled by the power of two
// `k` ≤ 1 that brings its largest entries (1/T, 1/t_ff) to at most 1: a thick medium makes them
// overflow half floats. Entries are formed in float and narrowed after scaling. M's non-zero
// entries: the diagonal (1/T, T, 1/t_ff, q, 1/t_ff, q with q = t_ff − r_fb²/t_ff),
// M₃₁ = 1/t_ff − 1/T, M₄₂ = q − T, M₃₆ = M₅₂ = M₅₄ = −r_fb/t_ff, M₄₅ = M₆₁ = M₆₃ = r_fb/t_ff
// (1-based; fluxes 5, 6 mirror 3, 4).
void tm6_mul_medium(inout Tm6Matrix a, vec3 transmission, vec3 r_fb, vec3 t_ff, out float k) {
    float smallest = min(min(min(transmission.r, transmission.g), transmission.b),
                         min(min(t_ff.r, t_ff.g), t_ff.b));
    k = exp2(min(floor(log2(max(smallest, 1e-30))), 0.0));
    vec3 inv = 1.0 / t_ff;
    vec3 m00 = 1.0 / transmission;
    vec3 q = t_ff - r_fb * r_fb * inv;
    real3 d0 = real3(m00 * k);
    real3 d1 = real3(transmission * k);
    real3 d2 = real3(inv * k);
    real3 d3 = real3(q * k);
    real3 minus = real3(-r_fb * inv * k);
    real3 plus = real3(r_fb * inv * k);
    real3 c20 = real3((inv - m00) * k);
    real3 c31 = real3((q - transmission) * k);
    for (int i = 0; i < 6; ++i) {
        real3 e0 = a.m[i][0];
        real3 e1 = a.m[i][1];
        real3 e2 = a.m[i][2];
        real3 e3 = a.m[i][3];
        real3 e4 = a.m[i][4];
        real3 e5 = a.m[i][5];
        a.m[i][0] = e0 * d0 + e2 * c20 + e5 * plus;
        a.m[i][1] = e1 * d1 + e3 * c31 + e4 * minus;
        a.m[i][2] = e2 * d2 + e5 * plus;
        a.m[i][3] = e3 * d3 + e4 * minus;
        a.m[i][4] = e3 * plus + e4 * d2;
        a.m[i][5] = e2 * minus + e5 * d3;
    }
}

// Scales `a` by the power of two that brings its largest entry near 1 and returns that factor.
// Exact in binary floating point, so it changes nothing but the range: the reflectances are
// ratios, and callers divide transmitted fluxes by the accumulated factor.
float tm6_normalize(inout Tm6Matrix a) {
    float largest = 0.0;
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            vec3 v = abs(vec3(a.m[i][j]));
            largest = max(largest, max(max(v.r, v.g), v.b));
        }
    }
    float p = exp2(-floor(log2(max(largest, 1e-30))));
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            a.m[i][j] *= real(p);
        }
    }
    return p;
}

// The three upward fluxes (r, r_f, r_b) above a composed stack whose bottom reflects every
// class with r_c (0: nothing below), and the three downward fluxes at its bottom, from the
// top conditions a1 = 1, a3 = a5 = 0 (§5.1, §5.6). Solved in float whatever `real` is: the
// determinant of normalized entries can fall below the half-float range.
void tm6_extract(Tm6Matrix a, vec3 r_c, out vec3 up[3], out vec3 down[3]) {
    vec3 c[3][3];
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) {
            c[row][col] = vec3(a.m[2 * row][2 * col]) + vec3(a.m[2 * row][2 * col + 1]) * r_c;
        }
    }
    // Cramer's rule for c · (b1, b3, b5) = (1, 0, 0).
    vec3 det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
             - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
             + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
    vec3 inv_det = 1.0 / det;
    down[0] = (c[1][1] * c[2][2] - c[1][2] * c[2][1]) * inv_det;
    down[1] = -(c[1][0] * c[2][2] - c[1][2] * c[2][0]) * inv_det;
    down[2] = (c[1][0] * c[2][1] - c[1][1] * c[2][0]) * inv_det;
    for (int row = 0; row < 3; ++row) {
        vec3 s = vec3(0.0);
        for (int col = 0; col < 3; ++col) {
            s += (vec3(a.m[2 * row + 1][2 * col]) + vec3(a.m[2 * row + 1][2 * col + 1]) * r_c) * down[col];
        }
        up[row] = s;
    }
}

float tm6_safe_ratio(float num, float den) {
    return abs(den) > 1e-7 ? num / den : 0.0;
}

// Kubelka–Munk-type two-stream factors of a medium of thickness `depth` crossed at cosine
// `mu` (§5.3, numerics §5.8): T, r_fb, t_ff and the g's of r_fb and t_ff.
void tm6_medium_factors(LayerGpu layer, float mu, out vec3 transmission, out vec3 r_fb,
                        out vec3 t_ff, out float g_rfb, out float g_tff) {
    vec3 sigma_s = layer.sigma_s.rgb;
    vec3 sigma_k = max(layer.sigma_a.rgb, vec3(1e-7));
    float g = layer.params.z;
    vec3 sigma_sb = sigma_s * hg_lh_norm(g);
    vec3 sigma_sf = sigma_s - sigma_sb;
    vec3 sigma_ext = sigma_s + sigma_k;
    vec3 a = sigma_ext - sigma_sf;
    vec3 b = sigma_sb;
    vec3 gamma = sqrt(max(a * a - b * b, vec3(0.0)));
    vec3 a_g = sigma_ext - sigma_sf * g;
    vec3 b_g = -sigma_sb * g;
    vec3 gamma_g = sqrt(max(a_g * a_g - b_g * b_g, vec3(0.0)));
    float tau = layer.params.y / max(mu, 1e-7);
    float fastest = max(max(max(gamma.r, gamma.g), gamma.b), max(max(gamma_g.r, gamma_g.g), gamma_g.b));
    tau = min(tau, 45.0 / max(fastest, 1e-7));
    tau = min(tau, 45.0 / max(max(sigma_ext.r, sigma_ext.g), sigma_ext.b));
    vec3 s = sinh(gamma * tau);
    vec3 x = 1.0 / (sqrt(1.0 + s * s) * gamma + s * a);
    transmission = exp(-sigma_ext * tau);
    r_fb = s * b * x;
    t_ff = gamma * x;
    vec3 s_g = sinh(gamma_g * tau);
    vec3 x_g = 1.0 / (sqrt(1.0 + s_g * s_g) * gamma_g + s_g * a_g);
    vec3 rg = s_g * b_g * x_g;
    vec3 tg = gamma_g * x_g;
    g_rfb = (tm6_safe_ratio(rg.r, r_fb.r) + tm6_safe_ratio(rg.g, r_fb.g) + tm6_safe_ratio(rg.b, r_fb.b)) / 3.0;
    g_tff = (tm6_safe_ratio(tg.r, t_ff.r) + tm6_safe_ratio(tg.g, t_ff.g) + tm6_safe_ratio(tg.b, t_ff.b)) / 3.0;
}

// Walks the stack top to bottom for view cosine `mu`: step 2i is layer i's interface (nothing
// when index-matched, or the substrate, which ends the walk), step 2i + 1 its medium (nothing
// when its depth is 0). Each step composes its factors into the energy matrix `e` and the
// asymmetry matrix `g`, extracts the three reflectances and emits the lobes the request flags
// allow (§5.5–5.7) through tm_emit_lobe. Returns the lobe count.
uint tm6_evaluate(MaterialGpu material, float mu, out vec3 reflectance, out vec3 transmittance) {
    uint layers = min(material.info.x, MAX_LAYERS);
    Tm6Matrix e = tm6_identity();
    Tm6Matrix g = tm6_identity();
    // e holds the energy matrix times `scale` (see tm6_normalize).
    float scale = 1.0;
    vec3 prev[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 prev_g[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    // g of the primary and secondary paths transmitted down to the current component.
    float g_t0i = 1.0;
    float g_st0i = 1.0;
    bool primary = false;
    bool backward = false;
    uint lobe_count = 0u;
    float eta_above = IOR_AIR;
    float cos_i = mu;
    // The current layer's medium, found at its interface (whose secondary path needs its g).
    bool medium = false;
    vec3 m_transmission = vec3(1.0);
    vec3 m_r_fb = vec3(0.0);
    vec3 m_t_ff = vec3(1.0);
    float m_g_rfb = 0.0;
    float m_g_tff = 1.0;
    transmittance = vec3(0.0);
    for (uint step = 0u; step < 2u * layers; ++step) {
        uint i = step >> 1u;
        LayerGpu layer = material.layers[i];
        bool substrate = false;
        vec3 r_c = vec3(0.0);
        float g_r_c = 0.0;
        if ((step & 1u) == 0u && tm_is_conductor(layer)) {
            substrate = true;
            r_c = fgd_rgb(cos_i, layer.params.x, layer.ior.rgb / eta_above,
                          layer.kappa.rgb / eta_above);
            g_r_c = hg_g_of_alpha(layer.params.x);
            // A bare substrate emits its primary lobe too (the reference sets the flag only
            // after a dielectric, which would leave a single conductor without any lobe).
            primary = true;
        } else if ((step & 1u) == 0u) {
            float alpha = layer.params.x;
            float eta_layer = tm_mean(layer.ior.rgb);
            float eta = eta_layer / eta_above;
            float cos_below = cos_i;
            bool refracts = abs(eta - 1.0) >= 1e-5;
            if (refracts) {
                cos_below = tm_refracted_cos(cos_i, eta);
            }
            medium = layer.params.y > 0.0;
            if (medium) {
                tm6_medium_factors(layer, cos_below, m_transmission, m_r_fb, m_t_ff, m_g_rfb,
                                   m_g_tff);
            }
            if (refracts) {
                float g_r = hg_g_of_alpha(alpha);
                // Rough transmission widens less than reflection (§3.4).
                float s_down = abs(1.0 - cos_i / (eta * max(cos_below, 1e-7)));
                float s_up = abs(1.0 - eta * cos_below / max(cos_i, 1e-7));
                float g_t = hg_g_of_alpha(0.5 * s_down * alpha);
                float g_tp = hg_g_of_alpha(0.5 * s_up * alpha);
                // g of the next layer's reflection, and of this layer's medium crossed forward.
                float g_next = i + 1u < layers ? hg_g_of_alpha(material.layers[i + 1u].params.x) : 0.0;
                float g_medium = medium ? m_g_tff : 1.0;
                // Primary path (§4.4).
                float g_t0j = hg_refract(g_t0i, 1.0 / eta) * g_t;
                float g_t0j_r = g_t0j * g_next;
                float g_t0j_rt = hg_refract(g_t0j_r, eta) * g_tp;
                float gt = g_t0i > 0.0 ? g_t0j / g_t0i : 0.0;
                float gtp = g_t0j_r > 0.0 ? g_t0j_rt / g_t0j_r : 0.0;
                // Secondary path: the medium's forward transmission down and up (§5.5).
                float g_st0j = hg_refract(g_st0i, 1.0 / eta) * g_t;
                float g_st0j_r = g_st0j * g_medium * g_next * g_medium;
                float g_st0j_rt = hg_refract(g_st0j_r, eta) * g_tp;
                float gst = g_st0i > 0.0 ? g_st0j / g_st0i : 0.0;
                float gstp = g_st0j_r > 0.0 ? g_st0j_rt / g_st0j_r : 0.0;
                float r0 = abs(eta - 1.0) < 1e-3 ? 0.0 : fgd_dielectric(cos_i, alpha, eta);
                vec3 r = vec3(r0), t = vec3(1.0 - r0), rp = vec3(r0), tp = vec3(1.0 - r0);
                vec3 rs = r, ts = t, rsp = rp, tsp = tp;
                // Total internal reflection moves energy from transmission to reflection (§4.5).
                if (eta < 1.0) {
                    vec3 tau = tir_fraction(cos_i, hg_alpha_of_g(g_t0i), eta) * t;
                    r += tau; t -= tau;
                    vec3 tau_s = tir_fraction(cos_i, hg_alpha_of_g(g_st0i), eta) * ts;
                    rs += tau_s; ts -= tau_s;
                } else {
                    vec3 tau = tir_fraction(cos_below, hg_alpha_of_g(g_t0j_r), 1.0 / eta) * tp;
                    rp += tau; tp -= tau;
                    vec3 tau_s = tir_fraction(cos_below, hg_alpha_of_g(g_st0j_r), 1.0 / eta) * tsp;
                    rsp += tau_s; tsp -= tau_s;
                }
                tm6_mul_interface(e, tm_interface(real3(r), real3(t), real3(rp), real3(tp)),
                                  tm_interface(real3(rs), real3(ts), real3(rsp), real3(tsp)));
                scale *= tm6_normalize(e);
                tm6_mul_interface(g, tm_interface(real3(r * g_r), real3(t * gt),
                                                  real3(rp * g_r), real3(tp * gtp)),
                                  tm_interface(real3(rs * g_r), real3(ts * gst),
                                               real3(rsp * g_r), real3(tsp * gstp)));
                tm6_normalize(g);
                primary = true;
                g_t0i = g_t0j;
                g_st0i = g_st0j;
                cos_i = cos_below;
                eta_above = eta_layer;
            }
        } else if (medium) {
            float k;
            tm6_mul_medium(e, m_transmission, m_r_fb, m_t_ff, k);
            scale *= k * tm6_normalize(e);
            tm6_mul_medium(g, m_transmission, m_r_fb * m_g_rfb, m_t_ff * m_g_tff, k);
            tm6_normalize(g);
            backward = true;
        }
        vec3 up[3];
        vec3 up_g[3];
        vec3 down[3];
        tm6_extract(e, r_c, up, down);
        transmittance = substrate ? vec3(0.0) : (down[0] + down[1] + down[2]) * scale;
        tm6_extract(g, r_c * g_r_c, up_g, down);
        // Emit primary, secondary-forward, secondary-backward lobes (§5.7).
        bool emit[3] = bool[3](primary, primary && backward, backward);
        for (int k = 0; k < 3; ++k) {
            if (emit[k]) {
                vec3 dg = up_g[k] - prev_g[k];
                vec3 dr = up[k] - prev[k];
                float lobe_g = min((tm6_safe_ratio(dg.r, dr.r) + tm6_safe_ratio(dg.g, dr.g)
                                    + tm6_safe_ratio(dg.b, dr.b)) / 3.0, 1.0);
                tm_emit_lobe(max(dr, vec3(0.0)), hg_alpha_of_g(lobe_g),
                             k == 2 ? LOBE_RETRO : LOBE_MIRROR);
                lobe_count++;
            }
            prev[k] = up[k];
            prev_g[k] = up_g[k];
        }
        if (substrate) {
            break;
        }
    }
    reflectance = prev[0] + prev[1] + prev[2];
    return lobe_count;
}

#endif
