//! Reading and writing images: OpenEXR in, OpenEXR (RGBA half) and tone-mapped PNG out.
//!
//! Every output is written to a temporary file beside the target and renamed into place, so a
//! failed or interrupted run never leaves a partial file under the requested name.
//!
//! Errors are [`ImageIoError`]s, each naming the file (or the exposure and its allowed range).

use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use half::f16;

/// An image that cannot be read or written, or an exposure the tone mapper refuses.
#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    /// The input file does not exist.
    #[error("{path}: no such file")]
    NotFound { path: PathBuf },
    /// The `exr` crate cannot read the file as an RGBA OpenEXR image.
    #[error("{path}: not a readable OpenEXR image ({reason})")]
    NotExr { path: PathBuf, reason: String },
    /// The image is 0 pixels wide or high.
    #[error("{path}: image has no pixels")]
    Empty { path: PathBuf },
    /// The first pixel (column, row) whose radiance is NaN or infinite.
    #[error("{path}: pixel ({x}, {y}) has radiance {radiance:?}; expected finite values")]
    NonFinite {
        path: PathBuf,
        x: usize,
        y: usize,
        radiance: [f32; 3],
    },
    /// An output that could not be written; nothing is left under its name.
    #[error("writing {path}: {message}")]
    Write { path: PathBuf, message: String },
    /// An exposure outside [`EXPOSURE_RANGE_EV`].
    #[error(
        "exposure {exposure_ev}: allowed: a number of stops in {}..={}",
        EXPOSURE_RANGE_EV.start(),
        EXPOSURE_RANGE_EV.end()
    )]
    Exposure { exposure_ev: f32 },
}

/// A linear RGBA image in f32, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 4]>,
}

impl HdrImage {
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 4] {
        self.pixels[y * self.width + x]
    }
}

/// Reads the first RGBA layer of an OpenEXR file (any compression the `exr` crate reads, DWAB
/// included). Missing alpha reads as 1. Rejects non-finite radiance, which would otherwise turn
/// into NaN pixels downstream; slightly negative values, which lossy EXR compression (DWAB)
/// leaves around dark texels, are clamped to 0.
pub fn read_exr(path: &Path) -> Result<HdrImage, ImageIoError> {
    if !path.is_file() {
        return Err(ImageIoError::NotFound {
            path: path.to_owned(),
        });
    }
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| HdrImage {
            width: resolution.width(),
            height: resolution.height(),
            pixels: vec![[0.0; 4]; resolution.width() * resolution.height()],
        },
        |image: &mut HdrImage, position, (r, g, b, a): (f32, f32, f32, f32)| {
            let index = position.y() * image.width + position.x();
            image.pixels[index] = [r, g, b, a];
        },
    )
    .map_err(|e| ImageIoError::NotExr {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    let mut image = image.layer_data.channel_data.pixels;
    if image.width == 0 || image.height == 0 {
        return Err(ImageIoError::Empty {
            path: path.to_owned(),
        });
    }
    if let Some(i) = image
        .pixels
        .iter()
        .position(|p| p[..3].iter().any(|c| !c.is_finite()))
    {
        let [r, g, b, _] = image.pixels[i];
        return Err(ImageIoError::NonFinite {
            path: path.to_owned(),
            x: i % image.width,
            y: i / image.width,
            radiance: [r, g, b],
        });
    }
    for p in &mut image.pixels {
        for c in &mut p[..3] {
            *c = c.max(0.0);
        }
    }
    Ok(image)
}

/// Writes through a temporary file in the same directory, then renames it over `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), ImageIoError> {
    let output_error = |message: String| ImageIoError::Write {
        path: path.to_owned(),
        message,
    };
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|e| output_error(e.to_string()))?;
    let name = path
        .file_name()
        .ok_or_else(|| output_error("not a file name".into()))?
        .to_string_lossy();
    // Unique per process and call: two threads saving the same file must not share a temp.
    static WRITES: AtomicU64 = AtomicU64::new(0);
    let call = WRITES.fetch_add(1, Ordering::Relaxed);
    let temp: PathBuf = parent.join(format!(".{name}.{}.{call}.tmp", std::process::id()));
    let result = write(&temp).and_then(|()| {
        std::fs::rename(&temp, path).map_err(|e| format!("renaming the temporary file: {e}"))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result.map_err(output_error)
}

/// Writes `contents` (text or bytes) to `path` through [`write_atomically`].
pub fn write_file_atomically(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), ImageIoError> {
    write_atomically(path, |temp| {
        std::fs::write(temp, contents.as_ref()).map_err(|e| e.to_string())
    })
}

/// Writes RGBA pixels (rows top to bottom) as a half-float OpenEXR file: each value rounded to
/// the nearest half float (exact for a half-float render target's frames).
pub fn write_exr_rgba16f(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &[[f32; 4]],
) -> Result<(), ImageIoError> {
    write_exr(path, width, height, pixels, f16::from_f32)
}

/// Writes RGBA pixels (rows top to bottom) as a 32-bit float OpenEXR file (a reference image,
/// whose averages are finer than a half float).
pub fn write_exr_rgba32f(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &[[f32; 4]],
) -> Result<(), ImageIoError> {
    write_exr(path, width, height, pixels, |c| c)
}

/// Writes RGBA pixels as an OpenEXR file of the sample type `sample` converts to.
fn write_exr<T: exr::prelude::IntoSample>(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &[[f32; 4]],
    sample: impl Fn(f32) -> T + Sync,
) -> Result<(), ImageIoError> {
    assert_eq!(
        pixels.len(),
        width * height,
        "pixel count must match the size"
    );
    write_atomically(path, |temp| {
        exr::prelude::write_rgba_file(temp, width, height, |x, y| {
            let p = pixels[y * width + x].map(&sample);
            (p[0], p[1], p[2], p[3])
        })
        .map_err(|e| e.to_string())
    })
}

/// Narkowicz 2015's fit of the ACES filmic curve.
fn aces(x: f32) -> f32 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The exposures the tone mapper is asked for, in stops. Half-float radiance spans
/// 2⁻²⁴ … 2¹⁶, so past 24 stops either way every pixel is black or white; NaN and the
/// infinities are outside too.
pub const EXPOSURE_RANGE_EV: RangeInclusive<f32> = -24.0..=24.0;

/// Errs, naming the allowed range, unless `exposure_ev` is in [`EXPOSURE_RANGE_EV`].
pub fn check_exposure(exposure_ev: f32) -> Result<(), ImageIoError> {
    if EXPOSURE_RANGE_EV.contains(&exposure_ev) {
        return Ok(());
    }
    Err(ImageIoError::Exposure { exposure_ev })
}

/// Tone-maps linear radiance to 8-bit sRGB: exposure (in stops), ACES fit, sRGB encoding.
pub fn tonemap(pixels: &[[f32; 4]], exposure_ev: f32) -> Vec<u8> {
    let scale = exposure_ev.exp2();
    pixels
        .iter()
        .flat_map(|p| {
            let c = |v: f32| (srgb_encode(aces(v * scale)) * 255.0 + 0.5) as u8;
            [c(p[0]), c(p[1]), c(p[2]), 255]
        })
        .collect()
}

/// Writes a tone-mapped PNG of linear RGBA pixels; errs on an exposure outside
/// [`EXPOSURE_RANGE_EV`] before writing anything.
pub fn write_png_tonemapped(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &[[f32; 4]],
    exposure_ev: f32,
) -> Result<(), ImageIoError> {
    check_exposure(exposure_ev)?;
    let rgba = tonemap(pixels, exposure_ev);
    write_png(path, width, height, &rgba)
}

/// Writes 8-bit RGBA pixels as a PNG.
pub fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    rgba: &[u8],
) -> Result<(), ImageIoError> {
    write_atomically(path, |temp| {
        let file = std::fs::File::create(temp).map_err(|e| e.to_string())?;
        let mut encoder =
            png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(rgba).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("lamina-imageio-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn exr_round_trip_is_exact_for_half_floats() {
        let (w, h) = (37, 23);
        // Every pixel a distinct half value, including subnormals, large values and zero.
        let pixels: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let bits = (i as u16).wrapping_mul(97) & 0x7bff;
                [
                    f16::from_bits(bits),
                    f16::from_bits(bits ^ 0x0155),
                    f16::from_f32(i as f32 * 0.37),
                    f16::from_f32(1.0),
                ]
                .map(f16::to_f32)
            })
            .collect();
        let path = temp_dir("roundtrip").join("image.exr");
        write_exr_rgba16f(&path, w, h, &pixels).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        for (a, b) in pixels.iter().zip(&back.pixels) {
            for c in 0..4 {
                // f16 → f32 is exact, so equal f32s mean equal half bits.
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn corrupt_and_missing_files_are_named() {
        let dir = temp_dir("corrupt");
        let bad = dir.join("bad.exr");
        std::fs::write(&bad, b"this is not an EXR file").unwrap();
        let e = read_exr(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.exr") && e.contains("OpenEXR"), "{e}");
        let e = read_exr(&dir.join("missing.exr")).unwrap_err().to_string();
        assert!(
            e.contains("missing.exr") && e.contains("no such file"),
            "{e}"
        );
    }

    #[test]
    fn failed_writes_leave_nothing_behind() {
        let dir = temp_dir("atomic");
        let path = dir.join("out.png");
        let r = write_atomically(&path, |temp| {
            std::fs::write(temp, b"partial").unwrap();
            Err("simulated failure".into())
        });
        assert!(r.is_err());
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    }

    #[test]
    fn exposures_outside_the_range_are_refused_before_writing() {
        let path = temp_dir("exposure").join("never.png");
        for ev in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 24.5, -25.0] {
            let e = write_png_tonemapped(&path, 1, 1, &[[1.0; 4]], ev).unwrap_err();
            assert!(e.to_string().contains("-24..=24"), "{e}");
        }
        assert!(!path.exists());
        assert!(check_exposure(24.0).is_ok() && check_exposure(-24.0).is_ok());
    }

    #[test]
    fn tonemap_is_monotonic_and_bounded() {
        let ramp: Vec<[f32; 4]> = (0..64).map(|i| [i as f32 * 0.25; 4]).collect();
        let out = tonemap(&ramp, 0.0);
        let reds: Vec<u8> = out.chunks(4).map(|p| p[0]).collect();
        assert_eq!(reds[0], 0);
        assert!(reds.windows(2).all(|w| w[0] <= w[1]));
        assert!(*reds.last().unwrap() >= 250);
    }
}
