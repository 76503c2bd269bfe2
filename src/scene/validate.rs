//! Every value of a scene checked against the documented ranges
//! ([`crate::limits`]), in f64 where the check is about representability;
//! an error names the field. The kernels' own check (that the f32 camera is
//! computable at every image size) is the job module's, which runs both once.

use super::{
    Background, Camera, Group, Material, Medium, MediumBoundary, Mesh, MeshShape, Mode, ObjMeshes, Quad, QuadBox,
    Scene, Shape, Sphere, Texture,
};
use crate::error::{Error, Result};
use crate::limits::{self, MAX_ICOSPHERE_LEVEL, MAX_MEDIA, MAX_QUADS, MAX_SCENE_TRIANGLES, MAX_SPHERES};

/// What a non-finite value is: a number that overflowed f32 reads as an
/// infinity (JSON has no infinity literal, so there it always is one).
fn not_finite(v: f32) -> &'static str {
    if v.is_nan() {
        "must be a number, got nan"
    } else {
        "is too large for f32 (its magnitude must be below 3.4e38), or infinite"
    }
}

fn finite3(field: &str, v: [f32; 3]) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::invalid(format!("{field}[{i}]"), not_finite(v[i]))),
    }
}

fn finite(field: &str, v: f32) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(field, not_finite(v)))
    }
}

/// A point of the world: finite and inside the range where the kernels'
/// error bounds hold ([`crate::limits::MAX_COORD`]).
fn point(field: &str, v: [f32; 3]) -> Result<()> {
    finite3(field, v)?;
    let m = limits::MAX_COORD;
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
    /// Checks every value a render depends on; the error names the field.
    pub fn validate(&self) -> Result<()> {
        self.camera.validate(self.mode)?;
        self.render.validate()?;
        colour("sky.horizon", self.sky.horizon)?;
        colour("sky.zenith", self.sky.zenith)?;
        if self.spheres.len() > MAX_SPHERES {
            return Err(Error::invalid(
                "spheres",
                format!("at most {MAX_SPHERES} spheres, got {}", self.spheres.len()),
            ));
        }
        if let Background::Constant(c) = self.background {
            colour("background", c)?;
        }
        let (spheres, quads) = self.primitive_counts();
        if spheres > MAX_SPHERES {
            return Err(Error::invalid(
                "spheres",
                format!("at most {MAX_SPHERES} spheres (groups' included), got {spheres}"),
            ));
        }
        if quads > MAX_QUADS {
            return Err(Error::invalid(
                "quads",
                format!("at most {MAX_QUADS} quads (six per box, groups' included), got {quads}"),
            ));
        }
        let media = self.media_count();
        if media > MAX_MEDIA {
            return Err(Error::invalid("media", format!("at most {MAX_MEDIA} media (groups' included), got {media}")));
        }
        let triangles = self.generated_triangles();
        if triangles > MAX_SCENE_TRIANGLES {
            return Err(too_many_triangles(triangles));
        }
        members("", &self.spheres, &self.quads, &self.boxes)?;
        for (i, m) in self.meshes.iter().enumerate() {
            m.validate(&|name: &str| format!("meshes[{i}].{name}"))?;
        }
        for (i, m) in self.media.iter().enumerate() {
            m.validate(&|name: &str| format!("media[{i}].{name}"))?;
        }
        for (i, g) in self.groups.iter().enumerate() {
            g.validate(&format!("groups[{i}]"))?;
        }
        for (i, s) in self.sample_toward.iter().enumerate() {
            s.validate(&|name: &str| format!("sample_toward[{i}].{name}"))?;
        }
        Ok(())
    }
}

impl Shape {
    /// The limits of the primitive of the same shape (a quad's corners and
    /// edges, a sphere's centre and radius).
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        // The material is not the shape's: one that always validates.
        let material = Material::Dielectric { ior: 1.5 };
        match *self {
            Shape::Quad { q, u, v } => Quad { q, u, v, material }.validate(field),
            Shape::Sphere { center, radius } => Sphere { center, center1: None, radius, material }.validate(field),
        }
    }
}

/// The spheres, quads and boxes of a scene or of a group (`prefix`: "" or `groups[i].`).
fn members(prefix: &str, spheres: &[Sphere], quads: &[Quad], boxes: &[QuadBox]) -> Result<()> {
    for (i, s) in spheres.iter().enumerate() {
        s.validate(&|name: &str| format!("{prefix}spheres[{i}].{name}"))?;
    }
    for (i, q) in quads.iter().enumerate() {
        q.validate(&|name: &str| format!("{prefix}quads[{i}].{name}"))?;
    }
    for (i, b) in boxes.iter().enumerate() {
        b.validate(&|name: &str| format!("{prefix}boxes[{i}].{name}"))?;
    }
    Ok(())
}

impl Group {
    /// The transform and the members, then the members' world-space
    /// positions (within [`limits::MAX_COORD`] once moved).
    fn validate(&self, field: &str) -> Result<()> {
        finite(&format!("{field}.rotate_y"), self.rotate_y)?;
        point(&format!("{field}.translate"), self.translate)?;
        members(&format!("{field}."), &self.spheres, &self.quads, &self.boxes)?;
        for (i, m) in self.media.iter().enumerate() {
            m.validate(&|name: &str| format!("{field}.media[{i}].{name}"))?;
        }
        for (i, m) in self.meshes.iter().enumerate() {
            m.validate(&|name: &str| format!("{field}.meshes[{i}].{name}"))?;
            if let Some(reach) = super::flatten::mesh_reach(self, m) {
                if reach > limits::MAX_COORD as f64 {
                    return Err(too_far(format!("{field}.translate"), &format!("meshes[{i}] once moved"), reach));
                }
            }
        }
        let flat = super::flatten::group(self);
        for s in &flat.spheres {
            point(&format!("{field}.translate"), s.center)?;
            if let Some(c1) = s.center1 {
                point(&format!("{field}.translate"), c1)?;
            }
        }
        for m in &flat.media {
            if m.boundary.reach() > limits::MAX_COORD as f64 {
                return Err(Error::invalid(
                    format!("{field}.translate"),
                    format!(
                        "a medium once moved reaches {:e}, outside [-{m:e}, {m:e}] (the range rtow's f32 kernels are verified in)",
                        m.boundary.reach(),
                        m = limits::MAX_COORD
                    ),
                ));
            }
        }
        for q in &flat.quads {
            q.validate(&|name: &str| format!("{field} (a quad once moved).{name}"))?;
        }
        Ok(())
    }
}

/// The sine of the angle between `u` and `v` below which a quad is refused:
/// a sliver this thin is not a parallelogram the f32 hit test can resolve.
pub const MIN_QUAD_SINE: f64 = 1e-3;

impl Quad {
    /// The corner and edges: every corner within range, edges not zero and
    /// not parallel (their sine at least [`MIN_QUAD_SINE`]).
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        point(&field("q"), self.q)?;
        finite3(&field("u"), self.u)?;
        finite3(&field("v"), self.v)?;
        let d = |a: [f32; 3]| glam::DVec3::from_array(a.map(f64::from));
        let (q, u, v) = (d(self.q), d(self.u), d(self.v));
        for (name, c) in [("u", q + u), ("v", q + v), ("u", q + u + v)] {
            if c.abs().max_element() > limits::MAX_COORD as f64 {
                return Err(Error::invalid(
                    field(name),
                    format!(
                        "the quad's corner {:?} is outside [-{m:e}, {m:e}] (the range rtow's f32 kernels are verified in)",
                        c.to_array(),
                        m = limits::MAX_COORD
                    ),
                ));
            }
        }
        for (name, e) in [("u", u), ("v", v)] {
            if e.length() < limits::MIN_RADIUS as f64 {
                return Err(Error::invalid(
                    field(name),
                    format!("an edge must be at least {:e} long, got {:?}", limits::MIN_RADIUS, e.to_array()),
                ));
            }
        }
        let sine = u.cross(v).length() / (u.length() * v.length());
        if !(sine >= MIN_QUAD_SINE) {
            return Err(Error::invalid(
                field("v"),
                format!("u and v must not be parallel (the sine of their angle must be at least {MIN_QUAD_SINE:e}, got {sine:e})"),
            ));
        }
        self.material.validate(&|name: &str| field(&format!("material.{name}")))
    }
}

impl QuadBox {
    /// Both corners in range, and a positive size along every axis.
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        point(&field("a"), self.a)?;
        point(&field("b"), self.b)?;
        for axis in 0..3 {
            let size = (self.a[axis] as f64 - self.b[axis] as f64).abs();
            if size < limits::MIN_RADIUS as f64 {
                return Err(Error::invalid(
                    field("b"),
                    format!(
                        "a box must be at least {:e} in size along each axis, got {size:e} along {}",
                        limits::MIN_RADIUS,
                        ["x", "y", "z"][axis]
                    ),
                ));
            }
        }
        self.material.validate(&|name: &str| field(&format!("material.{name}")))
    }
}

impl Medium {
    /// The boundary (a sphere of positive radius, or a box of positive size,
    /// in range), a finite density `>= 0` and a colour.
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        match self.boundary {
            MediumBoundary::Sphere { center, radius } => {
                point(&field("boundary.sphere.center"), center)?;
                finite(&field("boundary.sphere.radius"), radius)?;
                if !(limits::MIN_RADIUS..=limits::MAX_RADIUS).contains(&radius) {
                    return Err(Error::invalid(
                        field("boundary.sphere.radius"),
                        format!(
                            "a medium's sphere must have a radius in [{:e}, {:e}], got {radius:e}",
                            limits::MIN_RADIUS,
                            limits::MAX_RADIUS
                        ),
                    ));
                }
                let reach = center.iter().fold(0.0f64, |m, &x| m.max((x as f64).abs())) + radius as f64;
                if reach > limits::MAX_COORD as f64 {
                    return Err(Error::invalid(
                        field("boundary.sphere.radius"),
                        format!(
                            "the sphere reaches {reach:e}, outside [-{m:e}, {m:e}] (the range rtow's f32 kernels are verified in)",
                            m = limits::MAX_COORD
                        ),
                    ));
                }
            }
            MediumBoundary::Box { a, b } => {
                point(&field("boundary.box.a"), a)?;
                point(&field("boundary.box.b"), b)?;
                for axis in 0..3 {
                    let size = (a[axis] as f64 - b[axis] as f64).abs();
                    if size < limits::MIN_RADIUS as f64 {
                        return Err(Error::invalid(
                            field("boundary.box.b"),
                            format!(
                                "a medium's box must be at least {:e} in size along each axis, got {size:e} along {}",
                                limits::MIN_RADIUS,
                                ["x", "y", "z"][axis]
                            ),
                        ));
                    }
                }
            }
        }
        finite(&field("density"), self.density)?;
        if self.density < 0.0 {
            return Err(Error::invalid(field("density"), format!("must be >= 0, got {}", self.density)));
        }
        colour(&field("albedo"), self.albedo)
    }
}

impl Camera {
    /// The camera's values; `mode` says whether rays are traced at all (the
    /// gradient needs no view).
    fn validate(&self, mode: Mode) -> Result<()> {
        point("camera.look_from", self.look_from)?;
        point("camera.look_at", self.look_at)?;
        finite3("camera.vup", self.vup)?;
        finite("camera.vfov_deg", self.vfov_deg)?;
        if mode != Mode::Gradient {
            self.validate_view()?;
        }
        if !(self.vfov_deg > 0.0 && self.vfov_deg < 180.0) {
            return Err(Error::invalid("camera.vfov_deg", format!("must be in (0, 180), got {}", self.vfov_deg)));
        }
        self.validate_lens_fields()?;
        if mode != Mode::Gradient {
            self.validate_lens()?;
        }
        Ok(())
    }

    /// A view direction, and an up vector not parallel to it.
    fn validate_view(&self) -> Result<()> {
        if self.look_from == self.look_at {
            return Err(Error::invalid("camera.look_at", "must differ from camera.look_from"));
        }
        let w: [f64; 3] = std::array::from_fn(|i| self.look_from[i] as f64 - self.look_at[i] as f64);
        let up = glam::DVec3::from_array(self.vup.map(|x| x as f64));
        let wv = glam::DVec3::from_array(w);
        if up.length() == 0.0 {
            return Err(Error::invalid("camera.vup", "must not be zero"));
        }
        let sin = up.cross(wv).length() / (up.length() * wv.length());
        if !(sin > 1e-6) {
            return Err(Error::invalid("camera.vup", "must not be parallel to the view direction"));
        }
        Ok(())
    }

    /// The lens fields one by one: at most one of aperture and defocus angle,
    /// each in range, and a positive focus distance.
    fn validate_lens_fields(&self) -> Result<()> {
        if self.defocus_angle_deg.is_some() && self.aperture.is_some() {
            return Err(Error::invalid("camera.aperture", "give either aperture or defocus_angle_deg, not both"));
        }
        if let Some(a) = self.defocus_angle_deg {
            finite("camera.defocus_angle_deg", a)?;
            if !(0.0..180.0).contains(&a) {
                return Err(Error::invalid("camera.defocus_angle_deg", format!("must be in [0, 180), got {a}")));
            }
        }
        if let Some(a) = self.aperture {
            finite("camera.aperture", a)?;
            if a < 0.0 {
                return Err(Error::invalid("camera.aperture", format!("must be >= 0, got {a}")));
            }
        }
        if let Some(f) = self.focus_dist {
            finite("camera.focus_dist", f)?;
            if f <= 0.0 {
                return Err(Error::invalid("camera.focus_dist", format!("must be > 0, got {f}")));
            }
        }
        Ok(())
    }

    /// The focus distance, field of view and lens radius together, in f64,
    /// within the ranges the f32 camera can represent.
    fn validate_lens(&self) -> Result<()> {
        use crate::limits::{MAX_FOCUS, MAX_LENS_RADIUS, MIN_FOCUS, MIN_VFOV_DEG};
        let focus = self.focus_distance();
        let field = if self.focus_dist.is_some() { "camera.focus_dist" } else { "camera.look_at" };
        if !(focus >= MIN_FOCUS as f64 && focus <= MAX_FOCUS as f64) {
            return Err(Error::invalid(
                field,
                format!(
                    "the focus distance{} must be in [{MIN_FOCUS:e}, {MAX_FOCUS:e}], got {focus:e}",
                    if self.focus_dist.is_some() { "" } else { " |look_from - look_at|" }
                ),
            ));
        }
        if self.vfov_deg < MIN_VFOV_DEG {
            return Err(Error::invalid(
                "camera.vfov_deg",
                format!("must be at least {MIN_VFOV_DEG:e} degrees for the f32 camera, got {}", self.vfov_deg),
            ));
        }
        let lr = self.lens_radius();
        if !(lr.is_finite() && lr <= MAX_LENS_RADIUS as f64) {
            let field = if self.aperture.is_some() { "camera.aperture" } else { "camera.defocus_angle_deg" };
            return Err(Error::invalid(
                field,
                format!("the lens radius must be at most {MAX_LENS_RADIUS:e}, got {lr:e}"),
            ));
        }
        Ok(())
    }
}

impl Mesh {
    /// The mesh's shape and material; `field` names one of them
    /// (`meshes[i].<name>`). An icosphere is held to a sphere's limits.
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        if let Material::Lambertian { albedo: Texture::Image { .. } } = self.material {
            return Err(Error::invalid(
                field("material.albedo"),
                "an image texture on a mesh is not supported (meshes carry no texture coordinates yet); give the \
                 mesh another albedo",
            ));
        }
        match self.shape {
            MeshShape::Icosphere { center, radius, level } => {
                if level > MAX_ICOSPHERE_LEVEL {
                    return Err(Error::invalid(
                        field("shape.icosphere.level"),
                        format!(
                            "must be at most {MAX_ICOSPHERE_LEVEL} ({} triangles), got {level}",
                            20u64 << (2 * MAX_ICOSPHERE_LEVEL)
                        ),
                    ));
                }
                let sphere = Sphere { center, center1: None, radius, material: self.material.clone() };
                sphere.validate(&|name: &str| {
                    if name.starts_with("material") {
                        field(name)
                    } else {
                        field(&format!("shape.icosphere.{name}"))
                    }
                })
            }
            MeshShape::Obj { ref file, scale } => {
                if file.is_empty() {
                    return Err(Error::invalid(field("shape.obj.file"), "must name an OBJ file, got an empty name"));
                }
                if file.len() > limits::MAX_PATH_BYTES || file.contains('\0') {
                    return Err(Error::invalid(
                        field("shape.obj.file"),
                        format!(
                            "must be a file name of at most {} bytes without NUL characters",
                            limits::MAX_PATH_BYTES
                        ),
                    ));
                }
                if !(scale > 0.0 && scale <= limits::MAX_COORD) {
                    return Err(Error::invalid(
                        field("shape.obj.scale"),
                        format!("must be positive and at most {:e}, got {scale}", limits::MAX_COORD),
                    ));
                }
                self.material.validate(&|name: &str| field(&format!("material.{name}")))
            }
        }
    }
}

impl Scene {
    /// The checks that need the scene's OBJ files read (`objs`, by the
    /// render job): every mesh within [`limits::MAX_COORD`] once scaled and
    /// moved, every mesh's triangles together at most
    /// [`MAX_SCENE_TRIANGLES`] (an instanced mesh's counted once) and the
    /// instances' triangles (each instance's counted) at most
    /// [`limits::MAX_INSTANCED_TRIANGLES`].
    pub fn validate_obj_meshes(&self, objs: &ObjMeshes) -> Result<()> {
        let mut triangles = self.generated_triangles();
        let sharing = super::Sharing::of(self, objs);
        let (mut held, mut instanced) = (std::collections::HashSet::new(), 0u64);
        for (g, i, m) in self.all_meshes() {
            let MeshShape::Obj { ref file, scale } = m.shape else { continue };
            let field = g.map_or_else(|| format!("meshes[{i}]"), |g| format!("groups[{g}].meshes[{i}]"));
            let Some(obj) = objs.get(file) else {
                return Err(Error::invalid(format!("{field}.shape.obj.file"), "was not read (a bug in rtow)"));
            };
            let shared = g.and_then(|_| sharing.shared(m, objs));
            if shared.is_none_or(|key| held.insert(key)) {
                triangles += obj.triangles.len() as u64;
            }
            if triangles > MAX_SCENE_TRIANGLES {
                return Err(too_many_triangles(triangles));
            }
            if shared.is_some() {
                instanced += obj.triangles.len() as u64;
                if instanced > limits::MAX_INSTANCED_TRIANGLES {
                    return Err(Error::invalid(
                        format!("{field}.shape.obj.file"),
                        format!(
                            "the groups place more than {} triangles of shared meshes, every placement counted \
                             (limits::MAX_INSTANCED_TRIANGLES)",
                            limits::MAX_INSTANCED_TRIANGLES
                        ),
                    ));
                }
            }
            let reach = super::flatten::obj_reach(g.map(|g| &self.groups[g]), scale, obj);
            if reach > limits::MAX_COORD as f64 {
                let (at, what) = match g {
                    Some(g) => (format!("groups[{g}].translate"), format!("meshes[{i}] once scaled and moved")),
                    None => (format!("{field}.shape.obj.scale"), "the mesh once scaled".to_string()),
                };
                return Err(too_far(at, &what, reach));
            }
        }
        Ok(())
    }
}

/// A scene with more than [`MAX_SCENE_TRIANGLES`] triangles (at least `n`).
fn too_many_triangles(n: u64) -> Error {
    Error::invalid(
        "meshes",
        format!("at most {MAX_SCENE_TRIANGLES} triangles (every mesh, groups' included), got {n} or more"),
    )
}

/// A mesh (`what`) that reaches `reach`, past [`limits::MAX_COORD`].
fn too_far(field: String, what: &str, reach: f64) -> Error {
    Error::invalid(
        field,
        format!(
            "{what} reaches {reach:e}, outside [-{m:e}, {m:e}] (the range rtow's f32 kernels are verified in)",
            m = limits::MAX_COORD
        ),
    )
}

impl Sphere {
    /// The sphere's values; `field` names one of them (`spheres[i].<name>`).
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        point(&field("center"), self.center)?;
        if let Some(c1) = self.center1 {
            point(&field("center1"), c1)?;
            if let Material::Lambertian { albedo: Texture::Image { .. } } = self.material {
                return Err(Error::invalid(
                    field("material.albedo"),
                    "an image texture on a moving sphere is not supported (its texture coordinates would need the \
                     path's time); give the sphere no center1, or another albedo",
                ));
            }
        }
        finite(&field("radius"), self.radius)?;
        if self.radius == 0.0 {
            return Err(Error::invalid(field("radius"), "must not be 0"));
        }
        let (lo, hi) = (limits::MIN_RADIUS, limits::MAX_RADIUS);
        if !(lo..=hi).contains(&self.radius.abs()) {
            return Err(Error::invalid(
                field("radius"),
                format!(
                    "|radius| must be in [{lo:e}, {hi:e}] (the range rtow's f32 kernels are verified in), got {}",
                    self.radius
                ),
            ));
        }
        self.material.validate(&|name: &str| field(&format!("material.{name}")))
    }
}

impl Texture {
    fn validate(&self, field: &str) -> Result<()> {
        let scale_in = |scale: f32, lo: f32, hi: f32| {
            let f = format!("{field}.scale");
            finite(&f, scale)?;
            if !(lo..=hi).contains(&scale) {
                return Err(Error::invalid(f, format!("must be in [{lo:e}, {hi:e}], got {scale}")));
            }
            Ok(())
        };
        match *self {
            Texture::Solid(c) => colour(field, c),
            Texture::Checker { scale, even, odd } => {
                scale_in(scale, limits::MIN_TEXTURE_SCALE, limits::MAX_TEXTURE_SCALE)?;
                colour(&format!("{field}.even"), even)?;
                colour(&format!("{field}.odd"), odd)
            }
            Texture::Noise { scale } => scale_in(scale, 0.0, limits::MAX_TEXTURE_SCALE),
            Texture::Image { ref file } => {
                let f = format!("{field}.file");
                if file.is_empty() {
                    return Err(Error::invalid(f, "must name an image file (PNG or JPEG), got an empty name"));
                }
                if file.len() > limits::MAX_PATH_BYTES || file.contains('\0') {
                    return Err(Error::invalid(
                        f,
                        format!(
                            "must be a file name of at most {} bytes without NUL characters",
                            limits::MAX_PATH_BYTES
                        ),
                    ));
                }
                Ok(())
            }
        }
    }
}

impl Material {
    fn validate(&self, field: &dyn Fn(&str) -> String) -> Result<()> {
        match *self {
            Material::Lambertian { ref albedo } => albedo.validate(&field("albedo")),
            Material::Metal { albedo, fuzz } => {
                colour(&field("albedo"), albedo)?;
                finite(&field("fuzz"), fuzz)?;
                if !(0.0..=1.0).contains(&fuzz) {
                    return Err(Error::invalid(field("fuzz"), format!("must be in [0, 1], got {fuzz}")));
                }
                Ok(())
            }
            Material::Dielectric { ior } => {
                finite(&field("ior"), ior)?;
                if ior <= 0.0 {
                    return Err(Error::invalid(field("ior"), format!("must be > 0, got {ior}")));
                }
                Ok(())
            }
            Material::DiffuseLight { emit, .. } => colour(&field("emit"), emit),
        }
    }
}
