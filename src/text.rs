//! Text on raster images with the bundled DejaVu Sans (assets/fonts/), through `ab_glyph`:
//! the charts' labels (plotters can only rasterise text through system fontconfig) and the
//! contact sheet's tile labels.

use ab_glyph::{Font, FontRef, Glyph, PxScale, ScaleFont};

static FONT_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// The bundled font.
pub struct TextFont(FontRef<'static>);

impl TextFont {
    pub fn bundled() -> Self {
        Self(FontRef::try_from_slice(FONT_BYTES).expect("the bundled font parses"))
    }

    /// Pixel-space layout of `text` at `size` px: the glyphs' pen positions (the baseline at
    /// the ascent) and the box (width, ascent + descent).
    pub fn layout(&self, text: &str, size: f64) -> (Vec<Glyph>, (i32, i32)) {
        let scale = PxScale::from(size as f32);
        let scaled = self.0.as_scaled(scale);
        let mut pen = 0.0f32;
        let mut previous = None;
        let mut glyphs = Vec::new();
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(p) = previous {
                pen += scaled.kern(p, id);
            }
            glyphs.push(id.with_scale_and_position(scale, ab_glyph::point(pen, scaled.ascent())));
            pen += scaled.h_advance(id);
            previous = Some(id);
        }
        let height = (scaled.ascent() - scaled.descent()).ceil() as i32;
        (glyphs, (pen.ceil() as i32, height))
    }

    /// Calls `plot(x, y, coverage)` for every pixel `text` covers at `size` px, relative to the
    /// top-left of its box.
    pub fn rasterize(&self, text: &str, size: f64, mut plot: impl FnMut(i32, i32, f32)) {
        let (glyphs, _) = self.layout(text, size);
        for glyph in glyphs {
            if let Some(outline) = self.0.outline_glyph(glyph) {
                let bounds = outline.px_bounds();
                outline.draw(|x, y, coverage| {
                    plot(
                        bounds.min.x as i32 + x as i32,
                        bounds.min.y as i32 + y as i32,
                        coverage,
                    );
                });
            }
        }
    }
}
