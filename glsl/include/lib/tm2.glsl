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
    bool diffuse;     // a Lambertian base (src/model/diffuse.rs; its albedo is read where used)
    bool skip;        // η_ij ≈ 1: no interface (ENoComponent)
    float mu;         // |cos| of the mean incident direction on the component
    float mu_t;       // |cos| of the mean refracted direction below it
    float eta;        // relative IOR η_ij (dielectrics; mean over RGB)
    float alpha;      // interface roughness
};

// The factors of layer i for the mean direction arriving at cosine `cos_i` from a medium of
// IOR `eta_above`; both move below the layer (§4.1).
Tm2Factors tm2_factor(uint i, inout float eta_above, inout float cos_i) {
    LayerGpu layer = tm_layer(i);
    Tm2Factors c;
    c.alpha = layer.params.x;
    c.mu = cos_i;
    c.gr = hg_g_of_alpha(c.alpha);
    c.grp = c.gr;
    c.conductor = tm_conductor_at(i, layer);
    c.diffuse = tm_diffuse_at(i, layer);
    c.skip = false;
    c.eta = 1.0;
    c.mu_t = cos_i;
    if (c.diffuse) {
        c.r = real3(0.0);
        c.t = real3(0.0);
        c.rp = real3(0.0);
        c.tp = real3(0.0);
        c.gt = 0.0;
        c.gtp = 0.0;
        return c;
    }
    if (c.conductor) {
        vec3 eta = layer.ior.rgb / eta_above;
        vec3 kappa = layer.kappa.rgb / eta_above;
        c.r = real3(tm_albedo_rgb(i, cos_i, c.alpha, eta, kappa));
        c.t = real3(0.0);
        c.rp = real3(0.0);
        c.tp = real3(0.0);
        c.gt = 0.0;
        c.gtp = 0.0;
        return c;
    }
    float eta_layer = tm_mean(layer.ior.rgb);
    c.eta = eta_layer / eta_above;
    if (tm_matched_at(i, c.eta)) {
        c.skip = true;
        c.r = real3(0.0);
        c.rp = real3(0.0);
        c.t = real3(1.0);
        c.tp = real3(1.0);
        c.gt = 1.0;
        c.gtp = 1.0;
        return c;
    }
    float cos_t = tm_refracted_cos(cos_i, c.eta);
    c.mu_t = cos_t;
    // Rough transmission widens less than reflection (§3.4).
    float s_down = abs(1.0 - cos_i / (c.eta * max(cos_t, 1e-7)));
    float s_up = abs(1.0 - c.eta * cos_t / max(cos_i, 1e-7));
    c.gt = hg_g_of_alpha(0.5 * s_down * c.alpha);
    c.gtp = hg_g_of_alpha(0.5 * s_up * c.alpha);
    float r = tm_clear_at(i, c.eta) ? 0.0 : tm_albedo_dielectric(i, cos_i, c.alpha, c.eta);
    c.r = real3(r);
    c.rp = real3(r);
    c.t = real3(1.0 - r);
    c.tp = real3(1.0 - r);
    cos_i = cos_t;
    eta_above = eta_layer;
    return c;
}

// The factors of every layer, written by pass 1 and read by pass 2. A module-scope array, not a
// parameter: GLSL passes an array parameter by copy in and out, whole, and llvmpipe's compute
// path paid that copy in every slot of MAX_LAYERS (about 250 instructions per pixel each).
Tm2Factors tm2_comps[MAX_LAYERS];

// Pass 1: the factors of every layer for view cosine `mu` into `tm2_comps`, following the mean
// direction down the stack by Snell's law (§4.1). A generic pipeline stops at the conductor; a
// specialized one knows it is the last layer, and unrolls.
void tm2_factors(float mu, out uint count) {
    float eta_above = IOR_AIR;
    float cos_i = mu;
    if (SPECIALIZED) {
        count = LAYER_COUNT;
        [[unroll]] for (uint i = 0u; i < LAYER_COUNT; ++i) {
            tm2_comps[i] = tm2_factor(i, eta_above, cos_i);
        }
        return;
    }
    count = tm_layer_count();
    for (uint i = 0u; i < count; ++i) {
        tm2_comps[i] = tm2_factor(i, eta_above, cos_i);
        if (tm2_comps[i].conductor || (DIFFUSE_BASE != 0u && tm2_comps[i].diffuse)) {
            count = i + 1u;
            return;
        }
    }
}

// The composition so far (pass 2): the energy and g-weighted stacks, the totals of the lobes
// above, and the g of the primary path transmitted down to the current component.
struct Tm2State {
    TmSlab e;
    TmSlab1 g;
    real3 r_prev;
    real g_prev;
    float g_t0i;
    // Where the view cosine falls among the energy ratios' (transport=corrected), and the sum
    // of the lobes emitted (the paper's r_prev, or under transport=corrected the transported
    // energies).
    TmTransportAt at;
    vec3 emitted;
    // Whether an interface above has been met (tm_top_reflects' `first` until then).
    bool met;
};

// Adds component c (layer i; `g_next`: the g of the next layer's reflection) below the stack
// by the adding equations and emits its lobe (§4.2–4.6); `transmittance` gets the stack's.
void tm2_add(uint i, Tm2Factors c, float g_next, inout Tm2State s, inout vec3 transmittance) {
    real3 r_total;
    real g_total;
    float g_t0j = s.g_t0i;
    // The constant first: `c` comes from an array, which hides that `diffuse` is false when
    // no diffuse base can occur, and lavapipe would run the branch masked at every layer.
    if (DIFFUSE_BASE != 0u && c.diffuse) {
        // A Lambertian base under the layers above: one diffuse lobe, nothing transmitted.
        vec3 rho = tm_layer(i).diffuse.rgb;
        vec3 weight = tm_diffuse_weight(vec3(s.e.t), rho, tm_diffuse_slab(i, false));
        vec3 emitted = tm_transported(i, s.at, weight);
        tm_emit_lobe(emitted, 1.0, LOBE_DIFFUSE, vec2(0.0));
        s.emitted += emitted;
        s.r_prev += real3(weight);
        transmittance = vec3(0.0);
        return;
    }
    if (c.conductor) {
        r_total = tm_over_base(s.e, c.r);
        g_total = tm_bound(tm_over_base1(s.g, tm_avg(c.r) * real(c.gr)), tm_avg(r_total));
    } else if (c.skip) {
        r_total = s.r_prev;
        g_total = s.g_prev;
    } else {
        // First-order transmitted-asymmetry correction (§4.4).
        g_t0j = hg_refract(s.g_t0i, 1.0 / c.eta) * c.gt;
        float g_t0j_r = g_t0j * g_next;
        float g_t0j_rt = hg_refract(g_t0j_r, c.eta) * c.gtp;
        c.gt = hg_safe_ratio(g_t0j, s.g_t0i);
        c.gtp = hg_safe_ratio(g_t0j_rt, g_t0j_r);
        // Total internal reflection moves energy from transmission to reflection (§4.5).
        if (!tm_denser_at(i, c.eta)) {
            real3 tau = real(tir_fraction(c.mu, s.g_t0i, c.eta)) * c.t;
            c.r += tau;
            c.t -= tau;
        } else {
            real3 tau = real(tir_fraction(c.mu_t, g_t0j_r, 1.0 / c.eta)) * c.tp;
            c.rp += tau;
            c.tp -= tau;
        }
        s.e = tm_over(s.e, c.r, c.t, c.rp, c.tp);
        s.g = tm_bounded1(tm_over1(s.g, c.r.x * real(c.gr), c.t.x * real(c.gt),
                                   c.rp.x * real(c.grp), c.tp.x * real(c.gtp)), s.e);
        r_total = s.e.r;
        g_total = s.g.r;
    }
    transmittance = c.conductor ? vec3(0.0) : vec3(s.e.t);
    real3 weight = r_total - s.r_prev;
    real energy = tm_avg(weight);
    float lobe_g = energy > real(0.0) ? min(float((g_total - s.g_prev) / energy), 1.0) : 0.0;
    vec3 emitted = tm_transported(i, s.at, vec3(weight));
    // The top's lobe: nothing above it, so its weight is the interface's own albedo c.r.
    bool top = tm_top_reflects(i, !s.met, c.conductor, c.eta);
    s.met = s.met || !c.skip;
    tm_emit_lobe(emitted, hg_alpha_of_g(lobe_g), top ? LOBE_FRESNEL : LOBE_MIRROR,
                 top ? vec2(c.eta, float(weight.x)) : vec2(0.0));
    s.emitted += emitted;
    s.r_prev = r_total;
    s.g_prev = g_total;
    s.g_t0i = g_t0j;
}

// Pass 2: compose the components top to bottom by the adding equations and emit one lobe per
// layer through tm_emit_lobe (§4.2–4.6). Returns the lobe count (= layers); `reflectance` and
// `transmittance` get the stack totals, `transmitted_alpha` the roughness of the transmitted
// lobe (tm_transmitted_alpha; 0 where TRANSMITS is 0).
uint tm2_evaluate(float mu, out vec3 reflectance, out vec3 transmittance,
                  out float transmitted_alpha) {
    uint count;
    tm2_factors(mu, count);

    Tm2State s = Tm2State(tm_slab_empty(), tm_slab1_empty(), real3(0.0), real(0.0), 1.0,
                          tm_transport_at(mu), vec3(0.0), false);
    transmittance = vec3(1.0);
    if (SPECIALIZED) {
        [[unroll]] for (uint i = 0u; i < LAYER_COUNT; ++i) {
            float g_next = i + 1u < LAYER_COUNT ? tm2_comps[i + 1u].gr : 0.0;
            tm2_add(i, tm2_comps[i], g_next, s, transmittance);
        }
    } else {
        for (uint i = 0u; i < count; ++i) {
            float g_next = i + 1u < count ? tm2_comps[i + 1u].gr : 0.0;
            tm2_add(i, tm2_comps[i], g_next, s, transmittance);
        }
    }
    reflectance = TRANSPORT == TRANSPORT_CORRECTED ? s.emitted : vec3(s.r_prev);
    transmittance = tm_transported_transmittance(s.at, transmittance);
    transmitted_alpha = TRANSMITS != 0u ? tm_transmitted_alpha(s.g_t0i, count) : 0.0;
    return count;
}

#endif
