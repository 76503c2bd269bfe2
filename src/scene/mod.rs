//! The user side of the bridge: what a scene file or a preset describes.
//!
//! These types are also the schema of scene files (JSON or TOML, see
//! `file.rs`), so a scene written by `rtow export` loads back into the
//! identical value. Loading parses (with bounded memory); [`Scene::validate`]
//! checks every value against the documented ranges, once, when a render
//! job is resolved from the scene (`crate::job`). Nothing here knows the
//! kernels: the job module reads this side and lays it out for them.

mod assignment;
pub(crate) mod de;
mod file;
mod flatten;
mod presets;
mod render_table;
#[cfg(feature = "schema")]
mod schema;
mod source;
mod suggest;
mod tessellate;
mod validate;

pub use crate::choice::Mode;
pub use assignment::{apply as apply_assignments, Assignment};
pub use file::{load_scene, save_meshes_obj, save_scene, scene_from_bytes, scene_from_str, scene_to_string, Format};
#[cfg(test)]
pub(crate) use flatten::FLATTENED;
pub use flatten::{box_quads, Flat, FlatBoundary, FlatInstance, FlatMedium, FlatMesh, FlatShared, Sharing};
pub use presets::{final_scene, preset, presets, Preset, PresetGroup};
pub use render_table::{BookTable, RenderTable};
#[cfg(feature = "schema")]
pub use schema::scene_schema;
pub use source::{nearest_preset, SceneSource};

use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Written as `{"type": "<kind>", ...fields}`. Read through `MaterialFields`:
/// serde reads an internally tagged enum through a buffer, and errors inside it
/// (`"ior": "abc"`) would name neither the field nor its position.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", try_from = "MaterialFields")]
#[cfg_attr(
    feature = "schema",
    derive(schemars::JsonSchema),
    schemars(!try_from, deny_unknown_fields, description = "A material: `type` and that type's fields.")
)]
pub enum Material {
    /// The albedo is a colour `[r, g, b]` or a texture ([`Texture`]).
    Lambertian {
        albedo: Texture,
    },
    Metal {
        albedo: [f32; 3],
        fuzz: f32,
    },
    Dielectric {
        ior: f32,
    },
    /// The Next Week's light: emits `emit` and ends the path. Two-sided (as
    /// The Next Week) unless `one_sided`, then only the front face (the side
    /// the primitive's normal points to: `u x v` for a quad, outwards for a
    /// sphere of positive radius) emits, as The Rest of Your Life.
    #[serde(rename = "diffuse_light")]
    DiffuseLight {
        emit: [f32; 3],
        #[serde(default, skip_serializing_if = "is_false")]
        one_sided: bool,
    },
}

/// A lambertian's albedo: a colour, written `[r, g, b]` (the book's
/// `solid_color`), or a texture written `{"type": "checker", "scale": s,
/// "even": [r, g, b], "odd": [r, g, b]}` (the book's 3-D spatial
/// `checker_texture` of two colours: the parity of the sum of
/// `floor(p / scale)` over the axes picks `even` or `odd`) or `{"type":
/// "noise", "scale": s}` (the book's `noise_texture`: Perlin marble,
/// `0.5 (1 + sin(scale z + 10 turb(p)))`) or `{"type": "image", "file":
/// "earthmap.jpg"}` (the book's `image_texture`: a PNG or JPEG file, its
/// nearest texel at the hit's (u, v), linearized as the book does; a
/// relative name is found beside the scene file, else in the folder
/// `RTOW_IMAGES` names: `crate::job::images`).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Solid([f32; 3]),
    Checker { scale: f32, even: [f32; 3], odd: [f32; 3] },
    Noise { scale: f32 },
    Image { file: String },
}

impl From<[f32; 3]> for Texture {
    fn from(c: [f32; 3]) -> Self {
        Texture::Solid(c)
    }
}

impl Texture {
    /// The texture's `type`, as scene files write it (`solid` for a colour).
    pub fn type_name(&self) -> &'static str {
        match self {
            Texture::Solid(_) => "solid",
            Texture::Checker { .. } => "checker",
            Texture::Noise { .. } => "noise",
            Texture::Image { .. } => "image",
        }
    }
}

impl Serialize for Texture {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        match self {
            Texture::Solid(c) => c.serialize(s),
            Texture::Checker { scale, even, odd } => {
                let mut m = s.serialize_struct("Texture", 4)?;
                m.serialize_field("type", "checker")?;
                m.serialize_field("scale", scale)?;
                m.serialize_field("even", even)?;
                m.serialize_field("odd", odd)?;
                m.end()
            }
            Texture::Noise { scale } => {
                let mut m = s.serialize_struct("Texture", 2)?;
                m.serialize_field("type", "noise")?;
                m.serialize_field("scale", scale)?;
                m.end()
            }
            Texture::Image { file } => {
                let mut m = s.serialize_struct("Texture", 2)?;
                m.serialize_field("type", "image")?;
                m.serialize_field("file", file)?;
                m.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for Texture {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        de::texture(d)
    }
}

/// A texture as a file writes it: every field of every kind, checked against
/// its `type` afterwards.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TextureFields {
    #[serde(rename = "type")]
    kind: TextureType,
    #[serde(default, deserialize_with = "de::opt_f32")]
    scale: Option<f32>,
    #[serde(default, deserialize_with = "de::opt_vec3")]
    even: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "de::opt_vec3")]
    odd: Option<[f32; 3]>,
    #[serde(default)]
    file: Option<String>,
}

/// A texture's `type` as files write it.
#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum TextureType {
    Checker,
    Noise,
    Image,
}

impl TryFrom<TextureFields> for Texture {
    type Error = String;
    fn try_from(t: TextureFields) -> std::result::Result<Self, String> {
        let need = |v: Option<[f32; 3]>, f: &str, name: &str| {
            v.ok_or_else(|| format!("missing field `{f}` for a {name} texture"))
        };
        let scale = |name: &str| t.scale.ok_or_else(|| format!("missing field `scale` for a {name} texture"));
        let kind = match t.kind {
            TextureType::Checker => "a checker",
            TextureType::Noise => "a noise",
            TextureType::Image => "an image",
        };
        let unknown =
            |f: &str, expected: &str| Err(format!("unknown field `{f}` for {kind} texture, expected {expected}"));
        match t.kind {
            TextureType::Image => match (t.scale.is_some(), t.even.is_some() || t.odd.is_some()) {
                (true, _) => unknown("scale", "`file`"),
                (_, true) => unknown(if t.even.is_some() { "even" } else { "odd" }, "`file`"),
                _ => Ok(Texture::Image { file: t.file.ok_or("missing field `file` for an image texture")? }),
            },
            _ if t.file.is_some() => unknown("file", "`scale`"),
            TextureType::Checker => Ok(Texture::Checker {
                scale: scale("checker")?,
                even: need(t.even, "even", "checker")?,
                odd: need(t.odd, "odd", "checker")?,
            }),
            TextureType::Noise => match (t.even.is_some(), t.odd.is_some()) {
                (false, false) => Ok(Texture::Noise { scale: scale("noise")? }),
                (true, _) => Err("unknown field `even` for a noise texture, expected `scale`".into()),
                (_, true) => Err("unknown field `odd` for a noise texture, expected `scale`".into()),
            },
        }
    }
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// A material as a file writes it: every field of every kind, checked against
/// its `type` afterwards.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialFields {
    #[serde(rename = "type")]
    kind: MaterialType,
    #[serde(default, deserialize_with = "de::opt_texture")]
    albedo: Option<Texture>,
    #[serde(default, deserialize_with = "de::opt_f32")]
    fuzz: Option<f32>,
    #[serde(default, deserialize_with = "de::opt_f32")]
    ior: Option<f32>,
    #[serde(default, deserialize_with = "de::opt_vec3")]
    emit: Option<[f32; 3]>,
    #[serde(default)]
    one_sided: Option<bool>,
}

impl TryFrom<MaterialFields> for Material {
    type Error = String;
    fn try_from(m: MaterialFields) -> std::result::Result<Self, String> {
        let name = m.kind.name();
        fn need<T>(v: Option<T>, field: &str, name: &str) -> std::result::Result<T, String> {
            v.ok_or_else(|| format!("missing field `{field}` for a {name} material"))
        }
        let present = [
            ("albedo", m.albedo.is_some()),
            ("fuzz", m.fuzz.is_some()),
            ("ior", m.ior.is_some()),
            ("emit", m.emit.is_some()),
            ("one_sided", m.one_sided.is_some()),
        ];
        let (material, fields) = match m.kind {
            MaterialType::Lambertian => {
                (Material::Lambertian { albedo: need(m.albedo, "albedo", name)? }, &["albedo"][..])
            }
            MaterialType::Metal => (
                Material::Metal {
                    albedo: match need(m.albedo, "albedo", name)? {
                        Texture::Solid(c) => c,
                        t => {
                            return Err(format!(
                                "a metal's `albedo` must be a colour [r, g, b], got a {} texture (textures are for lambertian materials)",
                                t.type_name()
                            ))
                        }
                    },
                    fuzz: need(m.fuzz, "fuzz", name)?,
                },
                &["albedo", "fuzz"][..],
            ),
            MaterialType::Dielectric => (Material::Dielectric { ior: need(m.ior, "ior", name)? }, &["ior"][..]),
            MaterialType::DiffuseLight => (
                Material::DiffuseLight { emit: need(m.emit, "emit", name)?, one_sided: m.one_sided.unwrap_or(false) },
                &["emit", "one_sided"][..],
            ),
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

/// A material's `type` as files write it.
#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum MaterialType {
    Lambertian,
    Metal,
    Dielectric,
    DiffuseLight,
}

impl MaterialType {
    fn name(self) -> &'static str {
        match self {
            MaterialType::Lambertian => "lambertian",
            MaterialType::Metal => "metal",
            MaterialType::Dielectric => "dielectric",
            MaterialType::DiffuseLight => "diffuse_light",
        }
    }
}

impl Material {
    /// The material's `type`, as scene files write it.
    pub fn type_name(&self) -> &'static str {
        match self {
            Material::Lambertian { .. } => "lambertian",
            Material::Metal { .. } => "metal",
            Material::Dielectric { .. } => "dielectric",
            Material::DiffuseLight { .. } => "diffuse_light",
        }
    }
}

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Sphere {
    /// The centre (at time 0, for a moving sphere).
    #[serde(deserialize_with = "de::vec3")]
    pub center: [f32; 3],
    /// A moving sphere's centre at time 1 (The Next Week's
    /// `sphere(center1, center2, r, mat)`): the centre at time `t` in [0, 1)
    /// is `center + t (center1 - center)`. Absent for a static sphere.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "de::opt_vec3")]
    pub center1: Option<[f32; 3]>,
    /// Signed: a negative radius is the book's hollow sphere (normal flipped inwards).
    #[serde(deserialize_with = "de::f32")]
    pub radius: f32,
    pub material: Material,
}

/// A parallelogram (The Next Week's `quad`): the points `q + a u + b v` for
/// `a, b` in [0, 1]. Its normal, and so its front face, is `u x v`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Quad {
    #[serde(deserialize_with = "de::vec3")]
    pub q: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    pub u: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    pub v: [f32; 3],
    pub material: Material,
}

/// A shape of a scene's `sample_toward` list, in world space: `{"type":
/// "quad", "q": .., "u": .., "v": ..}` or `{"type": "sphere", "center": ..,
/// "radius": ..}` (a static sphere; a negative radius is its size).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub enum Shape {
    Quad {
        #[serde(deserialize_with = "de::vec3")]
        q: [f32; 3],
        #[serde(deserialize_with = "de::vec3")]
        u: [f32; 3],
        #[serde(deserialize_with = "de::vec3")]
        v: [f32; 3],
    },
    Sphere {
        #[serde(deserialize_with = "de::vec3")]
        center: [f32; 3],
        #[serde(deserialize_with = "de::f32")]
        radius: f32,
    },
}

/// The Next Week's `box(a, b)`: the axis-aligned box with opposite corners
/// `a` and `b`, as its six quads (faces outwards, in the book's order).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct QuadBox {
    #[serde(deserialize_with = "de::vec3")]
    pub a: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    pub b: [f32; 3],
    pub material: Material,
}

/// The Next Week's `constant_medium`: a convex boundary filled with a medium
/// of constant `density` (per unit length) that scatters isotropically with
/// attenuation `albedo`. The boundary is no surface: it is invisible unless a
/// primitive is placed on it too (the book's subsurface sphere is a glass
/// sphere and a medium with the same boundary).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Medium {
    pub boundary: MediumBoundary,
    #[serde(deserialize_with = "de::f32")]
    pub density: f32,
    #[serde(deserialize_with = "de::vec3")]
    pub albedo: [f32; 3],
}

/// A medium's boundary, written `{"sphere": {"center": [x, y, z], "radius":
/// r}}` or `{"box": {"a": [x, y, z], "b": [x, y, z]}}` (the axis-aligned box of
/// corners `a`, `b`, turned and moved with its group): exactly one shape.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(rename_all = "lowercase", try_from = "BoundaryFields")]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema), schemars(!try_from, deny_unknown_fields))]
pub enum MediumBoundary {
    Sphere { center: [f32; 3], radius: f32 },
    Box { a: [f32; 3], b: [f32; 3] },
}

/// A medium's boundary as a file writes it: either shape, checked to be
/// exactly one afterwards (serde's enum would say "invalid type: map" of
/// a boundary that gives both, and "expected value" of one that gives none).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BoundaryFields {
    #[serde(default)]
    sphere: Option<BoundarySphere>,
    #[serde(default, rename = "box")]
    cuboid: Option<BoundaryBox>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoundarySphere {
    #[serde(deserialize_with = "de::vec3")]
    center: [f32; 3],
    #[serde(deserialize_with = "de::f32")]
    radius: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoundaryBox {
    #[serde(deserialize_with = "de::vec3")]
    a: [f32; 3],
    #[serde(deserialize_with = "de::vec3")]
    b: [f32; 3],
}

impl TryFrom<BoundaryFields> for MediumBoundary {
    type Error = &'static str;
    fn try_from(f: BoundaryFields) -> std::result::Result<Self, Self::Error> {
        match (f.sphere, f.cuboid) {
            (Some(s), None) => Ok(MediumBoundary::Sphere { center: s.center, radius: s.radius }),
            (None, Some(b)) => Ok(MediumBoundary::Box { a: b.a, b: b.b }),
            (Some(_), Some(_)) => Err("gives two shapes, a sphere and a box; a medium's boundary is one of them"),
            (None, None) => Err("gives no shape; a medium's boundary is {\"sphere\": {\"center\": [x, y, z], \
                                 \"radius\": r}} or {\"box\": {\"a\": [x, y, z], \"b\": [x, y, z]}}"),
        }
    }
}

/// A triangle mesh (past the books), with one material: `{"shape":
/// {"icosphere": {"center": [x, y, z], "radius": r, "level": n}},
/// "material": ..}` or `{"shape": {"obj": {"file": "bunny.obj", "scale":
/// s}}, "material": ..}`.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Mesh {
    pub shape: MeshShape,
    pub material: Material,
}

/// Where a mesh's triangles come from.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub enum MeshShape {
    /// The sphere `(center, radius)` as a closed icosphere of `20 4^level`
    /// triangles (`crate::mesh::icosphere`), its vertices on the sphere,
    /// wound outwards (inwards for a negative radius: the book's hollow
    /// sphere). Level 0 to [`crate::limits::MAX_ICOSPHERE_LEVEL`].
    Icosphere {
        #[serde(deserialize_with = "de::vec3")]
        center: [f32; 3],
        #[serde(deserialize_with = "de::f32")]
        radius: f32,
        level: u32,
    },
    /// The triangles of a Wavefront OBJ file (`crate::mesh::obj`'s rules),
    /// its positions multiplied by `scale` (default 1; positive) before a
    /// group turns and moves them. `file` is found as an image texture's
    /// file is, but without a folder of its own: an absolute path as it
    /// is, a relative one beside the scene file (or the partial film).
    /// Read once per job, however many meshes name it.
    Obj {
        file: String,
        #[serde(default = "one", deserialize_with = "de::f32", skip_serializing_if = "is_one")]
        scale: f32,
    },
}

fn one() -> f32 {
    1.0
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

impl MeshShape {
    /// The number of triangles known without reading a file: an icosphere's;
    /// 0 for an OBJ file (counted once the job reads it).
    pub fn generated_triangles(&self) -> u64 {
        match *self {
            MeshShape::Icosphere { level, .. } => 20u64 << (2 * level.min(31) as u64),
            MeshShape::Obj { .. } => 0,
        }
    }
}

/// The meshes of a scene's OBJ files, read (by the render job) before the
/// scene is flattened: one entry per distinct file, under every name the
/// scene gives it.
#[derive(Clone, Debug, Default)]
pub struct ObjMeshes {
    list: Vec<ObjMesh>,
    by_name: std::collections::HashMap<String, usize>,
}

/// One OBJ file's mesh: the name the scene gives it, the hash of its bytes,
/// its positions and its triangles (shared by every mesh that names it).
#[derive(Clone, Debug)]
pub struct ObjMesh {
    pub name: String,
    pub hash: u64,
    pub positions: Arc<Vec<[f32; 3]>>,
    pub triangles: Arc<Vec<[u32; 3]>>,
    /// A normal per position, when the file gives every vertex one
    /// (smooth shading); as the file writes them (not normalized).
    pub normals: Option<Arc<Vec<[f32; 3]>>>,
    /// The smallest box holding every position, `(min, max)`.
    pub bounds: ([f32; 3], [f32; 3]),
}

impl ObjMeshes {
    /// The mesh of the file a scene names `name`.
    pub fn get(&self, name: &str) -> Option<&ObjMesh> {
        self.by_name.get(name).map(|&k| &self.list[k])
    }

    /// Adds the mesh a scene names `mesh.name` (a name given again replaces
    /// nothing: the first stays).
    pub fn insert(&mut self, mesh: ObjMesh) {
        if !self.by_name.contains_key(&mesh.name) {
            self.by_name.insert(mesh.name.clone(), self.list.len());
            self.list.push(mesh);
        }
    }

    /// Every name with its mesh, in the order the names were added.
    pub fn iter(&self) -> impl Iterator<Item = &ObjMesh> {
        self.list.iter()
    }
}

/// Primitives under one transform, the book's instance order: first
/// `rotate_y` (degrees, about the y axis through the origin), then
/// `translate`. Flattened into world-space primitives when a render job is
/// prepared ([`Scene::flatten`]). Groups do not nest.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Group {
    #[serde(default, skip_serializing_if = "is_zero", deserialize_with = "de::f32")]
    pub rotate_y: f32,
    #[serde(default, skip_serializing_if = "is_default", deserialize_with = "de::vec3")]
    pub translate: [f32; 3],
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::spheres")]
    pub spheres: Vec<Sphere>,
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::quads")]
    pub quads: Vec<Quad>,
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::boxes")]
    pub boxes: Vec<QuadBox>,
    /// Constant media, their boundaries turned and moved with the group.
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::media")]
    pub media: Vec<Medium>,
    /// Triangle meshes, turned and moved with the group.
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::meshes")]
    pub meshes: Vec<Mesh>,
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

/// What a ray that leaves the scene sees: book one's sky gradient (the
/// scene's `sky` colours; the default), or one colour in every direction
/// (The Next Week's `background`, black for its lit scenes). Written as
/// `"sky"` or as a colour `[r, g, b]`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Background {
    #[default]
    Sky,
    Constant([f32; 3]),
}

impl Serialize for Background {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Background::Sky => s.serialize_str("sky"),
            Background::Constant(c) => c.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Background {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        de::background(d)
    }
}

fn default_vup() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_vfov() -> f32 {
    90.0
}

#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
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
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
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
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Scene {
    #[serde(default, skip_serializing_if = "is_default")]
    pub mode: Mode,
    pub camera: Camera,
    #[serde(default, deserialize_with = "de::spheres")]
    pub spheres: Vec<Sphere>,
    /// The Next Week's quads (world space).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::quads")]
    pub quads: Vec<Quad>,
    /// The Next Week's boxes (six quads each, world space).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::boxes")]
    pub boxes: Vec<QuadBox>,
    /// Instances: primitives under `rotate_y` then `translate`.
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::groups")]
    pub groups: Vec<Group>,
    /// The Next Week's constant media (world space).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::media")]
    pub media: Vec<Medium>,
    /// Triangle meshes (world space).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::meshes")]
    pub meshes: Vec<Mesh>,
    #[serde(default)]
    pub sky: Sky,
    /// What rays that leave the scene see (default: the sky gradient).
    #[serde(default, skip_serializing_if = "is_default")]
    pub background: Background,
    /// The shapes the `book` estimator samples directions toward (The Rest
    /// of Your Life's `lights` list: they need not emit, nor be in the
    /// world). Empty: the scene's lights (static spheres and quads of
    /// `diffuse_light`, groups' included).
    #[serde(default, skip_serializing_if = "Vec::is_empty", deserialize_with = "de::sample_toward")]
    pub sample_toward: Vec<Shape>,
    /// The render table: size, samples, depth, seed and sampler a scene asks
    /// for (overrides win; see `crate::job`).
    #[serde(default, skip_serializing_if = "is_default")]
    pub render: RenderTable,
}
