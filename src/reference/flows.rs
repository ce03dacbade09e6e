//! Where the energy goes at each boundary of a stack, by crossing order: `lamina reference
//! --tally`, the measurement behind the model's transport (issue 27's causes: transmission
//! taken as 1 − r, and one TIR ratio for every order).
//!
//! Every arrival of a path at a boundary is one event, sorted by the boundary, the direction
//! it arrives from (from above: travelling down; from below: travelling up) and its order — the
//! how-manyth arrival of that path at that boundary from that side (1, 2, 3 or more). Each
//! event adds the path's energy to *arriving* and splits it into *sent back* (reflected to the
//! side it came from), *passed* (transmitted to the other side) and *lost* (what the
//! interface's single scattering removes to masking, or a base absorbs). Under
//! `interfaces=multiple` a dielectric loses nothing.

use serde::Serialize;

/// Crossing orders kept apart: 1, 2, and 3 or more.
pub const ORDERS: usize = 3;

/// Most boundaries a stack has (every layer's interface and the open bottom).
pub const MAX_BOUNDARIES: usize = crate::variant::MAX_LAYERS_LIMIT as usize + 1;

/// The direction a path arrives at a boundary from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// From above, travelling down.
    Above,
    /// From below, travelling up.
    Below,
}

/// Sums of one (boundary, side, order) class of events, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Flow {
    pub arriving: [f64; 3],
    pub sent_back: [f64; 3],
    pub passed: [f64; 3],
    pub lost: [f64; 3],
}

impl Flow {
    fn merge(&mut self, other: &Flow) {
        for c in 0..3 {
            self.arriving[c] += other.arriving[c];
            self.sent_back[c] += other.sent_back[c];
            self.passed[c] += other.passed[c];
            self.lost[c] += other.lost[c];
        }
    }

    fn scaled(&self, s: f64) -> Flow {
        Flow {
            arriving: self.arriving.map(|v| v * s),
            sent_back: self.sent_back.map(|v| v * s),
            passed: self.passed.map(|v| v * s),
            lost: self.lost.map(|v| v * s),
        }
    }
}

/// The events of a set of paths.
#[derive(Clone, Debug, PartialEq)]
pub struct Flows {
    cells: Vec<Flow>,
}

/// One path's count of arrivals per (boundary, side), for the order of the next.
#[derive(Clone, Copy, Debug)]
pub struct Arrivals([u8; 2 * MAX_BOUNDARIES]);

impl Arrivals {
    pub fn new() -> Self {
        Self([0; 2 * MAX_BOUNDARIES])
    }

    /// The order (0-based, capped) of an arrival at boundary `b` from `from`, counted.
    pub fn next(&mut self, b: usize, from: Side) -> usize {
        let slot = &mut self.0[2 * b + from as usize];
        let order = usize::from(*slot).min(ORDERS - 1);
        *slot = slot.saturating_add(1);
        order
    }
}

impl Default for Arrivals {
    fn default() -> Self {
        Self::new()
    }
}

/// Where an arrival's energy went.
#[derive(Clone, Copy, Debug)]
pub enum Fate {
    SentBack(f64),
    Passed(f64),
    /// Nothing left the boundary (lost whole).
    Lost,
    /// Neither resolved nor lost (a walk on the microsurface given up): counted as arriving
    /// only.
    Unresolved,
}

/// One row of [`Flows::rows`]: a (boundary, side, order) class's mean energies per path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlowRow {
    /// Boundary index, 0 the top interface.
    pub boundary: usize,
    pub from: Side,
    /// "1", "2" or "3+".
    pub order: &'static str,
    #[serde(flatten)]
    pub flow: Flow,
}

impl Flows {
    pub fn new() -> Self {
        Self {
            cells: vec![Flow::default(); 2 * MAX_BOUNDARIES * ORDERS],
        }
    }

    fn cell(&mut self, b: usize, from: Side, order: usize) -> &mut Flow {
        &mut self.cells[(2 * b + from as usize) * ORDERS + order]
    }

    /// Records an arrival of energy `w` in channel `c` and its fate.
    pub fn record(&mut self, c: usize, b: usize, from: Side, order: usize, w: f64, fate: Fate) {
        let cell = self.cell(b, from, order);
        cell.arriving[c] += w;
        match fate {
            Fate::SentBack(out) => {
                cell.sent_back[c] += out;
                cell.lost[c] += w - out;
            }
            Fate::Passed(out) => {
                cell.passed[c] += out;
                cell.lost[c] += w - out;
            }
            Fate::Lost => cell.lost[c] += w,
            Fate::Unresolved => {}
        }
    }

    pub fn merge(&mut self, other: &Flows) {
        for (a, b) in self.cells.iter_mut().zip(&other.cells) {
            a.merge(b);
        }
    }

    /// The classes any path reached, as means over `paths` paths per channel.
    pub fn rows(&self, paths: f64) -> Vec<FlowRow> {
        let mut rows = Vec::new();
        for b in 0..MAX_BOUNDARIES {
            for from in [Side::Above, Side::Below] {
                for (order, name) in ["1", "2", "3+"].into_iter().enumerate() {
                    let flow = self.cells[(2 * b + from as usize) * ORDERS + order];
                    if flow.arriving.iter().any(|&a| a > 0.0) {
                        rows.push(FlowRow {
                            boundary: b,
                            from,
                            order: name,
                            flow: flow.scaled(1.0 / paths),
                        });
                    }
                }
            }
        }
        rows
    }
}

impl Default for Flows {
    fn default() -> Self {
        Self::new()
    }
}
