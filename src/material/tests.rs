//! One test per error class, each checking that the message names the file, the layer and the
//! field; preset resolution; every preset; the TOML round trip.

use std::path::Path;

use super::{presets, Stack};
use crate::variant::Model;

const FILE: &str = "bad/material.toml";

const GOLD: &str = "ior = [0.143, 0.374, 1.442]\nkappa = [3.983, 2.385, 1.603]\nroughness = 0.3\n";
const COAT: &str = "ior = [1.5, 1.5, 1.5]\nroughness = 0.1\n";

fn error(text: &str) -> String {
    Stack::from_toml(text, Path::new(FILE))
        .unwrap_err()
        .to_string()
}

/// A coat (layer 1, with `extra` lines) over gold (layer 2).
fn coat_over_gold(model: &str, extra: &str) -> String {
    format!("model = \"{model}\"\n[[layer]]\n{COAT}{extra}\n[[layer]]\n{GOLD}")
}

fn assert_names(message: &str, parts: &[&str]) {
    assert!(message.contains(FILE), "no file in: {message}");
    for p in parts {
        assert!(message.contains(p), "`{p}` missing from: {message}");
    }
}

#[test]
fn unknown_layer_key() {
    let m = error(&format!(
        "[[layer]]\n{COAT}\n[[layer]]\n{GOLD}roughnes = 0.2\n"
    ));
    assert_names(&m, &["layer 2", "`roughnes`", "unknown key", "roughness"]);
}

#[test]
fn unknown_top_level_key() {
    let m = error(&format!("colour = 1\n[[layer]]\n{GOLD}"));
    assert_names(
        &m,
        &[
            "`colour`",
            "unknown key",
            "name, model, map_resolution, layer",
        ],
    );
}

#[test]
fn wrong_array_length() {
    let m = error(&coat_over_gold("tm2", "").replace("[0.143, 0.374, 1.442]", "[0.143, 0.374]"));
    assert_names(&m, &["layer 2", "`ior`", "3 numbers", "found 2"]);
    let m = error(&coat_over_gold("tm6", "depth = 1.0\nsigma_a = 0.5"));
    assert_names(&m, &["layer 1", "`sigma_a`", "array of 3 numbers", "float"]);
}

#[test]
fn wrong_type() {
    let m = error(&coat_over_gold("tm2", "").replace("roughness = 0.1", "roughness = \"0.1\""));
    assert_names(
        &m,
        &["layer 1", "`roughness`", "expected a number", "string"],
    );
}

#[test]
fn non_finite_value() {
    let m = error(&coat_over_gold("tm2", "").replace("[1.5, 1.5, 1.5]", "[1.5, nan, 1.5]"));
    assert_names(
        &m,
        &["layer 1", "`ior`", "G: NaN is not finite", "[0.001, 400]"],
    );
    let m = error(&coat_over_gold("tm6", "depth = inf"));
    assert_names(&m, &["layer 1", "`depth`", "not finite", "[0, 100]"]);
}

#[test]
fn out_of_range_value() {
    let cases = [
        (
            "roughness = 0.1",
            "roughness = 1.5",
            "`roughness`",
            "[0, 1]",
        ),
        ("[1.5, 1.5, 1.5]", "[1.5, 0, 1.5]", "`ior`", "[0.001, 400]"),
        (
            "roughness = 0.1",
            "roughness = 0.1\ng = 1.0\ndepth = 1",
            "`g`",
            "(-1, 1)",
        ),
    ];
    for (from, to, field, range) in cases {
        let m = error(&coat_over_gold("tm6", "").replace(from, to));
        assert_names(&m, &["layer 1", field, "out of range", range]);
    }
    let m = error(&coat_over_gold("tm2", "").replace("kappa = [3.983", "kappa = [-3.983"));
    assert_names(&m, &["layer 2", "`kappa`", "R: -3.983", "[0, 200]"]);
}

#[test]
fn artist_form_out_of_range() {
    let m =
        error("[[layer]]\nf0 = [0.9, 0.995, 0.9]\nedge_tint = [0.9, 0.9, 0.9]\nroughness = 0.2\n");
    assert_names(&m, &["layer 1", "`f0`", "G: 0.995", "[0, 0.99]"]);
    let m =
        error("[[layer]]\nf0 = [0.9, 0.9, 0.9]\nedge_tint = [0.9, 1.1, 0.9]\nroughness = 0.2\n");
    assert_names(&m, &["layer 1", "`edge_tint`", "G: 1.1", "[0, 1]"]);
}

/// The corners of the artist domain convert into the physical ranges, so what `to_toml`
/// writes for them loads back.
#[test]
fn artist_domain_fits_the_physical_ranges() {
    for (r, g) in [
        (0.99, 0.0),
        (0.99, 0.5),
        (0.99, 1.0),
        (0.0, 0.0),
        (0.0, 1.0),
    ] {
        let (f0, tint) = (
            format!("[{r:?}, {r:?}, {r:?}]"),
            format!("[{g:?}, {g:?}, {g:?}]"),
        );
        let text = format!("[[layer]]\nf0 = {f0}\nedge_tint = {tint}\nroughness = 0.2\n");
        let stack = Stack::from_toml(&text, Path::new(FILE)).unwrap_or_else(|e| panic!("{e}"));
        let back = Stack::from_toml(&stack.to_toml(), Path::new(FILE)).unwrap();
        assert_eq!(back, stack);
    }
}

#[test]
fn both_interface_forms() {
    let m = error(&format!(
        "[[layer]]\n{GOLD}f0 = [0.5, 0.5, 0.5]\nedge_tint = [0.5, 0.5, 0.5]\n"
    ));
    assert_names(&m, &["layer 1", "`f0`", "not both"]);
}

#[test]
fn neither_interface_form() {
    let m = error(&format!("[[layer]]\nroughness = 0.1\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["layer 1", "`ior`", "missing"]);
}

#[test]
fn half_an_interface_form() {
    let m = error("[[layer]]\nkappa = [1.0, 1.0, 1.0]\nroughness = 0.1\n");
    assert_names(&m, &["layer 1", "`ior`", "missing"]);
    let m = error("[[layer]]\nf0 = [0.9, 0.9, 0.9]\nroughness = 0.1\n");
    assert_names(&m, &["layer 1", "`edge_tint`", "missing"]);
}

#[test]
fn missing_roughness() {
    let m = error(&coat_over_gold("tm2", "").replace("roughness = 0.1\n", ""));
    assert_names(&m, &["layer 1", "`roughness`", "missing", "[0, 1]"]);
}

#[test]
fn conductor_above_another_layer() {
    let m = error(&format!(
        "[[layer]]\n{COAT}[[layer]]\n{GOLD}[[layer]]\n{COAT}"
    ));
    assert_names(&m, &["layer 2", "`kappa`", "must be the last layer"]);
    let artist = "f0 = [0.9, 0.9, 0.9]\nedge_tint = [0.9, 0.9, 0.9]\nroughness = 0.2\n";
    let m = error(&format!("[[layer]]\n{artist}[[layer]]\n{COAT}"));
    assert_names(&m, &["layer 1", "`f0`", "must be the last layer"]);
}

#[test]
fn conductor_with_a_medium() {
    let m = error(&format!(
        "model = \"tm6\"\n[[layer]]\n{COAT}[[layer]]\n{GOLD}depth = 1.0\n"
    ));
    assert_names(&m, &["layer 2", "`depth`", "no medium"]);
}

#[test]
fn medium_without_depth() {
    let m = error(&coat_over_gold("tm6", "sigma_s = [1.0, 1.0, 1.0]"));
    assert_names(&m, &["layer 1", "`depth`", "missing", "sigma_s"]);
}

#[test]
fn medium_fields_need_tm6() {
    let m = error(&coat_over_gold("tm2", "depth = 1.0"));
    assert_names(&m, &["layer 1", "`depth`", "tm6"]);
}

#[test]
fn empty_stack() {
    assert_names(&error("name = \"x\"\n"), &["`layer`", "at least one"]);
    assert_names(
        &error(&format!("[layer]\n{GOLD}")),
        &["`layer`", "[[layer]]"],
    );
}

#[test]
fn unknown_model() {
    let m = error(&format!("model = \"tm4\"\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["`model`", "tm4", "tm2", "tm6"]);
}

#[test]
fn syntax_error_names_the_line() {
    let m = error(&format!("[[layer]]\n{COAT}roughness = = 2\n"));
    assert_names(&m, &["line 4", "not valid TOML"]);
}

#[test]
fn too_many_layers_for_the_variant() {
    let text = format!(
        "{}[[layer]]\n{GOLD}",
        format!("[[layer]]\n{COAT}").repeat(4)
    );
    let stack = Stack::from_toml(&text, Path::new(FILE)).unwrap();
    let m = stack.check_fits(4).unwrap_err().to_string();
    assert_names(&m, &["layer 5", "`max_layers`", "5 layers", "max_layers=4"]);
    stack.check_fits(5).unwrap();
}

#[test]
fn too_many_layers_for_the_buffer() {
    let m = error(&format!("[[layer]]\n{COAT}").repeat(17));
    assert_names(&m, &["layer 17", "`layer`", "at most 16"]);
}

#[test]
fn preset_names_and_paths_resolve() {
    let gold = Stack::resolve("gold").unwrap();
    assert!(gold.source.ends_with("assets/materials/gold.toml"));
    let by_path = Stack::resolve(gold.source.to_str().unwrap()).unwrap();
    assert_eq!(by_path, gold);
    let m = Stack::resolve("unobtainium").unwrap_err().to_string();
    assert!(
        m.contains("unobtainium") && m.contains("assets/materials"),
        "{m}"
    );
    let m = Stack::resolve("unobtainium.toml").unwrap_err().to_string();
    assert!(m.starts_with("unobtainium.toml: "), "{m}");
}

#[test]
fn artist_form_converts_to_physical() {
    let text = "[[layer]]\nf0 = [0.04, 0.5, 0.9]\nedge_tint = [0.0, 0.5, 0.9]\nroughness = 0.2\n";
    let l = Stack::from_toml(text, Path::new(FILE)).unwrap().layers[0];
    let want = [(1.5, 0.0), (3.08088, 2.82727), (3.84474, 11.41569)];
    for (c, (n, k)) in want.into_iter().enumerate() {
        assert!(
            (l.ior[c] - n).abs() < 1e-4 && (l.kappa[c] - k).abs() < 1e-4,
            "{l:?}"
        );
    }
}

#[test]
fn round_trip_is_exact() {
    let text = "name = \"a \\\"quoted\\\" name\"\nmodel = \"tm6\"\n[[layer]]\n\
                ior = [1.1, 1.3000000000000003, 1.7]\nroughness = 0.30000000000000004\n\
                depth = 0.1\nsigma_s = [1e-7, 2.5, 3]\nsigma_a = [0.1, 0.2, 0.3]\ng = -0.3\n\
                [[layer]]\nf0 = [0.9, 0.6, 0.3]\nedge_tint = [0.7, 0.5, 0.3]\nroughness = 0.2\n";
    let stack = Stack::from_toml(text, Path::new(FILE)).unwrap();
    let back = Stack::from_toml(&stack.to_toml(), Path::new(FILE)).unwrap();
    assert_eq!(back, stack);
    assert_eq!(back.to_toml(), stack.to_toml());
}

#[test]
fn save_writes_a_file_that_loads_back() {
    let dir = std::env::temp_dir().join(format!("lamina-material-{}", std::process::id()));
    let path = dir.join("saved.toml");
    let stack = Stack::resolve("dusty-varnish").unwrap();
    stack.save(&path).unwrap();
    let back = Stack::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(back.layers, stack.layers);
    assert_eq!((back.name, back.model), (stack.name, stack.model));
}

#[test]
fn every_preset_loads_and_round_trips() {
    let files = presets();
    assert!(files.len() >= 8, "{files:?}");
    let mut models = Vec::new();
    for path in files {
        let stack = Stack::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let back = Stack::from_toml(&stack.to_toml(), &path).unwrap();
        assert_eq!(back, stack, "{}", path.display());
        models.push(stack.model);
    }
    assert!(models.contains(&Model::Tm6) && models.contains(&Model::Tm2));
}

#[test]
fn aluminium_is_the_ggx_baseline_material() {
    let stack = Stack::resolve("aluminium").unwrap();
    assert_eq!(stack.model, Model::Tm2);
    assert_eq!(stack.layers.len(), 1);
    assert!(stack.layers[0].is_conductor());
}

/// The stack `text` with maps, read from the repository's materials directory (where the
/// textures' relative paths resolve).
fn varying(text: &str) -> Stack {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/materials/test.toml");
    Stack::from_toml(text, &path).unwrap()
}

#[test]
fn coverage_zero_and_one_are_the_stacks_without_and_with_the_layer_on_the_cpu() {
    use crate::model::{fgd::ExactFgd, tm2, NoTir};
    let text = |coverage: &str| {
        format!(
            "map_resolution = 8\n[[layer]]\n{COAT}\n[[layer]]\nior = [1.8, 1.8, 1.8]\nroughness = 0.3\n\
             coverage = {coverage}\n[[layer]]\n{GOLD}"
        )
    };
    let zero = varying(&text("0"));
    let one = varying(&text("1"));
    let maps = |s: &Stack| s.surface.as_ref().unwrap().maps.clone();
    let fgd = ExactFgd::new(crate::variant::G2::HeightCorrelated);
    let without = vec![zero.layers[0], zero.layers[2]];
    for (u, v) in [(0.1, 0.2), (0.7, 0.9), (0.33, 0.5)] {
        let at_zero = maps(&zero).layers_at(&zero.layers, (u, v), (0, 0));
        let at_one = maps(&one).layers_at(&one.layers, (u, v), (3, 5));
        assert_eq!(at_zero, without);
        assert_eq!(at_one, one.layers);
        for mu in [0.05, 0.5, 1.0] {
            let a = tm2::evaluate(&at_zero, mu, &fgd, &NoTir);
            let b = tm2::evaluate(&without, mu, &fgd, &NoTir);
            assert_eq!(a.reflectance, b.reflectance);
        }
    }
    assert_eq!(maps(&zero).coverage_fraction(1), 0.0);
    assert_eq!(maps(&one).coverage_fraction(1), 1.0);
    // A fractional coverage holds the layer on about that share of the texels.
    let most = varying(&text("0.7").replace("map_resolution = 8", "map_resolution = 64"));
    let share = maps(&most).coverage_fraction(1);
    assert!((share - 0.7).abs() < 0.03, "coverage 0.7 kept {share}");
}

#[test]
fn maps_read_their_range_and_round_trip() {
    let text = "name = \"mapped\"\nmodel = \"tm6\"\nmap_resolution = 16\n[[layer]]\nior = [1.5, 1.5, 1.5]\n\
                roughness = { pattern = \"noise\", scale = 2, range = [0.1, 0.3] }\n\
                depth = { pattern = \"cells\", scale = 4, seed = 3, range = [0.2, 0.4] }\n\
                sigma_s = [1.0, 1.0, 1.0]\n\
                coverage = { pattern = \"checker\", scale = 4, coords = \"screen\" }\n\
                [[layer]]\nf0 = { texture = \"../textures/bronze-mottle.png\", space = \"srgb\", range = [0, 0.99] }\n\
                edge_tint = [0.9, 0.8, 0.6]\n\
                roughness = { texture = \"../textures/brushed-streaks.png\", space = \"linear\", range = [0.2, 0.5] }\n";
    let stack = varying(text);
    let surface = stack.surface.as_ref().unwrap();
    // Coverage, roughness and depth on layer 1; η, κ (from f0) and roughness on layer 2.
    assert_eq!(surface.maps.slices.len(), 6);
    let at = surface.maps.layers_at(&stack.layers, (0.3, 0.6), (1, 0));
    assert_eq!(
        at.len(),
        1,
        "pixel (1, 0) lies in an uncovered checker cell"
    );
    let at = surface.maps.layers_at(&stack.layers, (0.3, 0.6), (5, 0));
    assert_eq!(at.len(), 2);
    assert!(
        (0.1..=0.3).contains(&at[0].roughness),
        "{}",
        at[0].roughness
    );
    assert!((0.2..=0.4).contains(&at[0].depth), "{}", at[0].depth);
    assert!(
        (0.2..=0.5).contains(&at[1].roughness),
        "{}",
        at[1].roughness
    );
    assert!(at[1].is_conductor());
    let again = Stack::from_toml(&stack.to_toml(), Path::new("elsewhere/copy.toml")).unwrap();
    assert_eq!(again.layers, stack.layers);
    assert_eq!(again.surface, stack.surface);
}

#[test]
fn a_kappa_map_that_crosses_zero_and_a_resolution_without_maps_are_refused() {
    let m = error(&format!(
        "[[layer]]\n{COAT}\n[[layer]]\nior = [0.2, 0.9, 1.1]\nroughness = 0.2\n\
         kappa = {{ pattern = \"noise\", range = [0.0, 3.0] }}\n"
    ));
    assert_names(
        &m,
        &[
            "layer 2",
            "`kappa`",
            "reaches κ = 0",
            "conductor everywhere or nowhere",
        ],
    );
    let m = error(&format!(
        "[[layer]]\n{COAT}coverage = {{ pattern = \"checker\", scale = 3 }}\n[[layer]]\n{GOLD}"
    ));
    assert_names(&m, &["`coverage.scale`", "even scale"]);
    let m = error(&format!("map_resolution = 64\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["`map_resolution`", "no layer has one"]);
    let m = error(&format!(
        "[[layer]]\n{COAT}coverage = {{ pattern = \"stripes\" }}\n[[layer]]\n{GOLD}"
    ));
    assert_names(
        &m,
        &["layer 1", "`coverage.pattern`", "checker", "noise", "cells"],
    );
    let m = error(&format!(
        "[[layer]]\n{COAT}coverage = {{ pattern = \"checker\", colour = 1 }}\n[[layer]]\n{GOLD}"
    ));
    assert_names(&m, &["`coverage.colour`", "unknown key"]);
    let m = error(&format!(
        "[[layer]]\n{COAT}coverage = {{ pattern = \"checker\", coords = \"world\" }}\n[[layer]]\n{GOLD}"
    ));
    assert_names(&m, &["`coverage.coords`", "\"uv\", \"screen\""]);
}
