//! The cross-device table: a study run on several devices (`lamina report` over each device's
//! results, e.g. lavapipe's and an H100's) set side by side as ratios to each run's own `ggx`
//! baseline — the only figures that compare across machines.

use std::fmt::Write as _;

use super::super::dirs::StudyDir;
use super::anchor;

/// Per study that more than one device ran: one row per point of the first run (its axis
/// values, or its variant where the study has no axes), one column per device, each cell the
/// run's time over its baseline's (and, where the device's run was counted, its JIT
/// instructions per shaded pixel over the baseline's).
pub fn devices_section(md: &mut String, studies: &[StudyDir]) {
    let mut groups: Vec<Vec<&StudyDir>> = Vec::new();
    for s in studies.iter().filter(|s| s.meta.reference.is_empty()) {
        match groups.iter_mut().find(|g| g[0].meta.name == s.meta.name) {
            Some(g) => g.push(s),
            None => groups.push(vec![s]),
        }
    }
    groups.retain(|g| {
        g.iter()
            .any(|s| s.results.device.name != g[0].results.device.name)
    });
    if groups.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "## Across devices\n\n\
         Each study that more than one device ran, as ratios to the `ggx` baseline of the same \
         run (time; per shaded pixel in JIT instructions where the run was counted): absolute \
         times of different machines do not compare, these do.\n"
    );
    for g in groups {
        let _ = writeln!(
            md,
            "### [{}](#{})\n",
            g[0].meta.title,
            anchor(&g[0].meta.title)
        );
        let names: Vec<&str> = g.iter().map(|s| s.results.device.name.as_str()).collect();
        let first = g[0];
        let axes = if first.meta.axes.is_empty() {
            "variant".to_owned()
        } else {
            first.meta.axes.join(", ")
        };
        // The material is a column of its own unless it is an axis.
        let material = !first.meta.axes.iter().any(|a| a == "material");
        let head = if material { " material |" } else { "" };
        let _ = writeln!(md, "| {axes} |{head} {} |", names.join(" | "));
        let columns = names.len() + 1 + usize::from(material);
        let _ = writeln!(md, "|{}", "---|".repeat(columns));
        for point in &first.meta.points {
            let run = &first.results.runs[point.run];
            let label = if point.coords.is_empty() {
                format!("`{}`", run.variant)
            } else {
                point.coords.join(", ")
            };
            let cells: Vec<String> = g
                .iter()
                .map(|s| {
                    s.results
                        .runs
                        .iter()
                        .find(|r| r.variant == run.variant && r.material == run.material)
                        .map_or("–".into(), |r| match r.instructions_per_pixel_ratio {
                            Some(i) => format!("{:.2}× ({i:.2}×)", r.ratio_to_baseline),
                            None => format!("{:.2}×", r.ratio_to_baseline),
                        })
                })
                .collect();
            let material = if material {
                format!(" {} |", run.material)
            } else {
                String::new()
            };
            let _ = writeln!(md, "| {label} |{material} {} |", cells.join(" | "));
        }
        md.push('\n');
    }
}
