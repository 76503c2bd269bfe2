//! Spheres as triangle meshes: `--tessellate N` and the mesh presets turn
//! every static sphere of a scene (its groups' included) into a closed
//! icosphere of level `N` with the sphere's material (`MeshShape::Icosphere`,
//! vertex for vertex the definition of [`crate::mesh::icosphere`]); a
//! negative radius gives the inward-wound hollow shell. Moving spheres stay
//! spheres (a mesh does not move).

use super::{Mesh, MeshShape, Scene, Sphere};
use crate::error::{Error, Result};
use crate::limits::MAX_ICOSPHERE_LEVEL;

/// The static spheres of `spheres` as icospheres of `level`, appended to
/// `meshes` in order; the moving ones are kept.
fn spheres_to_meshes(spheres: &mut Vec<Sphere>, meshes: &mut Vec<Mesh>, level: u32) {
    let (moving, fixed): (Vec<Sphere>, Vec<Sphere>) = spheres.drain(..).partition(|s| s.center1.is_some());
    *spheres = moving;
    meshes.extend(fixed.into_iter().map(|s| Mesh {
        shape: MeshShape::Icosphere { center: s.center, radius: s.radius, level },
        material: s.material,
    }));
}

impl Scene {
    /// The scene with every static sphere as an icosphere of `level`
    /// (after the scene's own meshes, in sphere order; a group's in the
    /// group). The `sample_toward` list is kept: its spheres are shapes to
    /// sample, not primitives.
    pub fn tessellate(mut self, level: u32) -> Result<Scene> {
        if level > MAX_ICOSPHERE_LEVEL {
            return Err(Error::invalid(
                "--tessellate",
                format!(
                    "the icosphere level must be at most {MAX_ICOSPHERE_LEVEL} ({} triangles a sphere), got {level}",
                    20u64 << (2 * MAX_ICOSPHERE_LEVEL)
                ),
            ));
        }
        spheres_to_meshes(&mut self.spheres, &mut self.meshes, level);
        for g in &mut self.groups {
            spheres_to_meshes(&mut g.spheres, &mut g.meshes, level);
        }
        Ok(self)
    }
}
