//! Triangle meshes' sources (placeholder until the mesh-sources branch lands).
pub mod icosphere;
