//! How the transfer-matrix model composes its components: the adding equations.
//!
//! The reference composes each component's transfer matrix M = (1/t)·[1, −r′; r, t t′ − r r′]
//! top to bottom and reads the stack's reflectance and transmittance from the product
//! (R = M₂₁/M₁₁, T = 1/M₁₁; ALGORITHMS.md §4.2, §5.6). Those matrices hold the inverse of every
//! transmission, so they fail exactly where a valid stack stops transmitting:
//! - a component that transmits nothing — a TIR fraction of 1, or an FGD of 1 beyond the
//!   critical angle — makes M infinite (1/0), and R = ∞/∞ = NaN;
//! - the asymmetry matrix divides by t·g_t, and g_t is 0 whenever a lobe refracted out of a
//!   denser layer collapses (hg::refract), so its lobe g was NaN too;
//! - media grow the primary and the scattered flux classes at different exponential rates
//!   (1/T against 1/t_ff): a few thick media span more than a float's range, the scattered
//!   class underflows, and the 3×3 solve of §5.6 divides 0 by 0.
//!
//! The same factors composed by the adding equations (the star product of scattering
//! descriptions, Redheffer 1961) give the same R and T wherever the matrix product exists, and
//! every quantity stays an energy in [0, 1]: the stack above (reflectance R and transmittance T
//! from above, R′ and T′ from below) over a component (r, t, r′, t′) is
//!
//!   R ← R + T′·r·T / (1 − R′r),   T ← t·T / (1 − R′r),
//!   R′ ← r′ + t·R′·t′ / (1 − R′r),  T′ ← T′·t′ / (1 − R′r),
//!
//! and with three flux classes (6-flux) the same with 3×3 operators and (I − R′r)⁻¹. The
//! asymmetry ("g-weighted") composition uses the same equations on g-weighted factors
//! (ALGORITHMS.md §4.3): it is linear in them as the matrix product was.
//!
//! 1 − R′r is the share of the light between the two that is not sent back down. Formed as a
//! difference it loses every digit when both sides reflect nearly everything (a TIR fraction of
//! 1 above, r = 1 − 10⁻¹² below: 1 − r keeps four digits of t in f64, and the stack transmitted
//! 1e-6 more than it received). So the stack carries q = 1 − R′ (what it does not send back
//! down: its upward transmission and losses), each component gives 1 − r as t + a (its
//! transmission and absorption, a = 0 for an interface), and the denominator is
//! q + R′·(1 − r): a sum of non-negative terms. q itself is updated without a difference:
//! q ← t′·(q + R′a)/(1 − R′r) + a′ (the 6-flux interfaces likewise; a medium, whose operators
//! mix the classes, forms I − R′ directly). What is left is 0 only when nothing leaves the gap
//! (q = 0 and t + a = 0), where the terms it divides are 0 too ([`GAP_FLOOR`]).

/// RGB, one value per channel.
pub(crate) type Rgb = [f64; 3];

/// Smallest denominator (or determinant) the composition divides by: the smallest normal f64.
/// The denominators are sums of non-negative terms, 0 only where nothing can leave the gap,
/// and then the terms they divide are 0 too; the floor makes that 0/0 a 0.
pub(crate) const GAP_FLOOR: f64 = f64::MIN_POSITIVE;

pub(crate) fn map3(f: impl Fn(usize) -> f64) -> Rgb {
    [f(0), f(1), f(2)]
}

pub(crate) fn avg(v: Rgb) -> f64 {
    (v[0] + v[1] + v[2]) / 3.0
}

/// One component as two-flux scattering, per channel: from above, reflectance `r` and
/// transmittance `t`; from below, `rp` and `tp`; and 1 − r, 1 − r′ given as such
/// (`one_minus_r`, `one_minus_rp`) so that they keep their digits where r is near 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Component {
    pub r: Rgb,
    pub t: Rgb,
    pub rp: Rgb,
    pub tp: Rgb,
    pub one_minus_r: Rgb,
    pub one_minus_rp: Rgb,
}

impl Component {
    /// A lossless component, the same in every channel (a dielectric interface: r + t = 1,
    /// r′ + t′ = 1), so 1 − r is t.
    pub fn lossless(r: f64, t: f64, rp: f64, tp: f64) -> Self {
        Self {
            r: [r; 3],
            t: [t; 3],
            rp: [rp; 3],
            tp: [tp; 3],
            one_minus_r: [t; 3],
            one_minus_rp: [tp; 3],
        }
    }

    /// A component that is the same seen from above and below, per channel (a medium crossed
    /// by diffuse light: `model::diffuse`).
    pub fn symmetric(r: Rgb, t: Rgb) -> Self {
        let one_minus_r = map3(|c| 1.0 - r[c]);
        Self {
            r,
            t,
            rp: r,
            tp: t,
            one_minus_r,
            one_minus_rp: one_minus_r,
        }
    }

    /// Factors that are not energies (the g-weighted ones of the asymmetry composition).
    pub fn weighted(r: f64, t: f64, rp: f64, tp: f64) -> Self {
        Self {
            r: [r; 3],
            t: [t; 3],
            rp: [rp; 3],
            tp: [tp; 3],
            one_minus_r: [1.0 - r; 3],
            one_minus_rp: [1.0 - rp; 3],
        }
    }
}

/// A composed stack seen as two-flux scattering: from above, reflectance `r` and transmittance
/// `t`; from below, `rp` and `tp`, and q = 1 − r′ (per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Slab {
    pub r: Rgb,
    pub t: Rgb,
    pub rp: Rgb,
    pub tp: Rgb,
    pub q: Rgb,
}

impl Slab {
    /// Nothing yet: reflects nothing, transmits everything.
    pub fn empty() -> Self {
        Self {
            r: [0.0; 3],
            t: [1.0; 3],
            rp: [0.0; 3],
            tp: [1.0; 3],
            q: [1.0; 3],
        }
    }

    /// This stack with `below` under it (the adding equations, module docs).
    pub fn over(&self, below: &Component) -> Slab {
        let gap = map3(|c| 1.0 / (self.q[c] + self.rp[c] * below.one_minus_r[c]).max(GAP_FLOOR));
        Slab {
            r: map3(|c| self.r[c] + self.tp[c] * below.r[c] * self.t[c] * gap[c]),
            t: map3(|c| below.t[c] * self.t[c] * gap[c]),
            rp: map3(|c| below.rp[c] + below.t[c] * self.rp[c] * below.tp[c] * gap[c]),
            tp: map3(|c| self.tp[c] * below.tp[c] * gap[c]),
            q: map3(|c| {
                let a = below.one_minus_r[c] - below.t[c];
                let ap = below.one_minus_rp[c] - below.tp[c];
                below.tp[c] * (self.q[c] + self.rp[c] * a) * gap[c] + ap
            }),
        }
    }

    /// Reflectance of this stack over an opaque base of reflectance `r_c`.
    pub fn over_base(&self, r_c: Rgb) -> Rgb {
        map3(|c| {
            let gap = 1.0 / (self.q[c] + self.rp[c] * (1.0 - r_c[c])).max(GAP_FLOOR);
            self.r[c] + self.tp[c] * r_c[c] * self.t[c] * gap
        })
    }

    /// This g-weighted stack with each quantity bounded by the same quantity of the energy
    /// stack `energy` ([`bound`]).
    pub fn bounded_by(&self, energy: &Slab) -> Slab {
        let rp = map3(|c| bound(self.rp[c], energy.rp[c]));
        Slab {
            r: map3(|c| bound(self.r[c], energy.r[c])),
            t: map3(|c| bound(self.t[c], energy.t[c])),
            tp: map3(|c| bound(self.tp[c], energy.tp[c])),
            q: map3(|c| {
                if rp[c] == self.rp[c] {
                    self.q[c]
                } else {
                    1.0 - rp[c]
                }
            }),
            rp,
        }
    }
}

/// A g-weighted flux bounded by its energy: it is the energy times a mean cosine. The
/// first-order transmitted-asymmetry factors (§4.4) are ratios of cumulative g's, above 1
/// where refraction narrows a lobe, and the reference's composition multiplies them along
/// multiply-reflected paths without bound: where a path's g collapses to almost 0 the ratio
/// back up is huge (the 6-flux secondary path under a thick medium at grazing incidence gave
/// g-weighted fluxes of 1e152 and then a NaN on the GPU). Bounding the cumulative quantities
/// leaves every stack whose g-weighted fluxes are mean cosines as it was.
pub(crate) fn bound(g_weighted: f64, energy: f64) -> f64 {
    g_weighted.clamp(-energy.abs(), energy.abs())
}

/// A 3×3 operator on the three flux classes (primary, secondary forward, secondary backward),
/// per channel: `m[out][in]`.
pub(crate) type Mat3 = [[Rgb; 3]; 3];

fn identity3() -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| [if i == j { 1.0 } else { 0.0 }; 3]))
}

fn mul3(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| map3(|c| (0..3).map(|k| a[i][k][c] * b[k][j][c]).sum()))
    })
}

fn apply3(a: &Mat3, x: &[Rgb; 3]) -> [Rgb; 3] {
    std::array::from_fn(|i| map3(|c| (0..3).map(|k| a[i][k][c] * x[k][c]).sum()))
}

/// a⁻¹ by its adjugate. a = I − R′r is singular only where light is trapped between the stack
/// and the component below; a determinant below 4 epsilons of its rows' scale (‖a‖∞³) is that
/// trap at the precision's resolution, and is floored there (and at [`GAP_FLOOR`]).
fn inverse(a: &Mat3) -> Mat3 {
    let mut inv = identity3();
    for c in 0..3 {
        let m = |i: usize, j: usize| a[i][j][c];
        let cof = |i: usize, j: usize| {
            let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
            let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
            m(r0, c0) * m(r1, c1) - m(r0, c1) * m(r1, c0)
        };
        let det = (0..3).map(|j| m(0, j) * cof(0, j)).sum::<f64>();
        let scale = (0..3)
            .map(|i| (0..3).map(|j| m(i, j).abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let det = det.max(4.0 * f64::EPSILON * scale.powi(3)).max(GAP_FLOOR);
        for (i, row) in inv.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                v[c] = cof(j, i) / det;
            }
        }
    }
    inv
}

fn diag3(d: [Rgb; 3]) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { d[i] } else { [0.0; 3] }))
}

/// A component in the 6-flux model as scattering operators between the three flux classes:
/// from above `r` (to the upward fluxes above) and `t` (to the downward fluxes below); from
/// below `rp` and `tp`. An interface keeps each class on its own and carries its per-class
/// 1 − r and 1 − r′ (`Some`); a medium mixes the classes and has `None` (module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Component6 {
    pub r: Mat3,
    pub t: Mat3,
    pub rp: Mat3,
    pub tp: Mat3,
    /// (1 − r, 1 − r′) per class of a block-diagonal component.
    pub one_minus: Option<([Rgb; 3], [Rgb; 3])>,
}

impl Component6 {
    /// An interface: each class on its own (block-diagonal transfer matrix, §5.2), the primary
    /// class with `primary`'s factors, both secondary classes with `secondary`'s.
    pub fn interface(primary: Component, secondary: Component) -> Self {
        let per_class = |f: fn(&Component) -> Rgb| [f(&primary), f(&secondary), f(&secondary)];
        Self {
            r: diag3(per_class(|c| c.r)),
            t: diag3(per_class(|c| c.t)),
            rp: diag3(per_class(|c| c.rp)),
            tp: diag3(per_class(|c| c.tp)),
            one_minus: Some((per_class(|c| c.one_minus_r), per_class(|c| c.one_minus_rp))),
        }
    }

    /// A homogeneous medium of primary transmission `t_primary`, secondary back-reflection
    /// `r_fb` and forward transmission `t_ff` (the matrix of §5.4 solved for its outgoing
    /// fluxes): the primary flux crossing it keeps T, loses t_ff − T to the forward class and
    /// sends r_fb back in the backward class; a forward-class flux keeps t_ff and sends r_fb
    /// back; a backward-class flux keeps t_ff and sends r_fb back in the forward class. The
    /// same from below.
    pub fn medium(t_primary: Rgb, r_fb: Rgb, t_ff: Rgb) -> Self {
        let zero = [0.0; 3];
        let r = [[zero; 3], [zero, zero, r_fb], [r_fb, r_fb, zero]];
        let t = [
            [t_primary, zero, zero],
            [map3(|c| t_ff[c] - t_primary[c]), t_ff, zero],
            [zero, zero, t_ff],
        ];
        Self {
            r,
            t,
            rp: r,
            tp: t,
            one_minus: None,
        }
    }

    /// The g-weighted medium: as [`Component6::medium`] with g-weighted back-reflection `gr`
    /// and forward transmission `gt` (the primary flux keeps g = 1). A g-weighted flux is an
    /// energy times a mean cosine, so each entry is bounded by its energy's magnitude: the
    /// two-stream g's (g_rfb, g_tff) and the scattered part gt − T, formed as a difference,
    /// step outside it in thick or weakly scattering media, and the composition then diverges
    /// (the g-weighted fluxes reached 1e152).
    pub fn medium_weighted(t_primary: Rgb, r_fb: Rgb, t_ff: Rgb, gr: Rgb, gt: Rgb) -> Self {
        let mut m = Self::medium(
            t_primary,
            map3(|c| bound(gr[c], r_fb[c])),
            map3(|c| bound(gt[c], t_ff[c])),
        );
        m.t[1][0] = map3(|c| bound(m.t[1][1][c] - t_primary[c], t_ff[c] - t_primary[c]));
        m.tp = m.t;
        m
    }
}

/// A composed 6-flux stack: for unit primary light from above (a₁ = 1, a₃ = a₅ = 0), the upward
/// fluxes above it (`up`: r, r_f, r_b) and the downward fluxes at its bottom (`down`); for light
/// from below, `rp`, `tp` and q = I − rp.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slab6 {
    pub up: [Rgb; 3],
    pub down: [Rgb; 3],
    pub rp: Mat3,
    pub tp: Mat3,
    pub q: Mat3,
}

impl Slab6 {
    pub fn empty() -> Self {
        Self {
            up: [[0.0; 3]; 3],
            down: [[1.0; 3], [0.0; 3], [0.0; 3]],
            rp: [[[0.0; 3]; 3]; 3],
            tp: identity3(),
            q: identity3(),
        }
    }

    /// This stack with `below` under it (the adding equations with 3×3 operators):
    /// W = (I − R′r)⁻¹ = (q + R′(I − r))⁻¹, x = W·down, up += T′·r·x, down = t·x, and with
    /// P = W·R′ and V = I + r·P (= (I − rR′)⁻¹): R′ ← r′ + t·P·t′, T′ ← T′·V·t′, and
    /// q ← (q + A·R′)·V·t′ + A′ for an interface (A, A′ its absorption), I − R′ for a medium.
    pub fn over(&self, below: &Component6) -> Slab6 {
        let i_minus_r = match below.one_minus {
            Some((one_minus_r, _)) => diag3(one_minus_r),
            None => sub3(&identity3(), &below.r),
        };
        let w = inverse(&add3(&self.q, &mul3(&self.rp, &i_minus_r)));
        let x = apply3(&w, &self.down);
        let back = apply3(&self.tp, &apply3(&below.r, &x));
        let p = mul3(&w, &self.rp);
        let v = add3(&identity3(), &mul3(&below.r, &p));
        let rp = add3(&below.rp, &mul3(&mul3(&below.t, &p), &below.tp));
        let q = match below.one_minus {
            Some((one_minus_r, one_minus_rp)) => {
                let absorbed = |one_minus: [Rgb; 3], t: &Mat3| {
                    diag3(std::array::from_fn(|k| {
                        map3(|c| one_minus[k][c] - t[k][k][c])
                    }))
                };
                let a = absorbed(one_minus_r, &below.t);
                let ap = absorbed(one_minus_rp, &below.tp);
                let held = add3(&self.q, &mul3(&a, &self.rp));
                add3(&mul3(&mul3(&held, &v), &below.tp), &ap)
            }
            None => sub3(&identity3(), &rp),
        };
        Slab6 {
            up: std::array::from_fn(|k| map3(|c| self.up[k][c] + back[k][c])),
            down: apply3(&below.t, &x),
            rp,
            tp: mul3(&mul3(&self.tp, &v), &below.tp),
            q,
        }
    }

    /// This g-weighted stack with each flux and operator entry bounded by the energy stack's
    /// ([`bound`]). A channel whose R′ the bound moved takes q = I − R′; the others keep
    /// theirs: every channel is composed on its own, as the 2-flux [`Slab::bounded_by`] does,
    /// which lets the shader walk the channels one at a time (`channels=serial`).
    pub fn bounded_by(&self, energy: &Slab6) -> Slab6 {
        let vec = |g: &[Rgb; 3], e: &[Rgb; 3]| -> [Rgb; 3] {
            std::array::from_fn(|k| map3(|c| bound(g[k][c], e[k][c])))
        };
        let mat = |g: &Mat3, e: &Mat3| -> Mat3 { std::array::from_fn(|i| vec(&g[i], &e[i])) };
        let rp = mat(&self.rp, &energy.rp);
        let moved: [bool; 3] = std::array::from_fn(|c| {
            (0..9).any(|e| rp[e / 3][e % 3][c] != self.rp[e / 3][e % 3][c])
        });
        let reset = sub3(&identity3(), &rp);
        let q = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                map3(|c| {
                    if moved[c] {
                        reset[i][j][c]
                    } else {
                        self.q[i][j][c]
                    }
                })
            })
        });
        Slab6 {
            up: vec(&self.up, &energy.up),
            down: vec(&self.down, &energy.down),
            rp,
            tp: mat(&self.tp, &energy.tp),
            q,
        }
    }

    /// The upward fluxes above this stack over an opaque base reflecting every class with
    /// `r_c` (§5.6).
    pub fn over_base(&self, r_c: Rgb) -> [Rgb; 3] {
        let base = diag3([r_c; 3]);
        let one_minus = diag3([map3(|c| 1.0 - r_c[c]); 3]);
        let w = inverse(&add3(&self.q, &mul3(&self.rp, &one_minus)));
        let back = apply3(&self.tp, &apply3(&base, &apply3(&w, &self.down)));
        std::array::from_fn(|k| map3(|c| self.up[k][c] + back[k][c]))
    }
}

fn sub3(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| map3(|c| a[i][j][c] - b[i][j][c])))
}

fn add3(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| map3(|c| a[i][j][c] + b[i][j][c])))
}

#[cfg(test)]
mod tests {
    //! The adding equations against the transfer-matrix products they replace, where those
    //! exist (every transmission well above 0).
    use super::*;
    use crate::model::random::Rng;

    type M6 = [[f64; 6]; 6];

    fn mul6(a: &M6, b: &M6) -> M6 {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..6).map(|k| a[i][k] * b[k][j]).sum()))
    }

    /// The 2×2 transfer matrix of ALGORITHMS.md §4.2, one channel.
    fn tm2(r: f64, t: f64, rp: f64, tp: f64) -> [[f64; 2]; 2] {
        [[1.0 / t, -rp / t], [r / t, (t * tp - r * rp) / t]]
    }

    /// The 6×6 interface matrix of §5.2 and medium matrix of §5.4, one channel.
    fn tm6_interface(p: [f64; 4], s: [f64; 4]) -> M6 {
        let mut m = [[0.0; 6]; 6];
        for (o, f) in [(0, p), (2, s), (4, s)] {
            let b = tm2(f[0], f[1], f[2], f[3]);
            m[o][o] = b[0][0];
            m[o][o + 1] = b[0][1];
            m[o + 1][o] = b[1][0];
            m[o + 1][o + 1] = b[1][1];
        }
        m
    }

    fn tm6_medium(t: f64, r_fb: f64, t_ff: f64) -> M6 {
        let mut m = [[0.0; 6]; 6];
        let q = t_ff - r_fb * r_fb / t_ff;
        m[0][0] = 1.0 / t;
        m[1][1] = t;
        m[2][2] = 1.0 / t_ff;
        m[3][3] = q;
        m[4][4] = 1.0 / t_ff;
        m[5][5] = q;
        m[2][0] = 1.0 / t_ff - 1.0 / t;
        m[3][1] = q - t;
        for (i, j) in [(2, 5), (4, 1), (4, 3)] {
            m[i][j] = -r_fb / t_ff;
        }
        for (i, j) in [(3, 4), (5, 0), (5, 2)] {
            m[i][j] = r_fb / t_ff;
        }
        m
    }

    /// Upward fluxes above a 6×6 product over a base `r_c`, by the downward boundary
    /// conditions (§5.6).
    fn extract(m: &M6, r_c: f64) -> [f64; 3] {
        let col = |row: usize, k: usize| m[row][2 * k] + m[row][2 * k + 1] * r_c;
        let c: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|k| col(2 * r, k)));
        let det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
            - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
            + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
        let b = [
            (c[1][1] * c[2][2] - c[1][2] * c[2][1]) / det,
            -(c[1][0] * c[2][2] - c[1][2] * c[2][0]) / det,
            (c[1][0] * c[2][1] - c[1][1] * c[2][0]) / det,
        ];
        std::array::from_fn(|k| (0..3).map(|j| col(2 * k + 1, j) * b[j]).sum())
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn two_flux_adding_equals_the_matrix_product() {
        let mut rng = Rng(0x2468_ace0_1357_9bdf);
        for _ in 0..2000 {
            let mut slab = Slab::empty();
            let mut m = [[1.0, 0.0], [0.0, 1.0]];
            for _ in 0..1 + (rng.unit() * 5.0) as usize {
                let (r, rp) = (0.9 * rng.unit(), 0.9 * rng.unit());
                let (t, tp) = ((1.0 - r) * (0.1 + 0.9 * rng.unit()), 1.0 - rp);
                slab = slab.over(&Component::weighted(r, t, rp, tp));
                let b = tm2(r, t, rp, tp);
                m = std::array::from_fn(|i| {
                    std::array::from_fn(|j| m[i][0] * b[0][j] + m[i][1] * b[1][j])
                });
                assert!(close(slab.r[0], m[1][0] / m[0][0]), "{slab:?} {m:?}");
                assert!(close(slab.t[1], 1.0 / m[0][0]), "{slab:?} {m:?}");
            }
            let r_c = rng.unit();
            let want = (m[1][0] + m[1][1] * r_c) / (m[0][0] + m[0][1] * r_c);
            assert!(close(slab.over_base([r_c; 3])[2], want));
        }
    }

    #[test]
    fn six_flux_adding_equals_the_matrix_product() {
        let mut rng = Rng(0x1357_9bdf_2468_ace0);
        for _ in 0..1000 {
            let mut slab = Slab6::empty();
            let mut m: M6 =
                std::array::from_fn(|i| std::array::from_fn(|j| f64::from(u8::from(i == j))));
            for k in 0..2 + (rng.unit() * 6.0) as usize {
                let (component, matrix) = if k % 2 == 0 {
                    let mut f = || {
                        let (r, rp) = (0.9 * rng.unit(), 0.9 * rng.unit());
                        [r, (1.0 - r) * (0.2 + 0.8 * rng.unit()), rp, 1.0 - rp]
                    };
                    let (p, s) = (f(), f());
                    let slab = |f: [f64; 4]| Component::weighted(f[0], f[1], f[2], f[3]);
                    (Component6::interface(slab(p), slab(s)), tm6_interface(p, s))
                } else {
                    let t = 0.05 + 0.9 * rng.unit();
                    let t_ff = t + (1.0 - t) * rng.unit();
                    let r_fb = (1.0 - t_ff) * rng.unit();
                    (
                        Component6::medium([t; 3], [r_fb; 3], [t_ff; 3]),
                        tm6_medium(t, r_fb, t_ff),
                    )
                };
                slab = slab.over(&component);
                m = mul6(&m, &matrix);
                let want = extract(&m, 0.0);
                for c in 0..3 {
                    assert!(close(slab.up[c][1], want[c]), "{:?} vs {want:?}", slab.up);
                }
            }
            let r_c = rng.unit();
            let want = extract(&m, r_c);
            let got = slab.over_base([r_c; 3]);
            for c in 0..3 {
                assert!(close(got[c][0], want[c]), "{got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn a_component_that_transmits_nothing_hides_what_is_below() {
        let top = Component::lossless(0.04, 0.96, 0.04, 0.96);
        let opaque = Component::lossless(1.0, 0.0, 1.0, 0.0);
        let stack = Slab::empty().over(&top).over(&opaque);
        assert_eq!(stack.r, [1.0; 3], "{stack:?}");
        assert_eq!(stack.t, [0.0; 3]);
        let below = stack.over(&Component::lossless(0.5, 0.5, 0.5, 0.5));
        assert_eq!((below.r, below.t), (stack.r, stack.t));
        // Both sides reflecting everything: nothing leaves the gap, nothing becomes NaN.
        let mirror = Component::lossless(0.0, 1.0, 1.0, 0.0);
        let trapped = Slab::empty().over(&mirror).over(&opaque);
        assert!(
            trapped.r.iter().chain(&trapped.t).all(|v| v.is_finite()),
            "{trapped:?}"
        );
        let thick = Component6::medium([0.0; 3], [0.3; 3], [0.0; 3]);
        let six = Slab6::empty().over(&thick).over(&thick);
        assert!(six.up.iter().flatten().all(|v| v.is_finite()));
        assert!((six.up[2][0] - 0.3).abs() < 1e-15, "{:?}", six.up);
    }

    /// A trap (a top that sends all upward light back down) over a component that reflects
    /// all but 1e-12: the gap's denominator is t itself, and what enters is transmitted whole.
    #[test]
    fn a_trap_over_a_near_mirror_conserves_energy() {
        let trap = Component::lossless(0.3, 0.7, 1.0, 0.0);
        let t = 2.302494794849728e-12;
        let near_mirror = Component::lossless(1.0 - t, t, 0.5, 0.5);
        let stack = Slab::empty().over(&trap).over(&near_mirror);
        assert!((stack.r[0] + stack.t[0] - 1.0).abs() < 1e-15, "{stack:?}");
        let primary = Component6::interface(trap, trap);
        let below = Component6::interface(near_mirror, near_mirror);
        let six = Slab6::empty().over(&primary).over(&below);
        let total = six.up.iter().chain(&six.down).map(|v| v[0]).sum::<f64>();
        assert!((total - 1.0).abs() < 1e-15, "{six:?}");
    }
}
