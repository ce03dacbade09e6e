//! Image and window sizes as the command line and the sweep files spell them: `WxH`.
//!
//! One limit for every size: each side in 1..=[`Size::MAX_SIDE`] (16384, the
//! `maxImageDimension2D` of lavapipe and of desktop GPUs; Vulkan guarantees only 4096, and a
//! device with less fails later, naming its own limit). A side of 0 or past the limit is refused
//! here, naming the side and the allowed range.

use std::fmt;
use std::str::FromStr;

/// A width and a height in pixels, each in 1..=[`Size::MAX_SIDE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

/// Why a `WxH` text is not a [`Size`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SizeError {
    #[error("`{0}` is not WIDTHxHEIGHT, e.g. 640x360")]
    Malformed(String),
    #[error("{side} `{value}` must be an integer in 1..={max}", max = Size::MAX_SIDE)]
    Side { side: &'static str, value: String },
}

impl Size {
    /// Largest width or height accepted.
    pub const MAX_SIDE: u32 = 16384;
}

impl FromStr for Size {
    type Err = SizeError;

    /// `WxH` (or `WXH`), blanks around each side allowed.
    fn from_str(text: &str) -> Result<Self, SizeError> {
        let (w, h) = text
            .split_once(['x', 'X'])
            .ok_or_else(|| SizeError::Malformed(text.into()))?;
        let side = |value: &str, side: &'static str| {
            value
                .trim()
                .parse::<u32>()
                .ok()
                .filter(|n| (1..=Self::MAX_SIDE).contains(n))
                .ok_or_else(|| SizeError::Side {
                    side,
                    value: value.into(),
                })
        };
        Ok(Self {
            width: side(w, "width")?,
            height: side(h, "height")?,
        })
    }
}

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print_and_bad_ones_name_the_range() {
        let s: Size = "640x360".parse().unwrap();
        assert_eq!((s.width, s.height), (640, 360));
        assert_eq!(s.to_string(), "640x360");
        assert_eq!("16384X1".parse::<Size>().unwrap().height, 1);
        for (text, words) in [
            ("0x64", ["width", "1..=16384"]),
            ("64x16385", ["height", "1..=16384"]),
            ("64", ["WIDTHxHEIGHT", "64"]),
            ("axb", ["width", "`a`"]),
        ] {
            let e = text.parse::<Size>().unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "{text}: `{w}` missing from {e}");
            }
        }
    }
}
