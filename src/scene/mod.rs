//! The user-facing scene: what a scene file or a preset describes, validated.
//!
//! This is also the schema of scene files (JSON or TOML, see `file.rs`), so a
//! scene written by `rtow export` loads back into the identical value.

pub(crate) mod de;
mod file;
mod presets;

pub use file::{load_scene, save_scene, scene_from_bytes, scene_from_str, scene_to_string, Format};
pub use presets::{final_scene, preset, presets, Preset};

use crate::error::{Error, Result};
use crate::limits::MAX_SPHERES;
pub use crate::material::Kind;
pub use crate::plan::Mode;
pub use crate::settings::RenderDefaults;
use serde::{Deserialize, Serialize};

/// Written as `{"type": "<kind>", ...fields}`. Read through [`MaterialFields`]:
/// serde reads an internally tagged enum through a buffer, and errors inside it
/// (`"ior": "abc"`) would name neither the field nor its position.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", try_from = "MaterialFields")]
pub enum Material {
    Lambertian { albedo: [f32; 3] },
    Metal { albedo: [f32; 3], fuzz: f32 },
    Dielectric { ior: f32 },
}

/// A material as a file writes it: every field of every kind, checked against
/// its `type` afterwards.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialFields {
    #[serde(rename = "type")]
    kind: Kind,
    #[serde(default, deserialize_with = "de::opt_vec3")]
    albedo: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "de::opt_f32")]
    fuzz: Option<f32>,
    #[serde(default, deserialize_with = "de::opt_f32")]
    ior: Option<f32>,
}

impl TryFrom<MaterialFields> for Material {
    type Error = String;
    fn try_from(m: MaterialFields) -> std::result::Result<Self, String> {
        let name = m.kind.name();
        fn need<T>(v: Option<T>, field: &str, name: &str) -> std::result::Result<T, String> {
            v.ok_or_else(|| format!("missing field `{field}` for a {name} material"))
        }
        let present = [("albedo", m.albedo.is_some()), ("fuzz", m.fuzz.is_some()), ("ior", m.ior.is_some())];
        let (material, fields) = match m.kind {
            Kind::Lambertian => (Material::Lambertian { albedo: need(m.albedo, "albedo", name)? }, &["albedo"][..]),
            Kind::Metal => (
                Material::Metal { albedo: need(m.albedo, "albedo", name)?, fuzz: need(m.fuzz, "fuzz", name)? },
                &["albedo", "fuzz"][..],
            ),
            Kind::Dielectric => (Material::Dielectric { ior: need(m.ior, "ior", name)? }, &["ior"][..]),
        };
        match present.iter().find(|(f, p)| *p && !fields.contains(f)) {
            Some((f, _)) => Err(format!(
                "unknown field `{f}` for a {name} material, expected {}",
                fields.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(" and ")
            )),
            None => Ok(material),
        }
    }
}

impl Material {
    pub fn kind(&self) -> Kind {
        match self {
            Material::Lambertian { .. } => Kind::Lambertian,
            Material::Metal { .. } => Kind::Metal,
            Material::Dielectric { .. } => Kind::Dielectric,
        }
    }
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    #[serde(deserialize_with = "de::vec3")]
    pub center: [f32; 3],
    /// Signed: a negative radius is the book's hollow sphere (normal flipped inwards).
    #[serde(deserialize_with = "de::f32")]
    pub radius: f32,
    pub material: Material,
}

fn default_vup() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_vfov() -> f32 {
    90.0
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    #[serde(deserialize_with = "de::vec3")]
    pub look_from: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    pub look_at: [f32; 3],
    #[serde(default = "default_vup", deserialize_with = "de::vec3")]
    pub vup: [f32; 3],
    #[serde(default = "default_vfov", deserialize_with = "de::f32")]
    pub vfov_deg: f32,
    /// Cone angle of the thin lens seen from the focus plane; 0 = pinhole.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_f32")]
    pub defocus_angle_deg: Option<f32>,
    /// The seed's lens diameter: `2 * focus_dist * tan(defocus_angle / 2)`. Either this
    /// or `defocus_angle_deg`, not both.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_f32")]
    pub aperture: Option<f32>,
    /// Distance to the plane in focus; defaults to |look_from - look_at|.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_f32")]
    pub focus_dist: Option<f32>,
}

impl Camera {
    pub fn looking(look_from: [f32; 3], look_at: [f32; 3], vfov_deg: f32) -> Self {
        Camera {
            look_from,
            look_at,
            vup: default_vup(),
            vfov_deg,
            defocus_angle_deg: None,
            aperture: None,
            focus_dist: None,
        }
    }

    pub fn focus_distance(&self) -> f64 {
        match self.focus_dist {
            Some(f) => f as f64,
            None => {
                let d: [f64; 3] = std::array::from_fn(|i| self.look_from[i] as f64 - self.look_at[i] as f64);
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            }
        }
    }

    /// The lens radius in world units (0 for a pinhole).
    pub fn lens_radius(&self) -> f64 {
        match (self.defocus_angle_deg, self.aperture) {
            (Some(a), _) => self.focus_distance() * (a as f64 / 2.0).to_radians().tan(),
            (None, Some(ap)) => ap as f64 / 2.0,
            (None, None) => 0.0,
        }
    }
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Sky {
    #[serde(deserialize_with = "de::vec3")]
    pub horizon: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    pub zenith: [f32; 3],
}

impl Default for Sky {
    fn default() -> Self {
        Sky { horizon: [1.0, 1.0, 1.0], zenith: [0.5, 0.7, 1.0] }
    }
}

impl Sky {
    pub fn uniform(c: [f32; 3]) -> Self {
        Sky { horizon: c, zenith: c }
    }
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default, skip_serializing_if = "is_default")]
    pub mode: Mode,
    pub camera: Camera,
    #[serde(default, deserialize_with = "de::spheres")]
    pub spheres: Vec<Sphere>,
    #[serde(default)]
    pub sky: Sky,
    #[serde(default, skip_serializing_if = "is_default")]
    pub render: RenderDefaults,
}

fn finite3(field: &str, v: [f32; 3]) -> Result<()> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("must be finite, got {v:?}")))
    }
}

fn finite(field: &str, v: f32) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("must be finite, got {v}")))
    }
}

/// A point of the world: finite and inside the range where the kernels'
/// error bounds hold ([`crate::limits::MAX_COORD`]).
fn point(field: &str, v: [f32; 3]) -> Result<()> {
    finite3(field, v)?;
    let m = crate::limits::MAX_COORD;
    if v.iter().any(|x| x.abs() > m) {
        return Err(Error::invalid(
            field,
            format!(
                "coordinates must be within [-{m:e}, {m:e}] (the range rtow's f32 kernels are verified in), got {v:?}"
            ),
        ));
    }
    Ok(())
}

fn colour(field: &str, v: [f32; 3]) -> Result<()> {
    finite3(field, v)?;
    if v.iter().any(|&x| x < 0.0) {
        return Err(Error::invalid(field, format!("colour components must be >= 0, got {v:?}")));
    }
    Ok(())
}

impl Scene {
    /// The focus distance and the lens, checked in f64 to be what the f32
    /// camera can represent: the camera's pixel grid (relative to the eye, at
    /// the focus distance) and its lens vectors must be finite and normal f32
    /// numbers whatever the image size (see [`crate::camera::Camera::check`]).
    fn check_lens(&self) -> Result<()> {
        use crate::limits::{MAX_FOCUS, MAX_LENS_RADIUS, MIN_FOCUS};
        let c = &self.camera;
        let focus = c.focus_distance();
        let field = if c.focus_dist.is_some() { "camera.focus_dist" } else { "camera.look_at" };
        if !(focus >= MIN_FOCUS as f64 && focus <= MAX_FOCUS as f64) {
            return Err(Error::invalid(
                field,
                format!(
                    "the focus distance{} must be in [{MIN_FOCUS:e}, {MAX_FOCUS:e}], got {focus:e}",
                    if c.focus_dist.is_some() { "" } else { " |look_from - look_at|" }
                ),
            ));
        }
        if c.vfov_deg < crate::limits::MIN_VFOV_DEG {
            return Err(Error::invalid(
                "camera.vfov_deg",
                format!(
                    "must be at least {:e} degrees for the f32 camera, got {}",
                    crate::limits::MIN_VFOV_DEG,
                    c.vfov_deg
                ),
            ));
        }
        let lr = c.lens_radius();
        if !(lr.is_finite() && lr <= MAX_LENS_RADIUS as f64) {
            let field = if c.aperture.is_some() { "camera.aperture" } else { "camera.defocus_angle_deg" };
            return Err(Error::invalid(
                field,
                format!("the lens radius must be at most {MAX_LENS_RADIUS:e}, got {lr:e}"),
            ));
        }
        crate::camera::Camera::check(c)
    }

    /// Checks every value a render depends on; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let c = &self.camera;
        point("camera.look_from", c.look_from)?;
        point("camera.look_at", c.look_at)?;
        finite3("camera.vup", c.vup)?;
        finite("camera.vfov_deg", c.vfov_deg)?;
        if self.mode != Mode::Gradient {
            if c.look_from == c.look_at {
                return Err(Error::invalid("camera.look_at", "must differ from camera.look_from"));
            }
            let w: [f64; 3] = std::array::from_fn(|i| c.look_from[i] as f64 - c.look_at[i] as f64);
            let up = glam::DVec3::from_array(c.vup.map(|x| x as f64));
            let wv = glam::DVec3::from_array(w);
            if up.length() == 0.0 {
                return Err(Error::invalid("camera.vup", "must not be zero"));
            }
            let sin = up.cross(wv).length() / (up.length() * wv.length());
            if !(sin > 1e-6) {
                return Err(Error::invalid("camera.vup", "must not be parallel to the view direction"));
            }
        }
        if !(c.vfov_deg > 0.0 && c.vfov_deg < 180.0) {
            return Err(Error::invalid("camera.vfov_deg", format!("must be in (0, 180), got {}", c.vfov_deg)));
        }
        if c.defocus_angle_deg.is_some() && c.aperture.is_some() {
            return Err(Error::invalid("camera.aperture", "give either aperture or defocus_angle_deg, not both"));
        }
        if let Some(a) = c.defocus_angle_deg {
            finite("camera.defocus_angle_deg", a)?;
            if !(0.0..180.0).contains(&a) {
                return Err(Error::invalid("camera.defocus_angle_deg", format!("must be in [0, 180), got {a}")));
            }
        }
        if let Some(a) = c.aperture {
            finite("camera.aperture", a)?;
            if a < 0.0 {
                return Err(Error::invalid("camera.aperture", format!("must be >= 0, got {a}")));
            }
        }
        if let Some(f) = c.focus_dist {
            finite("camera.focus_dist", f)?;
            if f <= 0.0 {
                return Err(Error::invalid("camera.focus_dist", format!("must be > 0, got {f}")));
            }
        }
        if self.mode != Mode::Gradient {
            self.check_lens()?;
        }
        self.render.validate()?;
        colour("sky.horizon", self.sky.horizon)?;
        colour("sky.zenith", self.sky.zenith)?;
        if self.spheres.len() > MAX_SPHERES {
            return Err(Error::invalid(
                "spheres",
                format!("at most {MAX_SPHERES} spheres, got {}", self.spheres.len()),
            ));
        }
        for (i, s) in self.spheres.iter().enumerate() {
            let f = |name: &str| format!("spheres[{i}].{name}");
            point(&f("center"), s.center)?;
            finite(&f("radius"), s.radius)?;
            if s.radius == 0.0 {
                return Err(Error::invalid(f("radius"), "must not be 0"));
            }
            let (lo, hi) = (crate::limits::MIN_RADIUS, crate::limits::MAX_RADIUS);
            if !(lo..=hi).contains(&s.radius.abs()) {
                return Err(Error::invalid(
                    f("radius"),
                    format!(
                        "|radius| must be in [{lo:e}, {hi:e}] (the range rtow's f32 kernels are verified in), got {}",
                        s.radius
                    ),
                ));
            }
            match s.material {
                Material::Lambertian { albedo } => colour(&f("material.albedo"), albedo)?,
                Material::Metal { albedo, fuzz } => {
                    colour(&f("material.albedo"), albedo)?;
                    finite(&f("material.fuzz"), fuzz)?;
                    if !(0.0..=1.0).contains(&fuzz) {
                        return Err(Error::invalid(f("material.fuzz"), format!("must be in [0, 1], got {fuzz}")));
                    }
                }
                Material::Dielectric { ior } => {
                    finite(&f("material.ior"), ior)?;
                    if ior <= 0.0 {
                        return Err(Error::invalid(f("material.ior"), format!("must be > 0, got {ior}")));
                    }
                }
            }
        }
        Ok(())
    }
}
