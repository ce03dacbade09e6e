// The 6-flux transfer-matrix model (Randrianandrasana, Callet & Lucas 2021), as the reference
// implementation defines it (ALGORITHMS.md §5): fluxes (1,2) primary down/up, (3,4) secondary
// forward class, (5,6) secondary backward class; components alternate interface, medium, …,
// substrate. Mirrors src/model/tm6.rs.
//
// The stack is walked in one pass, component by component, and each lobe goes to the including
// shader's tm_emit_lobe as soon as it is known: no per-component or per-lobe array (but for
// channels=serial's held lobes, below, which an unrolled walk indexes by constants). Function-local
// arrays indexed by the loop counter are what made this shader slow to compile on llvmpipe (its
// indirect accesses become branch ladders as long as the array, about 5 s of LLVM per layer of
// `max_layers`) — profiling/README.md. Components are added below the stack by the adding
// equations with 3×3 operators between the flux classes (the reference's 6×6 transfer-matrix
// products and 3×3 extraction give the same values wherever they exist; src/model/adding.rs
// says where they do not). An interface is block-diagonal and a medium has seven non-zero
// operator entries, so each has its own composition function.
//
// The 3×3 adding state is float under fp16 too: half floats cannot resolve the gap between a
// TIR interface and a near-lossless thick scatterer below it (1 − R'r ≈ 1e-3 and below), and
// random valid stacks came out up to 0.44 off in reflectance. fp16=on therefore leaves the
// 6-flux model in float and narrows the 2-flux one (tm2.glsl), whose denominators are sums of
// non-negative terms.
#ifndef LAMINA_LIB_TM6
#define LAMINA_LIB_TM6

#include "tm_common.glsl"
#include "medium.glsl"

// The channels one walk carries (the `channels` axis, issue 28 item 5). By default all three
// at once: every value below is a vec3. Under LAMINA_TM6_SERIAL (`channels=serial`) a float:
// tm6_evaluate walks the stack once per channel, so only one channel's two slabs are live at a
// time (a third of the 198 floats of the energy and g-weighted slabs, which a GPU otherwise
// keeps in registers or spills), and recomputes each walk's scalar factors three times. The
// channels are independent in the model (src/model/adding.rs: even the bound's reset of q is
// per channel) except where a lobe's g averages them: the serial walk holds each lobe's first
// two channels (tm6_held_*) and emits it in the third. TM6_CH picks the walk's channel `c` out
// of an RGB value; TM6_NE is a per-channel `!=` and TM6_POS a per-channel `> 0`.
#ifdef LAMINA_TM6_SERIAL
#define TM6_T float
#define TM6_CH(v) ((v)[c])
#define TM6_NE(a, b) ((a) != (b))
#define TM6_POS(a) ((a) > 0.0)
#else
#define TM6_T vec3
#define TM6_CH(v) (v)
#define TM6_NE(a, b) notEqual(a, b)
#define TM6_POS(a) greaterThan(a, vec3(0.0))
#endif

// The stack composed so far, per channel, as scattering between the three flux classes
// (0 primary, 1 secondary forward, 2 secondary backward; src/model/adding.rs): for unit primary
// light from above, the upward fluxes above it (`up`: r, r_f, r_b) and the downward fluxes at its
// bottom (`down`); for light from below, the 3×3 reflection `rp`, transmission `tp` and
// q = I − rp ([out][in]). Components are added below it by the adding equations: every value
// stays an energy (or its g-weighted share), where the reference's 6×6 transfer matrices hold
// 1/T and 1/t_ff and overflow or divide 0 by 0 under thick media and opaque components.
struct Tm6Slab {
    TM6_T up[3];
    TM6_T down[3];
    TM6_T rp[3][3];
    TM6_T tp[3][3];
    TM6_T q[3][3];
};

Tm6Slab tm6_slab_empty() {
    Tm6Slab s;
    for (int i = 0; i < 3; ++i) {
        s.up[i] = TM6_T(0.0);
        s.down[i] = TM6_T(i == 0 ? 1.0 : 0.0);
        for (int j = 0; j < 3; ++j) {
            s.rp[i][j] = TM6_T(0.0);
            s.tp[i][j] = TM6_T(i == j ? 1.0 : 0.0);
            s.q[i][j] = s.tp[i][j];
        }
    }
    return s;
}

// w = a⁻¹ by the adjugate. a = I − R'r is singular only where light is trapped between the
// stack and the component below; a determinant below 4 float epsilons of its rows' scale (|a|³)
// is that trap at the precision's resolution (src/model/adding.rs), and is floored there.
void tm6_inverse(TM6_T m[3][3], out TM6_T w[3][3]) {
    TM6_T a[3][3] = m;
    TM6_T c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    TM6_T c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    TM6_T c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    TM6_T det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
    TM6_T scale = max(max(abs(a[0][0]) + abs(a[0][1]) + abs(a[0][2]),
                         abs(a[1][0]) + abs(a[1][1]) + abs(a[1][2])),
                     abs(a[2][0]) + abs(a[2][1]) + abs(a[2][2]));
    TM6_T inv = 1.0 / max(det, max(4.76837158e-7 * scale * scale * scale, TM6_T(1.17549435e-38)));
    w[0][0] = c00 * inv;
    w[1][0] = c01 * inv;
    w[2][0] = c02 * inv;
    w[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) * inv;
    w[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) * inv;
    w[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) * inv;
    w[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) * inv;
    w[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) * inv;
    w[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) * inv;
}

// p = w·s.rp, then the flux x = w·s.down between the stack and what is added below it.
void tm6_gap(Tm6Slab s, TM6_T w[3][3], out TM6_T p[3][3], out TM6_T x[3]) {
    for (int i = 0; i < 3; ++i) {
        x[i] = w[i][0] * s.down[0] + w[i][1] * s.down[1] + w[i][2] * s.down[2];
        for (int j = 0; j < 3; ++j) {
            p[i][j] = w[i][0] * s.rp[0][j] + w[i][1] * s.rp[1][j] + w[i][2] * s.rp[2][j];
        }
    }
}

// s ← s over an interface: each class on its own (block-diagonal, §5.2), the primary class
// (k = 0) with (r, t, r', t', 1 − r, 1 − r')[0], both secondary classes with [1]. With
// W = (q + R'·(1 − r))⁻¹, P = W·R' and V = I + r·P: R' ← r' + t·P·t', T' ← T'·V·t' and
// q ← (q + a·R')·V·t' + a' (a = 1 − r − t and a' = 1 − r' − t': 0 for the energies).
void tm6_over_interface(inout Tm6Slab s, TM6_T r[2], TM6_T t[2], TM6_T rp[2], TM6_T tp[2],
                        TM6_T one_minus_r[2], TM6_T one_minus_rp[2]) {
    TM6_T rd[3] = TM6_T[3](r[0], r[1], r[1]);
    TM6_T td[3] = TM6_T[3](t[0], t[1], t[1]);
    TM6_T rpd[3] = TM6_T[3](rp[0], rp[1], rp[1]);
    TM6_T tpd[3] = TM6_T[3](tp[0], tp[1], tp[1]);
    TM6_T omr[3] = TM6_T[3](one_minus_r[0], one_minus_r[1], one_minus_r[1]);
    TM6_T omrp[3] = TM6_T[3](one_minus_rp[0], one_minus_rp[1], one_minus_rp[1]);
    TM6_T x[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            x[i][j] = s.q[i][j] + s.rp[i][j] * omr[j];
        }
    }
    TM6_T w[3][3];
    tm6_inverse(x, w);
    TM6_T p[3][3];
    TM6_T flux[3];
    tm6_gap(s, w, p, flux);
    for (int i = 0; i < 3; ++i) {
        s.up[i] += s.tp[i][0] * rd[0] * flux[0] + s.tp[i][1] * rd[1] * flux[1]
                 + s.tp[i][2] * rd[2] * flux[2];
        s.down[i] = td[i] * flux[i];
    }
    TM6_T tv[3][3];
    TM6_T qv[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            TM6_T v = s.tp[i][j];
            TM6_T u = s.q[i][j] + (omr[i] - td[i]) * s.rp[i][j];
            for (int k = 0; k < 3; ++k) {
                TM6_T rpk = rd[k] * p[k][j];
                v += s.tp[i][k] * rpk;
                u += (s.q[i][k] + (omr[i] - td[i]) * s.rp[i][k]) * rpk;
            }
            tv[i][j] = v * tpd[j];
            qv[i][j] = u * tpd[j] + (i == j ? omrp[i] - tpd[i] : TM6_T(0.0));
        }
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            s.tp[i][j] = tv[i][j];
            s.q[i][j] = qv[i][j];
            s.rp[i][j] = td[i] * p[i][j] * tpd[j] + (i == j ? rpd[i] : TM6_T(0.0));
        }
    }
}

// s ← s over a homogeneous medium of primary transmission T, secondary back-reflection r_fb,
// forward transmission t_ff and primary-to-forward transfer `cross` (t_ff − T for the energies;
// §5.4 in scattering form, adding.rs's Component6::medium):
//   r = r' = [[0, 0, 0], [0, 0, r_fb], [r_fb, r_fb, 0]],
//   t = t' = [[T, 0, 0], [cross, t_ff, 0], [0, 0, t_ff]];
// it mixes the classes, so q ← I − R' afterwards.
void tm6_over_medium(inout Tm6Slab s, TM6_T transmission, TM6_T cross, TM6_T r_fb, TM6_T t_ff) {
    TM6_T x[3][3];
    for (int i = 0; i < 3; ++i) {
        x[i][0] = s.q[i][0] + s.rp[i][0] - s.rp[i][2] * r_fb;
        x[i][1] = s.q[i][1] + s.rp[i][1] - s.rp[i][2] * r_fb;
        x[i][2] = s.q[i][2] + s.rp[i][2] - s.rp[i][1] * r_fb;
    }
    TM6_T w[3][3];
    tm6_inverse(x, w);
    TM6_T p[3][3];
    TM6_T flux[3];
    tm6_gap(s, w, p, flux);
    TM6_T back1 = r_fb * flux[2];
    TM6_T back2 = r_fb * (flux[0] + flux[1]);
    for (int i = 0; i < 3; ++i) {
        s.up[i] += s.tp[i][1] * back1 + s.tp[i][2] * back2;
    }
    s.down[0] = transmission * flux[0];
    s.down[1] = cross * flux[0] + t_ff * flux[1];
    s.down[2] = t_ff * flux[2];
    // V = I + r·P (rows: 0, r_fb·P₂, r_fb·(P₀ + P₁)), then T' ← T'·V·t' and R' ← r' + t·P·t'.
    TM6_T tv[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            tv[i][j] = s.tp[i][j] + s.tp[i][1] * r_fb * p[2][j]
                     + s.tp[i][2] * r_fb * (p[0][j] + p[1][j]);
        }
    }
    TM6_T c[3][3];
    for (int j = 0; j < 3; ++j) {
        c[0][j] = transmission * p[0][j];
        c[1][j] = cross * p[0][j] + t_ff * p[1][j];
        c[2][j] = t_ff * p[2][j];
    }
    for (int i = 0; i < 3; ++i) {
        s.tp[i][0] = tv[i][0] * transmission + tv[i][1] * cross;
        s.tp[i][1] = tv[i][1] * t_ff;
        s.tp[i][2] = tv[i][2] * t_ff;
        s.rp[i][0] = c[i][0] * transmission + c[i][1] * cross;
        s.rp[i][1] = c[i][1] * t_ff;
        s.rp[i][2] = c[i][2] * t_ff;
    }
    s.rp[1][2] += r_fb;
    s.rp[2][0] += r_fb;
    s.rp[2][1] += r_fb;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            s.q[i][j] = TM6_T(i == j ? 1.0 : 0.0) - s.rp[i][j];
        }
    }
}

// A g-weighted flux bounded by its energy (tm_common.glsl's tm_bound).
TM6_T tm6_bound3(TM6_T g_weighted, TM6_T energy) {
    return clamp(g_weighted, -abs(energy), abs(energy));
}

// The g-weighted stack `g` bounded entry by entry by the energy stack `e`. A channel whose R′
// the bound moved takes q = I − R′ (src/model/adding.rs's Slab6::bounded_by).
void tm6_bound(inout Tm6Slab g, Tm6Slab e) {
    TM6_T moved = TM6_T(0.0);
    for (int i = 0; i < 3; ++i) {
        g.up[i] = tm6_bound3(g.up[i], e.up[i]);
        g.down[i] = tm6_bound3(g.down[i], e.down[i]);
        for (int j = 0; j < 3; ++j) {
            TM6_T rp = tm6_bound3(g.rp[i][j], e.rp[i][j]);
            moved = max(moved, TM6_T(TM6_NE(rp, g.rp[i][j])));
            g.rp[i][j] = rp;
            g.tp[i][j] = tm6_bound3(g.tp[i][j], e.tp[i][j]);
        }
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            g.q[i][j] = mix(g.q[i][j], TM6_T(i == j ? 1.0 : 0.0) - g.rp[i][j], TM6_POS(moved));
        }
    }
}

// The upward fluxes above the stack over an opaque base reflecting every class with r_c (§5.6):
// up + T'·r_c·(q + R'·(1 − r_c))⁻¹·down.
void tm6_over_base(Tm6Slab s, TM6_T r_c, out TM6_T up[3]) {
    TM6_T x[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            x[i][j] = s.q[i][j] + s.rp[i][j] * (TM6_T(1.0) - r_c);
        }
    }
    TM6_T w[3][3];
    tm6_inverse(x, w);
    TM6_T flux[3];
    for (int i = 0; i < 3; ++i) {
        flux[i] = r_c * (w[i][0] * s.down[0] + w[i][1] * s.down[1] + w[i][2] * s.down[2]);
    }
    for (int i = 0; i < 3; ++i) {
        up[i] = s.up[i] + s.tp[i][0] * flux[0] + s.tp[i][1] * flux[1] + s.tp[i][2] * flux[2];
    }
}

// The walk so far (tm6_step): the energy slab `e` and the asymmetry slab `g`, which hold the
// three reflectances as they grow, the lobe totals above, the g of the primary and secondary
// paths transmitted down to the current component, which lobes the components so far allow,
// the mean direction, and the current layer's medium (found at its interface, whose secondary
// path needs its g).
struct Tm6Walk {
    Tm6Slab e;
    Tm6Slab g;
    TM6_T prev[3];
    TM6_T prev_g[3];
    float g_t0i;
    float g_st0i;
    bool primary;
    bool backward;
    uint lobe_count;
    float eta_above;
    float cos_i;
    bool medium;
    TM6_T m_transmission;
    TM6_T m_r_fb;
    TM6_T m_t_ff;
    float m_g_rfb;
    float m_g_tff;
    // Where the view cosine falls among the energy ratios' (transport=corrected), and the sum
    // of the lobes emitted (under transport=corrected, the transported energies).
    TmTransportAt at;
    vec3 emitted;
};

// A lobe's mean cosine summed over the walk's channels: its g is the sum's mean over three.
float tm6_ratio_sum(vec3 dg, vec3 dr) {
    return hg_safe_ratio(dg.r, dr.r) + hg_safe_ratio(dg.g, dr.g) + hg_safe_ratio(dg.b, dr.b);
}

float tm6_ratio_sum(float dg, float dr) {
    return hg_safe_ratio(dg, dr);
}

#ifdef LAMINA_TM6_SERIAL
// The first two channels' weights and summed ratios of each lobe, by slot (3 per step: step
// 2i + 1's lobes follow step 2i's), until the third channel's walk emits it. A specialized
// pipeline's walk is unrolled, so every slot is a constant and these are registers.
const uint TM6_HELD = 6u * (LAYER_COUNT > MAX_LAYERS ? LAYER_COUNT : MAX_LAYERS);
float tm6_held_r[TM6_HELD];
float tm6_held_g[TM6_HELD];
float tm6_held_ratio[TM6_HELD];
#endif

// Emits a lobe of layer `i` (§5.7): its weight and the summed ratio of its channels, in
// `slot` of the walk of channel `c` (channels=serial, which holds it until the last channel's
// walk); a diffuse lobe's α is 1, a LOBE_FRESNEL lobe's interface of relative IOR `eta`.
void tm6_emit(inout Tm6Walk w, uint i, uint slot, uint c, TM6_T weight, float ratio,
              uint kind, float eta) {
#ifdef LAMINA_TM6_SERIAL
    if (c == 0u) {
        tm6_held_r[slot] = weight;
        tm6_held_ratio[slot] = ratio;
        return;
    }
    if (c == 1u) {
        tm6_held_g[slot] = weight;
        tm6_held_ratio[slot] += ratio;
        return;
    }
    vec3 rgb = vec3(tm6_held_r[slot], tm6_held_g[slot], weight);
    float sum = tm6_held_ratio[slot] + ratio;
#else
    vec3 rgb = weight;
    float sum = ratio;
#endif
    vec3 emitted = tm_transported(i, w.at, rgb);
    tm_emit_lobe(emitted, kind == LOBE_DIFFUSE ? 1.0 : hg_alpha_of_g(min(sum / 3.0, 1.0)), kind,
                 kind == LOBE_FRESNEL ? vec2(eta, rgb.x) : vec2(0.0));
    w.emitted += emitted;
}

// Step `step` of the walk down a stack of `layers` layers, in channel `c` under
// channels=serial: step 2i is layer i's interface (nothing when index-matched, or the
// substrate, which ends the walk: returns true), step 2i + 1 its medium (nothing when its
// depth is 0). Each step adds its factors below the slabs and emits the lobes the flags allow
// (§5.5–5.7) through tm6_emit.
bool tm6_step(uint step, uint layers, uint c, inout Tm6Walk w, inout TM6_T transmittance) {
    uint i = step >> 1u;
    LayerGpu layer = tm_layer(i);
    bool substrate = false;
    // The top's lobe (LOBE_FRESNEL): layer 0's interface, when it reflects from the air.
    float top_eta = 0.0;
    TM6_T up[3] = w.e.up;
    TM6_T up_g[3] = w.g.up;
    if ((step & 1u) == 0u && tm_diffuse_at(i, layer)) {
        // A Lambertian base under the layers above: every flux class reaching it feeds one
        // diffuse lobe, which ends the walk. Its weight is per channel.
        TM6_T t_view = w.e.down[0] + w.e.down[1] + w.e.down[2];
        TM6_T weight = TM6_CH(tm_diffuse_weight(vec3(t_view), layer.diffuse.rgb,
                                                tm_diffuse_slab(i, true)));
        tm6_emit(w, i, 3u * step, c, weight, 0.0, LOBE_DIFFUSE, 0.0);
        w.lobe_count++;
        w.prev[0] += weight;
        transmittance = TM6_T(0.0);
        return true;
    }
    if ((step & 1u) == 0u && tm_conductor_at(i, layer)) {
        substrate = true;
        vec3 r_c = tm_albedo_rgb(i, w.cos_i, layer.params.x, layer.ior.rgb / w.eta_above,
                                 layer.kappa.rgb / w.eta_above);
        tm6_over_base(w.e, TM6_CH(r_c), up);
        tm6_over_base(w.g, TM6_CH(r_c * hg_g_of_alpha(layer.params.x)), up_g);
        for (int k = 0; k < 3; ++k) {
            up_g[k] = tm6_bound3(up_g[k], up[k]);
        }
        // A bare substrate emits its primary lobe too (the reference sets the flag only
        // after a dielectric, which would leave a single conductor without any lobe).
        w.primary = true;
    } else if ((step & 1u) == 0u) {
        float alpha = layer.params.x;
        float eta_layer = tm_mean(layer.ior.rgb);
        float eta = eta_layer / w.eta_above;
        float cos_below = w.cos_i;
        bool refracts = !tm_matched_at(i, eta);
        if (refracts) {
            cos_below = tm_refracted_cos(w.cos_i, eta);
        }
        if (tm_top_reflects(i, !w.primary && !w.backward, false, eta)) {
            top_eta = eta;
        }
        w.medium = tm_medium_at(i, layer);
        if (w.medium) {
            vec3 transmission, r_fb, t_ff;
            medium_factors(layer, cos_below, transmission, r_fb, t_ff, w.m_g_rfb, w.m_g_tff);
            w.m_transmission = TM6_CH(transmission);
            w.m_r_fb = TM6_CH(r_fb);
            w.m_t_ff = TM6_CH(t_ff);
        }
        if (refracts) {
            float g_r = hg_g_of_alpha(alpha);
            // Rough transmission widens less than reflection (§3.4).
            float s_down = abs(1.0 - w.cos_i / (eta * max(cos_below, 1e-7)));
            float s_up = abs(1.0 - eta * cos_below / max(w.cos_i, 1e-7));
            float g_t = hg_g_of_alpha(0.5 * s_down * alpha);
            float g_tp = hg_g_of_alpha(0.5 * s_up * alpha);
            // g of the next layer's reflection, and of this layer's medium crossed forward.
            float g_next = i + 1u < layers ? hg_g_of_alpha(tm_layer(i + 1u).params.x) : 0.0;
            float g_medium = w.medium ? w.m_g_tff : 1.0;
            // Primary path (§4.4).
            float g_t0j = hg_refract(w.g_t0i, 1.0 / eta) * g_t;
            float g_t0j_r = g_t0j * g_next;
            float g_t0j_rt = hg_refract(g_t0j_r, eta) * g_tp;
            float gt = hg_safe_ratio(g_t0j, w.g_t0i);
            float gtp = hg_safe_ratio(g_t0j_rt, g_t0j_r);
            // Secondary path: the medium's forward transmission down and up (§5.5).
            float g_st0j = hg_refract(w.g_st0i, 1.0 / eta) * g_t;
            float g_st0j_r = g_st0j * g_medium * g_next * g_medium;
            float g_st0j_rt = hg_refract(g_st0j_r, eta) * g_tp;
            float gst = hg_safe_ratio(g_st0j, w.g_st0i);
            float gstp = hg_safe_ratio(g_st0j_rt, g_st0j_r);
            float r0 = tm_clear_at(i, eta) ? 0.0 : tm_albedo_dielectric(i, w.cos_i, alpha, eta);
            TM6_T r = TM6_T(r0), t = TM6_T(1.0 - r0), rp = TM6_T(r0), tp = TM6_T(1.0 - r0);
            TM6_T rs = r, ts = t, rsp = rp, tsp = tp;
            // Total internal reflection moves energy from transmission to reflection (§4.5).
            if (!tm_denser_at(i, eta)) {
                TM6_T tau = tir_fraction(w.cos_i, w.g_t0i, eta) * t;
                r += tau; t -= tau;
                TM6_T tau_s = tir_fraction(w.cos_i, w.g_st0i, eta) * ts;
                rs += tau_s; ts -= tau_s;
            } else {
                TM6_T tau = tir_fraction(cos_below, g_t0j_r, 1.0 / eta) * tp;
                rp += tau; tp -= tau;
                TM6_T tau_s = tir_fraction(cos_below, g_st0j_r, 1.0 / eta) * tsp;
                rsp += tau_s; tsp -= tau_s;
            }
            // Energies: lossless, 1 − r = t. Asymmetries: 1 − r as it is.
            TM6_T et[2] = TM6_T[2](t, ts);
            TM6_T etp[2] = TM6_T[2](tp, tsp);
            tm6_over_interface(w.e, TM6_T[2](r, rs), et, TM6_T[2](rp, rsp), etp, et, etp);
            TM6_T gr[2] = TM6_T[2](r * g_r, rs * g_r);
            TM6_T grp[2] = TM6_T[2](rp * g_r, rsp * g_r);
            tm6_over_interface(w.g, gr, TM6_T[2](t * gt, ts * gst), grp,
                               TM6_T[2](tp * gtp, tsp * gstp),
                               TM6_T[2](TM6_T(1.0) - gr[0], TM6_T(1.0) - gr[1]),
                               TM6_T[2](TM6_T(1.0) - grp[0], TM6_T(1.0) - grp[1]));
            tm6_bound(w.g, w.e);
            up = w.e.up;
            up_g = w.g.up;
            w.primary = true;
            w.g_t0i = g_t0j;
            w.g_st0i = g_st0j;
            w.cos_i = cos_below;
            w.eta_above = eta_layer;
        }
    } else if (w.medium) {
        TM6_T mt = w.m_transmission;
        TM6_T mr = w.m_r_fb;
        TM6_T mtf = w.m_t_ff;
        tm6_over_medium(w.e, mt, mtf - mt, mr, mtf);
        // The g-weighted medium, each entry bounded by its energy (adding.rs's
        // Component6::medium_weighted).
        TM6_T gt = tm6_bound3(w.m_t_ff * w.m_g_tff, mtf);
        tm6_over_medium(w.g, mt, tm6_bound3(gt - mt, mtf - mt),
                        tm6_bound3(w.m_r_fb * w.m_g_rfb, mr), gt);
        tm6_bound(w.g, w.e);
        up = w.e.up;
        up_g = w.g.up;
        w.backward = true;
    }
    transmittance = substrate ? TM6_T(0.0) : w.e.down[0] + w.e.down[1] + w.e.down[2];
    // Emit primary, secondary-forward, secondary-backward lobes (§5.7).
    bool emit[3] = bool[3](w.primary, w.primary && w.backward, w.backward);
    for (int k = 0; k < 3; ++k) {
        if (emit[k]) {
            TM6_T dr = up[k] - w.prev[k];
            uint kind = k == 2 ? LOBE_RETRO
                : (k == 0 && top_eta > 0.0 ? LOBE_FRESNEL : LOBE_MIRROR);
            tm6_emit(w, i, 3u * step + uint(k), c, max(dr, TM6_T(0.0)),
                     tm6_ratio_sum(up_g[k] - w.prev_g[k], dr), kind, top_eta);
            w.lobe_count++;
        }
        w.prev[k] = up[k];
        w.prev_g[k] = up_g[k];
    }
    return substrate;
}

// The walk of channel `c` (every channel at once unless channels=serial) for view cosine `mu`
// (tm6_step). A specialized pipeline knows the substrate is the last layer: its walk has a
// constant length (one step fewer over a conductor) and unrolls.
Tm6Walk tm6_walk(float mu, TmTransportAt at, uint c, out TM6_T transmittance) {
    Tm6Walk w;
    w.e = tm6_slab_empty();
    w.g = tm6_slab_empty();
    w.prev = TM6_T[3](TM6_T(0.0), TM6_T(0.0), TM6_T(0.0));
    w.prev_g = TM6_T[3](TM6_T(0.0), TM6_T(0.0), TM6_T(0.0));
    w.g_t0i = 1.0;
    w.g_st0i = 1.0;
    w.primary = false;
    w.backward = false;
    w.lobe_count = 0u;
    w.eta_above = IOR_AIR;
    w.cos_i = mu;
    w.medium = false;
    w.m_transmission = TM6_T(1.0);
    w.m_r_fb = TM6_T(0.0);
    w.m_t_ff = TM6_T(1.0);
    w.m_g_rfb = 0.0;
    w.m_g_tff = 1.0;
    w.at = at;
    w.emitted = vec3(0.0);
    transmittance = TM6_T(1.0);
    if (SPECIALIZED) {
        // A conductor or a diffuse base ends the walk at its interface: no medium step.
        uint ends_opaque = CONDUCTOR_BASE != 0u || DIFFUSE_BASE != 0u ? 1u : 0u;
        [[unroll]] for (uint step = 0u; step < 2u * LAYER_COUNT - ends_opaque; ++step) {
            tm6_step(step, LAYER_COUNT, c, w, transmittance);
        }
    } else {
        uint layers = tm_layer_count();
        for (uint step = 0u; step < 2u * layers; ++step) {
            if (tm6_step(step, layers, c, w, transmittance)) {
                break;
            }
        }
    }
    return w;
}

// Walks the stack top to bottom for view cosine `mu`: once, or once per channel under
// channels=serial. Returns the lobe count; `transmitted_alpha` as tm2_evaluate's.
uint tm6_evaluate(float mu, out vec3 reflectance, out vec3 transmittance,
                  out float transmitted_alpha) {
    TmTransportAt at = tm_transport_at(mu);
    Tm6Walk w;
#ifdef LAMINA_TM6_SERIAL
    // One channel at a time. Unrolled: where the channel is a constant, the first two walks'
    // emissions fold away (lavapipe would run them, lights and all, under a lane mask).
    [[unroll]] for (uint c = 0u; c < 3u; ++c) {
        float through;
        w = tm6_walk(mu, at, c, through);
        reflectance[c] = w.prev[0] + w.prev[1] + w.prev[2];
        transmittance[c] = through;
    }
#else
    w = tm6_walk(mu, at, 0u, transmittance);
    reflectance = w.prev[0] + w.prev[1] + w.prev[2];
#endif
    // The last walk emitted every lobe, whole.
    if (TRANSPORT == TRANSPORT_CORRECTED) {
        reflectance = w.emitted;
    }
    transmittance = tm_transported_transmittance(at, transmittance);
    transmitted_alpha = TRANSMITS != 0u
        ? tm_transmitted_alpha(w.g_t0i, SPECIALIZED ? LAYER_COUNT : tm_layer_count())
        : 0.0;
    return w.lobe_count;
}

#endif
