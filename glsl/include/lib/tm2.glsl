// The 2-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021), as the reference
// implementation defines it (ALGORITHMS.md §4): per-interface energy and asymmetry factors
// composed top to bottom by the adding equations (tm_common.glsl), one reflected lobe per layer.
// Mirrors src/model/tm2.rs.
//
// The per-layer state lives in arrays sized by the MAX_LAYERS specialization constant (the
// "static layer-array size" of the real-time study); loops run over the material's real layer
// count. Matrix arithmetic is in `real` (fp16 under the fp16 variant); directions and table
// lookups stay in float.
#ifndef LAMINA_LIB_TM2
#define LAMINA_LIB_TM2

#include "tm_common.glsl"

// Transfer factors of one component (§4.1): energies r, t (down) and r', t' (up), and the HG
// asymmetry of each.
struct Tm2Factors {
    real3 r, t, rp, tp;
    float gr, gt, grp, gtp;
    bool conductor;
    bool skip;        // η_ij ≈ 1: no interface (ENoComponent)
    float mu;         // |cos| of the mean incident direction on the component
    float mu_t;       // |cos| of the mean refracted direction below it
    float eta;        // relative IOR η_ij (dielectrics; mean over RGB)
    float alpha;      // interface roughness
};

// Pass 1: the factors of every layer for view cosine `mu`, following the mean direction down
// the stack by Snell's law (§4.1).
void tm2_factors(float mu, inout Tm2Factors comps[MAX_LAYERS], out uint count) {
    count = min(material.info.x, MAX_LAYERS);
    float eta_above = IOR_AIR;
    float cos_i = mu;
    for (uint i = 0u; i < count; ++i) {
        LayerGpu layer = material.layers[i];
        Tm2Factors c;
        c.alpha = layer.params.x;
        c.mu = cos_i;
        c.gr = hg_g_of_alpha(c.alpha);
        c.grp = c.gr;
        c.conductor = tm_is_conductor(layer);
        c.skip = false;
        c.eta = 1.0;
        c.mu_t = cos_i;
        if (c.conductor) {
            vec3 eta = layer.ior.rgb / eta_above;
            vec3 kappa = layer.kappa.rgb / eta_above;
            c.r = real3(fgd_rgb(cos_i, c.alpha, eta, kappa));
            c.t = real3(0.0);
            c.rp = real3(0.0);
            c.tp = real3(0.0);
            c.gt = 0.0;
            c.gtp = 0.0;
            comps[i] = c;
            count = i + 1u;
            return;
        }
        float eta_layer = tm_mean(layer.ior.rgb);
        c.eta = eta_layer / eta_above;
        if (abs(c.eta - 1.0) < TM_INDEX_MATCHED) {
            c.skip = true;
            c.r = real3(0.0);
            c.rp = real3(0.0);
            c.t = real3(1.0);
            c.tp = real3(1.0);
            c.gt = 1.0;
            c.gtp = 1.0;
            comps[i] = c;
            continue;
        }
        float cos_t = tm_refracted_cos(cos_i, c.eta);
        c.mu_t = cos_t;
        // Rough transmission widens less than reflection (§3.4).
        float s_down = abs(1.0 - cos_i / (c.eta * max(cos_t, 1e-7)));
        float s_up = abs(1.0 - c.eta * cos_t / max(cos_i, 1e-7));
        c.gt = hg_g_of_alpha(0.5 * s_down * c.alpha);
        c.gtp = hg_g_of_alpha(0.5 * s_up * c.alpha);
        float r = abs(c.eta - 1.0) < TM_REFLECTS_NOTHING ? 0.0 : fgd_dielectric(cos_i, c.alpha, c.eta);
        c.r = real3(r);
        c.rp = real3(r);
        c.t = real3(1.0 - r);
        c.tp = real3(1.0 - r);
        comps[i] = c;
        cos_i = cos_t;
        eta_above = eta_layer;
    }
}

// Pass 2: compose the components top to bottom by the adding equations and emit one lobe per
// layer through tm_emit_lobe (§4.2–4.6). Returns the lobe count (= layers); `reflectance` and
// `transmittance` get the stack totals.
uint tm2_evaluate(float mu, out vec3 reflectance, out vec3 transmittance) {
    Tm2Factors comps[MAX_LAYERS];
    uint count;
    tm2_factors(mu, comps, count);

    TmSlab e = tm_slab_empty();
    TmSlab1 g = tm_slab1_empty();
    real3 r_prev = real3(0.0);
    real g_prev = real(0.0);
    float g_t0i = 1.0;
    reflectance = vec3(0.0);
    transmittance = vec3(1.0);
    for (uint i = 0u; i < count; ++i) {
        Tm2Factors c = comps[i];
        real3 r_total;
        real g_total;
        float g_t0j = g_t0i;
        if (c.conductor) {
            r_total = tm_over_base(e, c.r);
            g_total = tm_bound(tm_over_base1(g, tm_avg(c.r) * real(c.gr)), tm_avg(r_total));
        } else if (c.skip) {
            r_total = r_prev;
            g_total = g_prev;
        } else {
            // First-order transmitted-asymmetry correction (§4.4).
            float g_next = i + 1u < count ? comps[i + 1u].gr : 0.0;
            g_t0j = hg_refract(g_t0i, 1.0 / c.eta) * c.gt;
            float g_t0j_r = g_t0j * g_next;
            float g_t0j_rt = hg_refract(g_t0j_r, c.eta) * c.gtp;
            c.gt = hg_safe_ratio(g_t0j, g_t0i);
            c.gtp = hg_safe_ratio(g_t0j_rt, g_t0j_r);
            // Total internal reflection moves energy from transmission to reflection (§4.5).
            if (c.eta < 1.0) {
                real3 tau = real(tir_fraction(c.mu, hg_alpha_of_g(g_t0i), c.eta)) * c.t;
                c.r += tau;
                c.t -= tau;
            } else {
                real3 tau = real(tir_fraction(c.mu_t, hg_alpha_of_g(g_t0j_r), 1.0 / c.eta)) * c.tp;
                c.rp += tau;
                c.tp -= tau;
            }
            e = tm_over(e, c.r, c.t, c.rp, c.tp);
            g = tm_bounded1(tm_over1(g, c.r.x * real(c.gr), c.t.x * real(c.gt),
                                     c.rp.x * real(c.grp), c.tp.x * real(c.gtp)), e);
            r_total = e.r;
            g_total = g.r;
        }
        transmittance = c.conductor ? vec3(0.0) : vec3(e.t);
        real3 weight = r_total - r_prev;
        real energy = tm_avg(weight);
        float lobe_g = energy > real(0.0) ? min(float((g_total - g_prev) / energy), 1.0) : 0.0;
        tm_emit_lobe(vec3(weight), hg_alpha_of_g(lobe_g), LOBE_MIRROR);
        r_prev = r_total;
        g_prev = g_total;
        g_t0i = g_t0j;
    }
    reflectance = vec3(r_prev);
    return count;
}

#endif
