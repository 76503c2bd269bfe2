//! Feature buffers (AOVs) for denoisers: which ones a render writes
//! ([`Aovs`]), the buffers themselves ([`Features`], computed by
//! [`crate::kernel::first_hit`]) and their files: layers of an EXR beside the
//! colour (`albedo.R`, `albedo.G`, `albedo.B`, `normal.X`, `normal.Y`,
//! `normal.Z`, `depth.Z`), or PFM files beside the image (`x.albedo.pfm`,
//! `x.normal.pfm`: three channels; `x.depth.pfm`: one), which is what Intel
//! Open Image Denoise's `oidnDenoise` reads.

use super::Image;
use crate::error::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The feature buffers a render writes (`--aov albedo,normal,depth`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Aovs {
    /// The first surface's albedo after textures.
    pub albedo: bool,
    /// The first surface's shading normal (unit, facing the camera ray).
    pub normal: bool,
    /// The distance to the first surface along the camera ray.
    pub depth: bool,
}

impl Aovs {
    /// Every buffer, in the order files and layers are written.
    pub const NAMES: [&'static str; 3] = ["albedo", "normal", "depth"];

    /// Parses a comma-separated list of buffer names (each at most once).
    pub fn parse(text: &str) -> Result<Aovs> {
        let mut a = Aovs::default();
        for name in text.split(',').map(str::trim) {
            let slot = match name {
                "albedo" => &mut a.albedo,
                "normal" => &mut a.normal,
                "depth" => &mut a.depth,
                _ => {
                    let hint = crate::choice::nearest(name, Aovs::NAMES.iter().copied())
                        .map(|n| format!(" (did you mean '{n}'?)"))
                        .unwrap_or_default();
                    return Err(Error::invalid(
                        "aov",
                        format!(
                            "'{}' is not a feature buffer{hint}: give a comma-separated list of {}",
                            crate::output::clip(name),
                            Aovs::NAMES.join(", ")
                        ),
                    ));
                }
            };
            if *slot {
                return Err(Error::invalid("aov", format!("'{name}' is listed twice")));
            }
            *slot = true;
        }
        Ok(a)
    }

    /// Whether any buffer is asked for.
    pub fn any(self) -> bool {
        self.albedo || self.normal || self.depth
    }

    /// The names of the buffers asked for, in [`Aovs::NAMES`] order.
    pub fn names(self) -> Vec<&'static str> {
        let on = [self.albedo, self.normal, self.depth];
        Aovs::NAMES.iter().zip(on).filter(|(_, on)| *on).map(|(n, _)| *n).collect()
    }
}

/// The feature buffers of a render (of its crop window, if any): per pixel,
/// the mean over its samples; `None` where not asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    pub width: u32,
    pub height: u32,
    pub albedo: Option<Image>,
    pub normal: Option<Image>,
    /// One value a pixel.
    pub depth: Option<Vec<f32>>,
}

impl Features {
    /// The buffers as named images (depth as a grey one), in [`Aovs::NAMES`] order.
    fn layers(&self) -> Vec<(&'static str, Buffer<'_>)> {
        let mut out = Vec::new();
        if let Some(a) = &self.albedo {
            out.push(("albedo", Buffer::Rgb(&a.data, ["R", "G", "B"])));
        }
        if let Some(n) = &self.normal {
            out.push(("normal", Buffer::Rgb(&n.data, ["X", "Y", "Z"])));
        }
        if let Some(d) = &self.depth {
            out.push(("depth", Buffer::Grey(d, "Z")));
        }
        out
    }

    /// The PFM files beside an image at `output` (`x.png` gives
    /// `x.albedo.pfm`...), with their bytes.
    pub fn pfm_files(&self, output: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        self.layers()
            .into_iter()
            .map(|(name, layer)| {
                let bytes = match layer {
                    Buffer::Rgb(data, _) => pfm(self.width, self.height, 3, data.iter().flatten()),
                    Buffer::Grey(data, _) => pfm(self.width, self.height, 1, data.iter()),
                };
                (beside(output, name), bytes)
            })
            .collect()
    }

    /// An EXR of `image` (channels R, G, B) with the buffers as layers
    /// (`albedo.R`..., `normal.X`..., `depth.Z`), 32-bit float, lossless.
    pub fn exr_bytes(&self, image: &Image) -> Vec<u8> {
        use exr::prelude::*;
        debug_assert_eq!((image.width, image.height), (self.width, self.height));
        let size = Vec2(self.width as usize, self.height as usize);
        let channel = |name: String, values: Vec<f32>| AnyChannel::new(name.as_str(), FlatSamples::F32(values));
        let rgb = |data: &[[f32; 3]], c: usize| data.iter().map(|p| p[c]).collect::<Vec<f32>>();
        let mut channels: Vec<AnyChannel<FlatSamples>> =
            (0..3).map(|c| channel(["R", "G", "B"][c].to_string(), rgb(&image.data, c))).collect();
        for (name, layer) in self.layers() {
            match layer {
                Buffer::Rgb(data, names) => {
                    (0..3).for_each(|c| channels.push(channel(format!("{name}.{}", names[c]), rgb(data, c))))
                }
                Buffer::Grey(data, n) => channels.push(channel(format!("{name}.{n}"), data.to_vec())),
            }
        }
        let layer = exr::image::Layer::new(
            size,
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(SmallVec::from_vec(channels)),
        );
        let mut out = std::io::Cursor::new(Vec::new());
        exr::image::Image::from_layer(layer).write().to_buffered(&mut out).expect("EXR encodes in memory");
        out.into_inner()
    }
}

/// One buffer's pixels and its channels' names.
enum Buffer<'a> {
    Rgb(&'a [[f32; 3]], [&'static str; 3]),
    Grey(&'a [f32], &'static str),
}

/// The file of buffer `name` beside the image `output`: `x.png` → `x.<name>.pfm`.
pub fn beside(output: &Path, name: &str) -> PathBuf {
    output.with_extension(format!("{name}.pfm"))
}

/// A portable float map of `channels` (3: `PF`, 1: `Pf`) values a pixel,
/// little-endian, rows bottom to top.
fn pfm<'a>(width: u32, height: u32, channels: usize, values: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    let magic = if channels == 3 { "PF" } else { "Pf" };
    let values: Vec<f32> = values.copied().collect();
    let row = width as usize * channels;
    let mut out = format!("{magic}\n{width} {height}\n-1.0\n").into_bytes();
    for y in (0..height as usize).rev() {
        values[y * row..(y + 1) * row].iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_and_bad_names_are_named() {
        let a = Aovs::parse("depth,albedo").unwrap();
        assert_eq!(a, Aovs { albedo: true, normal: false, depth: true });
        assert_eq!(a.names(), ["albedo", "depth"]);
        let e = Aovs::parse("albedo,normals").unwrap_err().to_string();
        assert!(e.contains("'normals'") && e.contains("did you mean 'normal'"), "{e}");
        assert!(Aovs::parse("depth,depth").unwrap_err().to_string().contains("twice"));
        assert!(Aovs::parse("").is_err());
    }

    #[test]
    fn files_sit_beside_the_image() {
        assert_eq!(beside(Path::new("out/final.png"), "albedo"), Path::new("out/final.albedo.pfm"));
        assert_eq!(beside(Path::new("x.pfm"), "depth"), Path::new("x.depth.pfm"));
    }

    #[test]
    fn a_grey_pfm_has_one_value_a_pixel_bottom_row_first() {
        let bytes = pfm(2, 2, 1, [1.0f32, 2.0, 3.0, 4.0].iter());
        let head = b"Pf\n2 2\n-1.0\n";
        assert_eq!(&bytes[..head.len()], head);
        let body: Vec<f32> = bytes[head.len()..].chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
        assert_eq!(body, [3.0, 4.0, 1.0, 2.0]);
    }
}
