//! The image buffer and its output formats.

use std::path::Path;

/// A linear-RGB image, rows top to bottom, three f32 per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` linear values, row-major, RGB interleaved.
    pub data: Vec<f32>,
}

/// Why an image could not be written.
#[derive(Debug)]
pub enum SaveError {
    /// PNG encoding or file error.
    Png(image::ImageError),
    /// OpenEXR encoding or file error.
    Exr(exr::error::Error),
    /// The file name ends neither in `.png` nor in `.exr`.
    UnknownExtension(String),
}

impl std::fmt::Display for SaveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SaveError::Png(e) => write!(f, "PNG output failed: {e}"),
            SaveError::Exr(e) => write!(f, "EXR output failed: {e}"),
            SaveError::UnknownExtension(p) => {
                write!(f, "output {p:?} must end in .png or .exr")
            }
        }
    }
}

impl std::error::Error for SaveError {}

/// sRGB opto-electronic transfer function on a value clamped to [0, 1].
fn srgb_encode(linear: f32) -> u8 {
    let c = if linear.is_finite() {
        linear.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (v * 255.0 + 0.5) as u8
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![0.0; width as usize * height as usize * 3],
        }
    }

    /// Linear RGB of pixel (`x`, `y`).
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Mean over pixels and channels of the squared linear difference (the tasks' loss).
    /// Images of different sizes compare as infinitely different.
    pub fn mse(&self, other: &Image) -> f64 {
        if self.width != other.width || self.height != other.height || self.data.is_empty() {
            return f64::INFINITY;
        }
        let sum: f64 = self
            .data
            .iter()
            .zip(&other.data)
            .map(|(&a, &b)| {
                let d = a as f64 - b as f64;
                d * d
            })
            .sum();
        sum / self.data.len() as f64
    }

    /// Mean of each channel over the pixel rectangle [x0, x1) x [y0, y1).
    pub fn mean_rgb(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> [f64; 3] {
        let mut acc = [0.0f64; 3];
        let mut n = 0usize;
        for y in y0..y1.min(self.height) {
            for x in x0..x1.min(self.width) {
                let p = self.pixel(x, y);
                for c in 0..3 {
                    acc[c] += p[c] as f64;
                }
                n += 1;
            }
        }
        acc.map(|v| v / n.max(1) as f64)
    }

    /// Writes `.png` (sRGB, clamped to [0, 1]) or `.exr` (linear f32), by extension.
    pub fn save(&self, path: &Path) -> Result<(), SaveError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => self.save_png(path),
            Some("exr") => self.save_exr(path),
            _ => Err(SaveError::UnknownExtension(path.display().to_string())),
        }
    }

    /// sRGB-encoded 8-bit PNG; values outside [0, 1] are clamped.
    pub fn save_png(&self, path: &Path) -> Result<(), SaveError> {
        let bytes: Vec<u8> = self.data.iter().map(|&v| srgb_encode(v)).collect();
        image::save_buffer(
            path,
            &bytes,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(SaveError::Png)
    }

    /// Linear f32 OpenEXR.
    pub fn save_exr(&self, path: &Path) -> Result<(), SaveError> {
        let w = self.width as usize;
        exr::prelude::write_rgb_file(path, w, self.height as usize, |x, y| {
            let i = 3 * (y * w + x);
            (self.data[i], self.data[i + 1], self.data[i + 2])
        })
        .map_err(SaveError::Exr)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mse_is_mean_over_pixels_and_channels() {
        let a = Image::new(2, 1);
        let mut b = Image::new(2, 1);
        b.data[0] = 1.0;
        b.data[5] = 2.0;
        assert!((a.mse(&b) - 5.0 / 6.0).abs() < 1e-12);
        assert_eq!(a.mse(&Image::new(1, 2)), f64::INFINITY);
    }

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        assert_eq!(srgb_encode(7.0), 255);
        assert_eq!(srgb_encode(f32::NAN), 0);
        assert_eq!(srgb_encode(0.215_861), 128);
    }
}
