//! CI's performance gates: orderings of deterministic instruction counts (callgrind, lavapipe,
//! `LP_NUM_THREADS=0`), measured in one pool of workers for both gates — never wall-clock
//! time. The gated count is the instructions executed in llvmpipe's JIT-compiled code: the
//! shader's own cost, free of the driver's per-draw work (see profiling/README.md for why the
//! total is not gated).

use crate::common;

use std::path::Path;
use std::sync::OnceLock;

use lamina::material::Stack;
use lamina::profile::counter::{count_instructions, CountRequest};
use lamina::profile::plan::Case;
use lamina::render::scene::Scene;
use lamina::variant::VariantKey;
use lamina::Size;

/// Every variant key the gates order, on varnished gold.
const KEYS: [&str; 12] = [
    "model=ggx,max_layers=2",
    "model=tm2,max_layers=2",
    "model=tm2,max_layers=16",
    "model=tm6,max_layers=2",
    "model=tm2,max_layers=4",
    "model=tm2,max_layers=4,fp16=on",
    "model=tm2,max_layers=4,tir=lut32",
    "model=tm2,max_layers=4,mode=specialized",
    "model=tm2,max_layers=16,mode=specialized",
    "model=tm2,mode=specialized-values",
    "model=tm2,mode=baked",
    // The first case again, after the others: the count must repeat.
    "model=tm2,max_layers=2",
];

/// The JIT instructions of varnished gold's shaded draw at 32×32 under each of [`KEYS`], in
/// order, counted once for both gates in one pool of workers (each shader compiles under
/// valgrind once) and printed.
fn jit_counts() -> &'static [u64] {
    static COUNTS: OnceLock<Vec<u64>> = OnceLock::new();
    COUNTS.get_or_init(|| {
        let stack = Stack::resolve("varnished-gold").unwrap();
        assert_eq!(stack.layers.len(), 2);
        let cases: Vec<Case> = KEYS
            .iter()
            .map(|k| Case {
                variant: k.parse::<VariantKey>().unwrap(),
                stack: stack.clone(),
            })
            .collect();
        let env = common::repo_path("assets/env/studio.exr");
        let counts = count_instructions(
            &CountRequest {
                exe: Path::new(env!("CARGO_BIN_EXE_lamina")),
                global_args: Vec::new(),
                env_map: &env,
                cases: &cases,
                scene: Scene::Sphere,
                lighting: None,
                sizes: &[Size {
                    width: 32,
                    height: 32,
                }],
            },
            |_, _| {},
        )
        .expect("callgrind worker");
        // One size: these gates order whole draws.
        let counts: Vec<_> = counts.into_iter().map(|by_size| by_size[0]).collect();
        for (k, n) in KEYS.iter().zip(&counts) {
            println!("{:>14} JIT {:>14} all  {k}", n.jit, n.total);
        }
        counts.iter().map(|c| c.jit).collect()
    })
}

#[test]
fn instruction_counts_order_the_variants() {
    let [ggx, tm2, tm2_16, tm6, tm2_4, tm2_4_fp16, tm2_4_lut32, .., tm2_again] = jit_counts()[..]
    else {
        panic!("one count per case");
    };
    let repeat = (tm2 as f64 - tm2_again as f64).abs() / tm2 as f64;
    println!("repeatability: {repeat:.2e}");
    assert!(
        common::same_count(tm2, tm2_again),
        "the same draw counted {tm2} then {tm2_again}"
    );
    assert!(tm2 > ggx, "tm2 {tm2} <= ggx {ggx}");
    assert!(tm6 > tm2, "tm6 {tm6} <= tm2 {tm2}");
    assert!(
        tm2_16 > tm2,
        "max_layers=16 {tm2_16} <= max_layers=2 {tm2} at 2 active layers"
    );
    // At max_layers=4: lavapipe rebuilds tm2 shaders of max_layers <= 2 at every draw,
    // specialised to the material (profiling/README.md), which blurs the fp16 comparison there.
    assert!(
        tm2_4_lut32 > tm2_4,
        "tir=lut32 {tm2_4_lut32} <= tir=none {tm2_4}"
    );
    assert!(
        tm2_4_fp16 > tm2_4,
        "lavapipe emulates fp16: {tm2_4_fp16} <= fp32 {tm2_4}"
    );
}

/// Issue 11's gate: on a two-layer preset, per-material pipelines cost less than the generic
/// one (baked < specialized < generic at max_layers 16), and a specialized pipeline does not
/// depend on `max_layers` at all (its arrays have the material's own size).
#[test]
fn specialization_orders_the_counts() {
    let [_, _, generic_16, _, _, _, _, specialized_4, specialized_16, values, baked, _] =
        jit_counts()[..]
    else {
        panic!("one count per case");
    };
    assert!(
        common::same_count(specialized_4, specialized_16),
        "a specialized pipeline's count depends on max_layers: {specialized_4} against \
         {specialized_16}"
    );
    assert!(
        specialized_4 < generic_16,
        "specialized {specialized_4} >= generic max_layers=16 {generic_16}"
    );
    assert!(
        values < specialized_4,
        "specialized-values {values} >= specialized {specialized_4}"
    );
    assert!(
        baked < specialized_4,
        "baked {baked} >= specialized {specialized_4}"
    );
}
