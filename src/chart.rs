//! Charts — a study's category and XY charts, a table's heat map — drawn with `plotters`
//! twice: once into SVG (text stays text) and once into an RGB canvas written as PNG. The canvas is lamina's own small plotters backend: plotters 0.3.7
//! can only rasterise text through `font-kit` (system fontconfig and freetype), so the canvas
//! draws text with the bundled DejaVu Sans ([`crate::text`]).

use std::path::Path;

use plotters::coord::ranged1d::{SegmentValue, SegmentedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordi32;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};

use crate::error::{Error, Result};
use crate::text::TextFont;

/// One line of a chart: `(category index, value, low, high)` per point.
pub struct Series {
    pub label: String,
    pub points: Vec<(usize, f64, f64, f64)>,
}

pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// The x axis's categories, in order.
    pub categories: Vec<String>,
    pub series: Vec<Series>,
    /// A horizontal reference line (the ggx baseline), labelled.
    pub reference: Option<(String, f64)>,
}

pub const WIDTH: u32 = 900;
pub const HEIGHT: u32 = 540;

impl Chart {
    /// Writes `STEM.png` and `STEM.svg` atomically.
    pub fn write(&self, stem: &Path) -> Result<()> {
        write_plot(self, stem)
    }

    /// Whether the values span enough decades to need a log-scaled y axis.
    fn log_scale(&self) -> bool {
        let values = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().flat_map(|p| [p.1, p.2, p.3]))
            .chain(self.reference.iter().map(|r| r.1));
        let (lo, hi) = values
            .filter(|v| *v > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        hi > 0.0 && hi / lo > 20.0
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let n = self.categories.len().max(1) as i32;
        let values = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter().flat_map(|p| [p.1, p.2, p.3]))
                .chain(self.reference.iter().map(|r| r.1))
                .filter(|v| v.is_finite() && *v > 0.0)
        };
        let top = values().fold(0.0f64, f64::max);
        let bottom = values().fold(f64::INFINITY, f64::min);
        let top = if top > 0.0 { top } else { 1.0 };
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(&self.title, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(78);
        let x = (0..n - 1).into_segmented();
        if self.log_scale() {
            let chart = builder.build_cartesian_2d(x, (bottom / 1.5..top * 1.5).log_scale())?;
            self.plot(chart, " (log scale)")?;
        } else {
            let chart = builder.build_cartesian_2d(x, 0.0..top * 1.12)?;
            self.plot(chart, "")?;
        }
        root.present()?;
        Ok(())
    }

    fn plot<'a, DB: DrawingBackend + 'a, Y: Ranged<ValueType = f64> + ValueFormatter<f64>>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<SegmentedCoord<RangedCoordi32>, Y>>,
        y_note: &str,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let categories = &self.categories;
        let y_desc = format!("{}{y_note}", self.y_label);
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(y_desc)
            .x_labels(categories.len().max(1))
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => {
                    categories.get(*i as usize).cloned().unwrap_or_default()
                }
                _ => String::new(),
            })
            .y_label_formatter(&|v| format_value(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        if let Some((label, value)) = &self.reference {
            let style = ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![
                        (SegmentValue::Exact(0), *value),
                        (SegmentValue::Last, *value),
                    ],
                    style,
                )))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        }
        for (k, series) in self.series.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let line = ShapeStyle::from(&colour).stroke_width(2);
            let at = |i: usize| SegmentValue::CenterOf(i as i32);
            chart
                .draw_series(LineSeries::new(
                    series.points.iter().map(|p| (at(p.0), p.1)),
                    line,
                ))?
                .label(series.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], line));
            chart.draw_series(
                series
                    .points
                    .iter()
                    .map(|p| Circle::new((at(p.0), p.1), 3, colour.filled())),
            )?;
            chart.draw_series(series.points.iter().filter(|p| p.3 > p.2).map(|p| {
                PathElement::new(
                    vec![(at(p.0), p.2), (at(p.0), p.3)],
                    ShapeStyle::from(&colour).stroke_width(1),
                )
            }))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}

/// One series of an [`XyChart`]: `(x, y, low, high)` per point (whiskers where high > low).
pub struct XySeries {
    pub label: String,
    pub points: Vec<(f64, f64, f64, f64)>,
    /// Joined by a line (a curve), or markers only (samples).
    pub line: bool,
    /// Palette index: series sharing one are drawn in one colour.
    pub colour: usize,
}

/// A chart with numeric axes: curves against samples (the model's BRDF slice against the
/// reference's), or cost against error (a Pareto chart).
pub struct XyChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_range: (f64, f64),
    pub series: Vec<XySeries>,
}

impl XyChart {
    /// Writes `STEM.png` and `STEM.svg` atomically.
    pub fn write(&self, stem: &Path) -> Result<()> {
        write_plot(self, stem)
    }

    fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.series
            .iter()
            .flat_map(|s| s.points.iter().flat_map(|p| [p.1, p.2, p.3]))
            .filter(|v| v.is_finite() && *v > 0.0)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        self.draw_in(&root, 22, SeriesLabelPosition::UpperLeft)?;
        root.present()?;
        Ok(())
    }

    /// Draws the chart into `area` (filled and presented by the caller), its caption at
    /// `caption` points and its legend at `legend`.
    fn draw_in<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, plotters::coord::Shift>,
        caption: u32,
        legend: SeriesLabelPosition,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let top = self.values().fold(0.0f64, f64::max);
        let bottom = self.values().fold(f64::INFINITY, f64::min);
        let top = if top > 0.0 { top } else { 1.0 };
        let mut builder = ChartBuilder::on(area);
        builder
            .caption(&self.title, ("sans-serif", caption))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(78);
        let x = self.x_range.0..self.x_range.1;
        if top / bottom > 20.0 {
            // Many decades (a glossy peak over a diffuse floor): no more than six below the top.
            let bottom = bottom.max(top * 1e-6);
            let chart = builder.build_cartesian_2d(x, (bottom / 1.5..top * 1.5).log_scale())?;
            self.plot(chart, " (log scale)", legend)
        } else {
            let chart = builder.build_cartesian_2d(x, 0.0..top * 1.12)?;
            self.plot(chart, "", legend)
        }
    }

    fn plot<'a, DB: DrawingBackend + 'a, Y: Ranged<ValueType = f64> + ValueFormatter<f64>>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, Y>>,
        y_note: &str,
        legend: SeriesLabelPosition,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(format!("{}{y_note}", self.y_label))
            .x_label_formatter(&|v| format_value(*v))
            .y_label_formatter(&|v| format_value(*v))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        for series in &self.series {
            let colour = Palette99::pick(series.colour).to_rgba();
            let style = ShapeStyle::from(&colour).stroke_width(2);
            let shown = |p: &&(f64, f64, f64, f64)| p.1.is_finite() && p.1 > 0.0;
            if series.line {
                chart
                    .draw_series(LineSeries::new(
                        series.points.iter().filter(shown).map(|p| (p.0, p.1)),
                        style,
                    ))?
                    .label(series.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            } else {
                chart
                    .draw_series(
                        series
                            .points
                            .iter()
                            .filter(shown)
                            .map(|p| Circle::new((p.0, p.1), 3, colour.filled())),
                    )?
                    .label(series.label.clone())
                    .legend(move |(x, y)| Circle::new((x + 9, y), 3, colour.filled()));
            }
            chart.draw_series(series.points.iter().filter(|p| p.3 > p.2 && p.2 > 0.0).map(
                |p| {
                    PathElement::new(
                        vec![(p.0, p.2), (p.0, p.3)],
                        ShapeStyle::from(&colour).stroke_width(1),
                    )
                },
            ))?;
        }
        chart
            .configure_series_labels()
            .position(legend)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    }
}

/// What [`write_plot`] draws twice: into SVG and into the PNG canvas.
trait Plot {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>;

    /// The image's size in pixels.
    fn size(&self) -> (u32, u32) {
        (WIDTH, HEIGHT)
    }
}

impl Plot for Chart {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        self.draw(root)
    }
}

impl Plot for XyChart {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        self.draw(root)
    }
}

/// [`XyChart`]s side by side under one title, a panel each, in rows of [`PANEL_COLUMNS`]: a
/// study's cost against image error with a panel per material, where one plot of every
/// material's runs and fronts hid them under its legend. Each panel's legend sits at its upper
/// right, where such a chart has no runs (high cost and high error at once).
pub struct PanelChart {
    pub title: String,
    pub panels: Vec<XyChart>,
}

/// Panels per row of a [`PanelChart`], and each panel's size in pixels.
const PANEL_COLUMNS: usize = 3;
const PANEL_WIDTH: u32 = 600;
const PANEL_HEIGHT: u32 = 420;

/// Height of a [`PanelChart`]'s title band.
const PANEL_TITLE: u32 = 44;

impl PanelChart {
    /// Writes `STEM.png` and `STEM.svg` atomically.
    pub fn write(&self, stem: &Path) -> Result<()> {
        write_plot(self, stem)
    }

    /// Rows and columns of the grid.
    fn grid(&self) -> (usize, usize) {
        let columns = self.panels.len().clamp(1, PANEL_COLUMNS);
        (self.panels.len().div_ceil(columns).max(1), columns)
    }
}

impl Plot for PanelChart {
    fn draw_on<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let (title, body) = root.split_vertically(PANEL_TITLE);
        title.titled(&self.title, ("sans-serif", 22))?;
        for (panel, area) in self.panels.iter().zip(&body.split_evenly(self.grid())) {
            panel.draw_in(area, 18, SeriesLabelPosition::UpperRight)?;
        }
        root.present()?;
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        let (rows, columns) = self.grid();
        (
            columns as u32 * PANEL_WIDTH,
            rows as u32 * PANEL_HEIGHT + PANEL_TITLE,
        )
    }
}

/// Writes `STEM.svg` (text stays text) and `STEM.png` (the bundled font's canvas) of `plot`,
/// each atomically.
fn write_plot(plot: &impl Plot, stem: &Path) -> Result<()> {
    let (width, height) = plot.size();
    let svg_path = stem.with_extension("svg");
    let mut svg = String::new();
    {
        let backend = SVGBackend::with_string(&mut svg, (width, height));
        plot.draw_on(backend.into_drawing_area())
            .map_err(|e| chart_error(&svg_path, e))?;
    }
    crate::imageio::write_file_atomically(&svg_path, &svg)?;
    let png_path = stem.with_extension("png");
    let mut canvas = Canvas::new(width, height);
    {
        let area = (&mut canvas).into_drawing_area();
        plot.draw_on(area).map_err(|e| chart_error(&png_path, e))?;
    }
    let rgba: Vec<u8> = canvas
        .rgb
        .chunks(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    crate::imageio::write_png(&png_path, width as usize, height as usize, &rgba)?;
    Ok(())
}

/// Axis numbers: plain where short, engineering form for counts.
fn format_value(v: f64) -> String {
    let a = v.abs();
    if a >= 1e9 {
        format!("{:.2}G", v / 1e9)
    } else if a >= 1e6 {
        format!("{:.1}M", v / 1e6)
    } else if a >= 1e4 {
        format!("{:.0}k", v / 1e3)
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

fn chart_error<E: std::error::Error + Send + Sync>(
    path: &Path,
    e: DrawingAreaErrorKind<E>,
) -> Error {
    Error::Output {
        path: path.to_owned(),
        message: format!("drawing the chart: {e}"),
    }
}

/// An RGB8 raster that plotters draws into; text through `ab_glyph`.
pub struct Canvas {
    width: u32,
    height: u32,
    pub rgb: Vec<u8>,
    font: TextFont,
}

#[derive(Debug)]
pub struct CanvasError;

impl std::fmt::Display for CanvasError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("canvas error")
    }
}

impl std::error::Error for CanvasError {}

impl Canvas {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            rgb: vec![255; (width * height * 3) as usize],
            font: TextFont::bundled(),
        }
    }

    fn blend(&mut self, (x, y): BackendCoord, rgb: (u8, u8, u8), alpha: f64) {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return;
        }
        let a = alpha.clamp(0.0, 1.0);
        let i = (y as usize * self.width as usize + x as usize) * 3;
        for (c, src) in [rgb.0, rgb.1, rgb.2].into_iter().enumerate() {
            let dst = f64::from(self.rgb[i + c]);
            self.rgb[i + c] = (dst + (f64::from(src) - dst) * a).round() as u8;
        }
    }
}

impl DrawingBackend for &mut Canvas {
    type ErrorType = CanvasError;

    fn get_size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn ensure_prepared(&mut self) -> std::result::Result<(), DrawingErrorKind<CanvasError>> {
        Ok(())
    }

    fn present(&mut self) -> std::result::Result<(), DrawingErrorKind<CanvasError>> {
        Ok(())
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> std::result::Result<(), DrawingErrorKind<CanvasError>> {
        self.blend(point, color.rgb, color.alpha);
        Ok(())
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> std::result::Result<(), DrawingErrorKind<CanvasError>> {
        let color = style.color();
        let (_, (width, height)) = self.font.layout(text, style.size());
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let transform = style.transform();
        let mut covered = Vec::new();
        self.font.rasterize(text, style.size(), |x, y, coverage| {
            covered.push((transform.transform(x + dx, y + dy), coverage));
        });
        for ((x, y), coverage) in covered {
            self.blend(
                (pos.0 + x, pos.1 + y),
                color.rgb,
                color.alpha * f64::from(coverage),
            );
        }
        Ok(())
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> std::result::Result<(u32, u32), DrawingErrorKind<CanvasError>> {
        let (_, (w, h)) = self.font.layout(text, style.size());
        Ok((w.max(0) as u32, h.max(0) as u32))
    }
}

/// A grid of values drawn as coloured cells, panels side by side, with a colour bar: the error
/// maps of `lamina tables`.
pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// The axes' extents: cells divide them evenly.
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    /// Each panel: its caption and `values[row][column]` (row 0 at the bottom).
    pub panels: Vec<(String, Vec<Vec<f64>>)>,
    /// What the colour bar measures.
    pub value_label: String,
}

/// A perceptually ordered ramp (dark blue → teal → yellow), `t` in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [0.07, 0.04, 0.33]),
        (0.25, [0.23, 0.32, 0.55]),
        (0.5, [0.13, 0.57, 0.55]),
        (0.75, [0.37, 0.79, 0.38]),
        (1.0, [0.99, 0.91, 0.14]),
    ];
    let t = t.clamp(0.0, 1.0);
    let k = STOPS.iter().position(|s| s.0 >= t).unwrap_or(4).max(1);
    let (a, b) = (STOPS[k - 1], STOPS[k]);
    let f = (t - a.0) / (b.0 - a.0);
    let c = |i: usize| ((a.1[i] + (b.1[i] - a.1[i]) * f) * 255.0).round() as u8;
    RGBColor(c(0), c(1), c(2))
}

impl HeatMap {
    /// Writes the map as PNG (`path`), text drawn with the bundled font.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let (width, height) = (300 * self.panels.len() as u32 + 140, 360);
        let mut canvas = Canvas::new(width, height);
        self.draw((&mut canvas).into_drawing_area())
            .map_err(|e| chart_error(path, e))?;
        let rgba: Vec<u8> = canvas
            .rgb
            .chunks(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        crate::imageio::write_png(path, width as usize, height as usize, &rgba)?;
        Ok(())
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let root = root.titled(&self.title, ("sans-serif", 18))?;
        let max = self
            .panels
            .iter()
            .flat_map(|p| p.1.iter().flatten())
            .fold(0.0f64, |m, &v| m.max(v));
        let scale = if max > 0.0 { max } else { 1.0 };
        let (panels_area, bar_area) = root.split_horizontally(root.dim_in_pixel().0 - 140);
        let areas = panels_area.split_evenly((1, self.panels.len().max(1)));
        for (area, (caption, values)) in areas.iter().zip(&self.panels) {
            let rows = values.len();
            let cols = values.first().map_or(0, Vec::len);
            let mut chart = ChartBuilder::on(area)
                .caption(caption, ("sans-serif", 14))
                .margin(8)
                .x_label_area_size(36)
                .y_label_area_size(40)
                .build_cartesian_2d(
                    self.x_range.0..self.x_range.1,
                    self.y_range.0..self.y_range.1,
                )?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .x_labels(3)
                .y_labels(3)
                .label_style(("sans-serif", 12))
                .axis_desc_style(("sans-serif", 13))
                .draw()?;
            let (x0, y0) = (self.x_range.0, self.y_range.0);
            let dx = (self.x_range.1 - x0) / cols.max(1) as f64;
            let dy = (self.y_range.1 - y0) / rows.max(1) as f64;
            chart.draw_series(values.iter().enumerate().flat_map(|(r, row)| {
                row.iter().enumerate().map(move |(c, &v)| {
                    let (x, y) = (x0 + c as f64 * dx, y0 + r as f64 * dy);
                    Rectangle::new([(x, y), (x + dx, y + dy)], ramp(v / scale).filled())
                })
            }))?;
        }
        let mut bar = ChartBuilder::on(&bar_area)
            .margin(8)
            .margin_top(28)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..1.0, 0.0..scale)?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(&self.value_label)
            .y_labels(5)
            .y_label_formatter(&|v| format!("{v:.3}"))
            .label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .draw()?;
        let steps = 64;
        bar.draw_series((0..steps).map(|i| {
            let (a, b) = (
                scale * f64::from(i) / f64::from(steps),
                scale * f64::from(i + 1) / f64::from(steps),
            );
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                ramp((f64::from(i) + 0.5) / f64::from(steps)).filled(),
            )
        }))?;
        root.present()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_canvas_draws_text_and_lines() {
        let chart = Chart {
            title: "title".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            categories: vec!["a".into(), "b".into()],
            series: vec![Series {
                label: "s".into(),
                points: vec![(0, 1.0, 0.9, 1.1), (1, 2.0, 1.8, 2.2)],
            }],
            reference: Some(("ggx".into(), 0.5)),
        };
        let mut canvas = Canvas::new(WIDTH, HEIGHT);
        chart.draw((&mut canvas).into_drawing_area()).unwrap();
        // Dark pixels (text, axes) and coloured ones (the series) are both present.
        let pixels: Vec<&[u8]> = canvas.rgb.chunks(3).collect();
        let dark = pixels.iter().filter(|p| p.iter().all(|&c| c < 80)).count();
        let coloured = pixels
            .iter()
            .filter(|p| p.iter().max().unwrap() - p.iter().min().unwrap() > 100)
            .count();
        assert!(dark > 500, "{dark} dark pixels");
        assert!(coloured > 100, "{coloured} coloured pixels");
        // The title's glyphs: dark pixels in the caption band at the top.
        let caption_dark = pixels[..(WIDTH * 40) as usize]
            .iter()
            .filter(|p| p.iter().all(|&c| c < 100))
            .count();
        assert!(caption_dark > 20, "no caption text drawn");
    }

    #[test]
    fn a_panel_chart_draws_each_panel_in_its_cell() {
        let panel = |title: String| XyChart {
            title,
            x_label: "x".into(),
            y_label: "y".into(),
            x_range: (0.0, 1.0),
            series: vec![XySeries {
                label: "s".into(),
                points: vec![(0.5, 2.0, 0.0, 0.0)],
                line: false,
                colour: 0,
            }],
        };
        let chart = PanelChart {
            title: "title".into(),
            panels: (0..4).map(|i| panel(format!("panel {i}"))).collect(),
        };
        // Four panels: two rows of three cells, the last two empty.
        let (width, height) = chart.size();
        assert_eq!(
            (width, height),
            (3 * PANEL_WIDTH, 2 * PANEL_HEIGHT + PANEL_TITLE)
        );
        let mut canvas = Canvas::new(width, height);
        chart.draw_on((&mut canvas).into_drawing_area()).unwrap();
        let dark_in = |column: u32, row: u32| {
            let (x0, y0) = (column * PANEL_WIDTH, PANEL_TITLE + row * PANEL_HEIGHT);
            let mut dark = 0;
            for y in y0 + 4..y0 + PANEL_HEIGHT - 4 {
                for x in x0 + 4..x0 + PANEL_WIDTH - 4 {
                    let p = 3 * (y * width + x) as usize;
                    dark += usize::from(canvas.rgb[p..p + 3].iter().all(|&c| c < 80));
                }
            }
            dark
        };
        for (column, row) in [(0, 0), (1, 0), (2, 0), (0, 1)] {
            assert!(dark_in(column, row) > 500, "panel at ({column}, {row})");
        }
        assert_eq!(dark_in(1, 1), 0);
        assert_eq!(dark_in(2, 1), 0);
    }
}
