//! Error of an image against a reference, and one measured row.

use super::variant::Variant;
use crate::choice::KernelChoice;
use crate::film::Image;

/// Added to a pixel's squared reference value in relMSE.
pub const RELMSE_EPSILON: f64 = 0.01;

/// Added to a pixel's reference value in the mean signed relative error.
pub const SIGNED_EPSILON: f64 = 0.01;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub mse: f64,
    pub rmse: f64,
    /// Mean of `(x - r)^2 / (r^2 + 0.01)`.
    pub relmse: f64,
    /// Mean signed relative error, `(x - r) / (r + 0.01)` averaged over every
    /// channel of every pixel: zero in expectation for an unbiased estimator
    /// (it is linear in `x`), so it shows a bias such as adaptive sampling's.
    pub mean_rel_error: f64,
}

/// Error of `image` against `reference` (the sizes must match).
pub fn error_metrics(image: &Image, reference: &Image) -> Metrics {
    let mut se = 0.0;
    let mut rel = 0.0;
    let mut signed = 0.0;
    let mut n = 0usize;
    for (p, r) in image.data.iter().zip(&reference.data) {
        for k in 0..3 {
            let d = p[k] as f64 - r[k] as f64;
            let r = r[k] as f64;
            se += d * d;
            rel += d * d / (r * r + RELMSE_EPSILON);
            signed += d / (r.abs() + SIGNED_EPSILON);
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Metrics { mse: se / n, rmse: (se / n).sqrt(), relmse: rel / n, mean_rel_error: signed / n }
}

/// One measured render.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergeRow {
    pub kernel: KernelChoice,
    pub variant: Variant,
    pub spp: u32,
    pub seconds: f64,
    pub rays: u64,
    pub samples: u64,
    pub rmse: f64,
    pub relmse: f64,
    pub mean_rel_error: f64,
    pub image_hash: String,
}

impl ConvergeRow {
    pub fn mse(&self) -> f64 {
        self.rmse * self.rmse
    }
    /// `1 / (MSE x seconds)`.
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.mse() * self.seconds)
    }
    pub fn label(&self) -> String {
        format!("{}/{}", self.kernel.name(), self.variant.name())
    }

    /// The row's cells as every table prints them (console and markdown):
    /// kernel, variant, spp, seconds, Mrays/s, samples per pixel (of `pixels`),
    /// RMSE, relMSE, mean signed relative error, efficiency.
    pub fn cells(&self, pixels: f64) -> [String; 10] {
        [
            self.kernel.name().to_string(),
            self.variant.name(),
            self.spp.to_string(),
            format!("{:.3}", self.seconds),
            format!("{:.2}", self.rays as f64 / self.seconds / 1e6),
            format!("{:.1}", self.samples as f64 / pixels.max(1.0)),
            format!("{:.5}", self.rmse),
            format!("{:.3e}", self.relmse),
            format!("{:+.5}", self.mean_rel_error),
            format!("{:.4e}", self.efficiency()),
        ]
    }
}
