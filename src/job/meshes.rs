//! OBJ meshes' files: found, read (bounded) and parsed once per job, before
//! the scene is flattened.
//!
//! A scene names an OBJ file in a mesh (`{"shape": {"obj": {"file":
//! "bunny.obj"}}, ..}`). An absolute name is read as it is; a relative one
//! beside the scene file (for a partial film being merged or resumed,
//! beside the film), and nowhere else: a scene without a file (a preset, or
//! a library caller's scene) names its OBJ files by absolute path.
//!
//! Each distinct file (on Unix: device and inode) is read and parsed once,
//! whatever names and meshes lead to it, and its triangles are shared by
//! every mesh that names it. The files are read one after the other, the
//! triangles of those read so far held to [`MAX_SCENE_TRIANGLES`], so a
//! scene cannot make rtow hold more than one file's worth past the bound.
//!
//! Every refusal is exit status 2, naming the scene field that names the
//! file, the name, the path read and what is wrong: not found (and where it
//! was looked for), not a regular file, larger than
//! [`MAX_MESH_FILE_BYTES`], or a fault in its text (with the line:
//! `crate::mesh::obj`'s rules). The bytes of every file are hashed into the
//! job's identity (the setting `meshes`), as image textures' are.
//!
//! Vertex normals, when the file gives every vertex one, are kept: the
//! mesh is shaded smooth (`geometry::smooth`); else flat.

use crate::error::{Error, Result};
use crate::film::part::fnv1a;
use crate::input::{self, at, FileId, ReadError, Regular};
use crate::limits::{MAX_MESH_FILES, MAX_MESH_FILE_BYTES, MAX_SCENE_TRIANGLES};
use crate::scene::{ObjMesh, ObjMeshes, Scene};
use std::path::Path;
use std::sync::Arc;

/// Reads every OBJ file `scene` names; `origin` is the scene file (or the
/// partial film) beside which relative names are found.
pub(crate) fn load(scene: &Scene, origin: Option<&Path>) -> Result<ObjMeshes> {
    let names = scene.obj_file_fields();
    if names.len() > MAX_MESH_FILES {
        return Err(Error::invalid(
            &names[MAX_MESH_FILES].1,
            format!(
                "the scene names {} OBJ files; at most {MAX_MESH_FILES} are read (limits::MAX_MESH_FILES)",
                names.len()
            ),
        ));
    }
    let mut meshes = ObjMeshes::default();
    let mut read: Vec<(FileId, ObjMesh)> = Vec::new();
    let mut triangles = 0u64;
    for (name, field) in &names {
        let refuse =
            |what: String| Error::invalid(field, format!("OBJ file '{}' {what}", input::shown(Path::new(name))));
        let found = find(name, origin).map_err(refuse)?;
        if let Some((_, mesh)) = read.iter().find(|(id, _)| *id == found.id) {
            meshes.insert(ObjMesh { name: name.to_string(), ..mesh.clone() });
            continue;
        }
        let at = at(&found.path, name);
        let bytes = input::read_bounded(&found.file, &found.meta, MAX_MESH_FILE_BYTES).map_err(|e| {
            refuse(match e {
                ReadError::TooLarge(_) => format!(
                    "{at}is larger than {} MiB, the most an OBJ file may take (limits::MAX_MESH_FILE_BYTES)",
                    MAX_MESH_FILE_BYTES >> 20
                ),
                ReadError::Io(e) => format!("{at}cannot be read: {e}"),
            })
        })?;
        let mesh = crate::mesh::parse_obj(&bytes, &found.path).map_err(|e| Error::invalid(field, e.to_string()))?;
        triangles += mesh.triangles.len() as u64;
        if triangles > MAX_SCENE_TRIANGLES {
            return Err(refuse(format!(
                "{at}has {} triangles: with the OBJ files before it, more than the {MAX_SCENE_TRIANGLES} a scene may \
                 have (limits::MAX_SCENE_TRIANGLES)",
                mesh.triangles.len()
            )));
        }
        let bounds = mesh.bounds().expect("a parsed OBJ mesh has triangles, so positions");
        let obj = ObjMesh {
            name: name.to_string(),
            hash: fnv1a(&bytes),
            positions: Arc::new(mesh.positions),
            triangles: Arc::new(mesh.triangles),
            normals: mesh.normals.map(Arc::new),
            bounds,
        };
        meshes.insert(obj.clone());
        read.push((found.id, obj));
    }
    Ok(meshes)
}

/// The file a scene's OBJ `name` is: itself if absolute, else beside
/// `origin`. Refused (a message that follows the name) when nothing is
/// there or what is there is not a regular file.
fn find(name: &str, origin: Option<&Path>) -> std::result::Result<Regular, String> {
    let given = Path::new(name);
    let path = if given.is_absolute() {
        given.to_path_buf()
    } else {
        let Some(origin) = origin else {
            return Err("is a relative name, and the scene has no file to find it beside: name it by its absolute \
                        path"
                .into());
        };
        origin.parent().unwrap_or(Path::new("")).join(given)
    };
    let not_a_file = "not an OBJ file";
    match input::open_regular(&path) {
        Ok(Some(found)) => Ok(found),
        Ok(None) => Err(format!("{}is not found: no such file", at(&path, name))),
        Err(u) => Err(format!("{}{}", at(&path, name), u.describe(not_a_file))),
    }
}
