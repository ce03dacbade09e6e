//! One test per error class, each checking the message names file, layer and field; presets;
//! the TOML round trip.

use std::path::Path;

use super::{presets, Stack};
use crate::shader::Model;

const FILE: &str = "bad/material.toml";

fn error(text: &str) -> String {
    Stack::from_toml(text, Path::new(FILE))
        .unwrap_err()
        .to_string()
}

fn assert_names(message: &str, parts: &[&str]) {
    assert!(message.contains(FILE), "no file in: {message}");
    for p in parts {
        assert!(message.contains(p), "`{p}` missing from: {message}");
    }
}

const GOLD: &str = "ior = [0.143, 0.374, 1.442]\nkappa = [3.983, 2.385, 1.603]\nroughness = 0.3\n";

#[test]
fn unknown_layer_key() {
    let m = error(&format!("[[layer]]\n{GOLD}roughnes = 0.2\n"));
    assert_names(&m, &["layer 1", "`roughnes`", "unknown key", "roughness"]);
}

#[test]
fn unknown_top_level_key() {
    let m = error(&format!("colour = 1\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["`colour`", "unknown key"]);
}

#[test]
fn wrong_array_length() {
    let m = error("[[layer]]\nior = [1.5, 1.5]\nroughness = 0.1\n");
    assert_names(&m, &["layer 1", "`ior`", "3 numbers", "found 2"]);
}

#[test]
fn non_finite_value() {
    let m = error(&format!(
        "[[layer]]\nior = [1.5, nan, 1.5]\nroughness = 0.1\n[[layer]]\n{GOLD}"
    ));
    assert_names(&m, &["layer 1", "`ior`", "not finite"]);
}

#[test]
fn out_of_range_value() {
    let m = error(&format!(
        "[[layer]]\nior = [1.5, 1.5, 1.5]\nroughness = 1.5\n[[layer]]\n{GOLD}"
    ));
    assert_names(&m, &["layer 1", "`roughness`", "1.5", "[0, 1]"]);
    let m = error(&format!("[[layer]]\n{GOLD}\n").replace("kappa = [3.983", "kappa = [-3.983"));
    assert_names(&m, &["layer 1", "`kappa`", "[0, 20]"]);
}

#[test]
fn conductor_above_another_layer() {
    let m = error(&format!(
        "[[layer]]\n{GOLD}[[layer]]\nior = [1.5, 1.5, 1.5]\nroughness = 0.1\n"
    ));
    assert_names(&m, &["layer 1", "`kappa`", "must be the last layer"]);
}

#[test]
fn medium_fields_need_tm6() {
    let m = error(&format!("model = \"tm2\"\n[[layer]]\nior = [1.5, 1.5, 1.5]\nroughness = 0.1\ndepth = 1.0\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["layer 1", "`depth`", "tm6"]);
}

#[test]
fn both_or_neither_interface_form() {
    let m = error(&format!(
        "[[layer]]\n{GOLD}f0 = [0.5, 0.5, 0.5]\nedge_tint = [0.5, 0.5, 0.5]\n"
    ));
    assert_names(&m, &["layer 1", "not both"]);
    let m = error("[[layer]]\nroughness = 0.1\n");
    assert_names(&m, &["layer 1", "`ior`", "missing"]);
}

#[test]
fn empty_stack_and_bad_model() {
    assert_names(&error("name = \"x\"\n"), &["`layer`", "at least one"]);
    let m = error(&format!("model = \"tm4\"\n[[layer]]\n{GOLD}"));
    assert_names(&m, &["`model`", "tm4", "tm2", "tm6"]);
}

#[test]
fn too_many_layers_for_the_variant() {
    let stack = Stack::resolve("five-layers").unwrap();
    let m = stack.check_fits(4).unwrap_err().to_string();
    assert!(m.contains("5 layers") && m.contains("max_layers=4"), "{m}");
    stack.check_fits(5).unwrap();
}

#[test]
fn unknown_preset_is_named() {
    let m = Stack::resolve("unobtainium").unwrap_err().to_string();
    assert!(
        m.contains("unobtainium") && m.contains("assets/materials"),
        "{m}"
    );
}

#[test]
fn artist_form_converts_to_physical() {
    let text = "[[layer]]\nf0 = [0.04, 0.5, 0.9]\nedge_tint = [0.0, 0.5, 0.9]\nroughness = 0.2\n";
    let stack = Stack::from_toml(text, Path::new(FILE)).unwrap();
    let l = stack.layers[0];
    assert!((l.ior[0] - 1.5).abs() < 1e-9 && l.kappa[0].abs() < 1e-9);
    assert!((l.ior[1] - 3.08088).abs() < 1e-4 && (l.kappa[1] - 2.82727).abs() < 1e-4);
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
