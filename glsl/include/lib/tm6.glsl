// The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021), as the reference
// implementation defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary
// forward class, (5,6) secondary backward class; components alternate interface, medium, …,
// substrate. Mirrors src/model/tm6.rs.
//
// lamina composes dense 6×6 matrices per RGB channel and extracts the reflectances by solving
// the three downward boundary conditions, instead of the reference's 20-entry sparse products:
// the same algebra, easier to check, and the baseline the sparse form will be measured against.
#ifndef LAMINA_LIB_TM6
#define LAMINA_LIB_TM6

#include "tm_common.glsl"

// Components of a stack of n layers: an interface and a medium per dielectric layer, then the
// substrate.
const uint TM6_MAX_COMPONENTS = 2u * MAX_LAYERS;

#define TM6_INTERFACE 0u
#define TM6_MEDIUM 1u
#define TM6_CONDUCTOR 2u
#define TM6_NONE 3u

// One component's factors. Interfaces: primary (r, t, r', t') and secondary (r_ff, …) energies
// with their HG g's. Media: T (primary transmission), r_fb, t_ff with g's (in r, t, r_ff, t_ff).
struct Tm6Component {
    uint kind;
    vec3 r, t, rp, tp;            // primary
    vec3 rs, ts, rsp, tsp;        // secondary (media: T in t, r_fb in rs, t_ff in ts)
    vec4 g_primary;               // g of r, t, r', t'
    vec4 g_secondary;             // g of r_ff, t_ff, r'_ff, t'_ff
    float mu;                     // |cos| of the mean direction arriving from above
    float mu_t;                   // |cos| of the mean direction below
    float eta;
    float alpha;
};

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

Tm6Matrix tm6_mul(Tm6Matrix a, Tm6Matrix b) {
    Tm6Matrix c;
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            real3 s = real3(0.0);
            for (int k = 0; k < 6; ++k) {
                s += a.m[i][k] * b.m[k][j];
            }
            c.m[i][j] = s;
        }
    }
    return c;
}

// Interface: block-diagonal, primary block from (r, t, r', t'), both secondary blocks from the
// secondary factors (§5.2).
Tm6Matrix tm6_interface(real3 r, real3 t, real3 rp, real3 tp,
                        real3 rs, real3 ts, real3 rsp, real3 tsp) {
    Tm6Matrix a = tm6_identity();
    TmMatrix p = tm_interface(r, t, rp, tp);
    TmMatrix s = tm_interface(rs, ts, rsp, tsp);
    a.m[0][0] = p.m11; a.m[0][1] = p.m12; a.m[1][0] = p.m21; a.m[1][1] = p.m22;
    for (int o = 2; o <= 4; o += 2) {
        a.m[o][o] = s.m11; a.m[o][o + 1] = s.m12; a.m[o + 1][o] = s.m21; a.m[o + 1][o + 1] = s.m22;
    }
    return a;
}

// Homogeneous medium from T, r_fb, t_ff (§5.4), scaled by the power of two `k` ≤ 1 that
// brings its largest entries (1/T, 1/t_ff) to at most 1: a thick medium makes them overflow
// half floats. Entries are formed in float and narrowed after scaling.
Tm6Matrix tm6_medium(vec3 transmission, vec3 r_fb, vec3 t_ff, out float k) {
    float smallest = min(min(min(transmission.r, transmission.g), transmission.b),
                         min(min(t_ff.r, t_ff.g), t_ff.b));
    k = exp2(min(floor(log2(max(smallest, 1e-30))), 0.0));
    Tm6Matrix a = tm6_identity();
    vec3 inv = 1.0 / t_ff;
    vec3 m00 = 1.0 / transmission;
    vec3 m22 = inv;
    vec3 m33 = t_ff - r_fb * r_fb * inv;
    a.m[0][0] = real3(m00 * k);
    a.m[1][1] = real3(transmission * k);
    a.m[2][2] = real3(m22 * k);
    a.m[3][3] = real3(m33 * k);
    a.m[2][5] = real3(-r_fb * inv * k);
    a.m[4][1] = a.m[2][5];
    a.m[3][4] = real3(r_fb * inv * k);
    a.m[5][0] = a.m[3][4];
    a.m[2][0] = real3((m22 - m00) * k);
    a.m[3][1] = real3((m33 - transmission) * k);
    // (5,6) mirrors (3,4): M55 = M33, M66 = M44, M54 = M36, M63 = M45.
    a.m[4][4] = a.m[2][2];
    a.m[5][5] = a.m[3][3];
    a.m[4][3] = a.m[2][5];
    a.m[5][2] = a.m[3][4];
    return a;
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

// Pass 1: components top to bottom with their factors, following the mean direction (§5.1–5.3).
void tm6_components(MaterialGpu material, float mu, inout Tm6Component comps[TM6_MAX_COMPONENTS],
                    out uint count) {
    uint layers = min(material.info.x, MAX_LAYERS);
    float eta_above = IOR_AIR;
    float cos_i = mu;
    count = 0u;
    for (uint i = 0u; i < layers; ++i) {
        LayerGpu layer = material.layers[i];
        Tm6Component c;
        c.alpha = layer.params.x;
        c.mu = cos_i;
        c.mu_t = cos_i;
        c.eta = 1.0;
        float g_r = hg_g_of_alpha(c.alpha);
        if (tm_is_conductor(layer)) {
            c.kind = TM6_CONDUCTOR;
            c.r = vec3(fgd_rgb(cos_i, c.alpha, layer.ior.rgb / eta_above, layer.kappa.rgb / eta_above));
            c.t = vec3(0.0); c.rp = vec3(0.0); c.tp = vec3(0.0);
            c.rs = c.r; c.ts = c.t; c.rsp = c.rp; c.tsp = c.tp;
            c.g_primary = vec4(g_r, 0.0, 0.0, 0.0);
            c.g_secondary = c.g_primary;
            comps[count++] = c;
            return;
        }
        float eta_layer = tm_mean(layer.ior.rgb);
        c.eta = eta_layer / eta_above;
        if (abs(c.eta - 1.0) < 1e-5) {
            c.kind = TM6_NONE;
            c.r = vec3(0.0); c.t = vec3(1.0); c.rp = vec3(0.0); c.tp = vec3(1.0);
            // g_r stays: the interface above reads it as its "next reflection" (as in 2-flux).
            c.g_primary = vec4(g_r, 1.0, g_r, 1.0);
        } else {
            c.kind = TM6_INTERFACE;
            float cos_t = tm_refracted_cos(cos_i, c.eta);
            c.mu_t = cos_t;
            float s_down = abs(1.0 - cos_i / (c.eta * max(cos_t, 1e-7)));
            float s_up = abs(1.0 - c.eta * cos_t / max(cos_i, 1e-7));
            float r = abs(c.eta - 1.0) < 1e-3 ? 0.0 : fgd_dielectric(cos_i, c.alpha, c.eta);
            c.r = vec3(r); c.rp = vec3(r); c.t = vec3(1.0 - r); c.tp = vec3(1.0 - r);
            c.g_primary = vec4(g_r, hg_g_of_alpha(0.5 * s_down * c.alpha), g_r,
                               hg_g_of_alpha(0.5 * s_up * c.alpha));
            cos_i = cos_t;
            eta_above = eta_layer;
        }
        c.rs = c.r; c.ts = c.t; c.rsp = c.rp; c.tsp = c.tp;
        c.g_secondary = c.g_primary;
        comps[count++] = c;

        // The medium filling the layer, crossed along the refracted mean direction.
        Tm6Component m;
        m.alpha = 0.0;
        m.eta = 1.0;
        m.mu = cos_i;
        m.mu_t = cos_i;
        if (layer.params.y <= 0.0) {
            m.kind = TM6_NONE;
            m.r = vec3(0.0); m.t = vec3(1.0); m.rp = vec3(0.0); m.tp = vec3(1.0);
            m.rs = vec3(0.0); m.ts = vec3(1.0);
            m.g_primary = vec4(0.0, 1.0, 0.0, 1.0);
            m.g_secondary = vec4(0.0, 1.0, 0.0, 1.0);
        } else {
            m.kind = TM6_MEDIUM;
            vec3 transmission, r_fb, t_ff;
            float g_rfb, g_tff;
            tm6_medium_factors(layer, cos_i, transmission, r_fb, t_ff, g_rfb, g_tff);
            m.t = vec3(transmission);
            m.rs = vec3(r_fb);
            m.ts = vec3(t_ff);
            m.g_primary = vec4(0.0, 1.0, 0.0, 1.0);
            m.g_secondary = vec4(g_rfb, g_tff, g_rfb, g_tff);
        }
        comps[count++] = m;
    }
}

// g of the next interface's (or substrate's) reflection below component `c`, skipping the
// medium in between, and the g of that medium's forward transmission.
void tm6_next(Tm6Component comps[TM6_MAX_COMPONENTS], uint c, uint count,
              out float g_reflect, out float g_medium) {
    g_medium = c + 1u < count && comps[c + 1u].kind == TM6_MEDIUM ? comps[c + 1u].g_secondary.y : 1.0;
    g_reflect = c + 2u < count ? comps[c + 2u].g_primary.x : 0.0;
}

// Pass 2: compose, extract the three reflectances after each component, and emit the lobes
// the request flags allow (§5.5–5.7). Returns the lobe count.
uint tm6_evaluate(MaterialGpu material, float mu, inout Lobe lobes[TM_MAX_LOBES],
                  out vec3 reflectance, out vec3 transmittance) {
    Tm6Component comps[TM6_MAX_COMPONENTS];
    uint count;
    tm6_components(material, mu, comps, count);

    Tm6Matrix e = tm6_identity();
    Tm6Matrix g = tm6_identity();
    // e holds the energy matrix times `scale` (see tm6_normalize).
    float scale = 1.0;
    vec3 prev[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    vec3 prev_g[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    float g_t0i = 1.0;
    float g_st0i = 1.0;
    bool primary = false;
    bool backward = false;
    uint lobe_count = 0u;
    transmittance = vec3(0.0);
    for (uint ci = 0u; ci < count; ++ci) {
        Tm6Component c = comps[ci];
        vec3 up[3];
        vec3 up_g[3];
        vec3 down[3];
        float g_t0j = g_t0i;
        float g_st0j = g_st0i;
        if (c.kind == TM6_CONDUCTOR) {
            tm6_extract(e, c.r, up, down);
            tm6_extract(g, c.r * c.g_primary.x, up_g, down);
            transmittance = vec3(0.0);
            // A bare substrate emits its primary lobe too (the reference sets the flag only
            // after a dielectric, which would leave a single conductor without any lobe).
            primary = true;
        } else {
            if (c.kind == TM6_INTERFACE) {
                float g_next, g_medium;
                tm6_next(comps, ci, count, g_next, g_medium);
                // Primary path (§4.4).
                g_t0j = hg_refract(g_t0i, 1.0 / c.eta) * c.g_primary.y;
                float g_t0j_r = g_t0j * g_next;
                float g_t0j_rt = hg_refract(g_t0j_r, c.eta) * c.g_primary.w;
                c.g_primary.y = g_t0i > 0.0 ? g_t0j / g_t0i : 0.0;
                c.g_primary.w = g_t0j_r > 0.0 ? g_t0j_rt / g_t0j_r : 0.0;
                // Secondary path: the medium's forward transmission down and up (§5.5).
                g_st0j = hg_refract(g_st0i, 1.0 / c.eta) * c.g_secondary.y;
                float g_st0j_r = g_st0j * g_medium * g_next * g_medium;
                float g_st0j_rt = hg_refract(g_st0j_r, c.eta) * c.g_secondary.w;
                c.g_secondary.y = g_st0i > 0.0 ? g_st0j / g_st0i : 0.0;
                c.g_secondary.w = g_st0j_r > 0.0 ? g_st0j_rt / g_st0j_r : 0.0;
                if (c.eta < 1.0) {
                    vec3 tau = tir_fraction(c.mu, hg_alpha_of_g(g_t0i), c.eta) * c.t;
                    c.r += tau; c.t -= tau;
                    vec3 tau_s = tir_fraction(c.mu, hg_alpha_of_g(g_st0i), c.eta) * c.ts;
                    c.rs += tau_s; c.ts -= tau_s;
                } else {
                    vec3 tau = tir_fraction(c.mu_t, hg_alpha_of_g(g_t0j_r), 1.0 / c.eta) * c.tp;
                    c.rp += tau; c.tp -= tau;
                    vec3 tau_s = tir_fraction(c.mu_t, hg_alpha_of_g(g_st0j_r), 1.0 / c.eta) * c.tsp;
                    c.rsp += tau_s; c.tsp -= tau_s;
                }
                e = tm6_mul(e, tm6_interface(real3(c.r), real3(c.t), real3(c.rp), real3(c.tp),
                                             real3(c.rs), real3(c.ts), real3(c.rsp), real3(c.tsp)));
                scale *= tm6_normalize(e);
                g = tm6_mul(g, tm6_interface(
                    real3(c.r * c.g_primary.x), real3(c.t * c.g_primary.y),
                    real3(c.rp * c.g_primary.z), real3(c.tp * c.g_primary.w),
                    real3(c.rs * c.g_secondary.x), real3(c.ts * c.g_secondary.y),
                    real3(c.rsp * c.g_secondary.z), real3(c.tsp * c.g_secondary.w)));
                tm6_normalize(g);
                primary = true;
            } else if (c.kind == TM6_MEDIUM) {
                float k;
                e = tm6_mul(e, tm6_medium(c.t, c.rs, c.ts, k));
                scale *= k * tm6_normalize(e);
                g = tm6_mul(g, tm6_medium(c.t, c.rs * c.g_secondary.x, c.ts * c.g_secondary.y, k));
                tm6_normalize(g);
                backward = true;
            }
            tm6_extract(e, vec3(0.0), up, down);
            transmittance = (down[0] + down[1] + down[2]) * scale;
            tm6_extract(g, vec3(0.0), up_g, down);
        }
        // Emit primary, secondary-forward, secondary-backward lobes (§5.7).
        bool emit[3] = bool[3](primary, primary && backward, backward);
        for (int k = 0; k < 3; ++k) {
            vec3 delta = max(up[k] - prev[k], vec3(0.0));
            if (emit[k]) {
                vec3 dg = up_g[k] - prev_g[k];
                vec3 dr = up[k] - prev[k];
                float lobe_g = min((tm6_safe_ratio(dg.r, dr.r) + tm6_safe_ratio(dg.g, dr.g)
                                    + tm6_safe_ratio(dg.b, dr.b)) / 3.0, 1.0);
                lobes[lobe_count++] = Lobe(delta, hg_alpha_of_g(lobe_g),
                                           k == 2 ? LOBE_RETRO : LOBE_MIRROR);
            }
            prev[k] = up[k];
            prev_g[k] = up_g[k];
        }
        g_t0i = g_t0j;
        g_st0i = g_st0j;
    }
    reflectance = prev[0] + prev[1] + prev[2];
    return lobe_count;
}

#endif
