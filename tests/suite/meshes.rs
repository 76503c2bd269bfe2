//! OBJ meshes in scenes: found beside the scene file, read once, rendered
//! as the meshes they were written from, hashed into the render's identity,
//! exact under shards, merge and resume, and refused with a message that
//! names the field, the file and, for a fault in its text, the line.

use crate::common::{self, assert_identical, failure, rtow};
use rtow::scene::{self, Mesh, MeshShape, Scene, SceneSource};
use rtow::{render, Job, KernelChoice, Overrides, RenderOptions};
use std::path::Path;

/// `cornell-box-mesh` with its mesh read from `file` instead of generated.
fn obj_box(file: &str, scale: f32) -> Scene {
    let mut s = scene::preset("cornell-box-mesh").unwrap();
    assert_eq!(s.meshes.len(), 1);
    s.meshes[0].shape = MeshShape::Obj { file: file.into(), scale };
    s.render.width = Some(24);
    s.render.height = Some(24);
    s.render.samples_per_pixel = Some(2);
    s.render.max_depth = Some(6);
    s
}

/// Writes `scene` to `dir/name` and resolves its job as `rtow render` would.
fn job_of(dir: &Path, name: &str, scene: &Scene, kernel: KernelChoice) -> rtow::Result<Job> {
    let path = dir.join(name);
    scene::save_scene(scene, &path).unwrap();
    let src = SceneSource::open(path.to_str().unwrap())?;
    Job::from_source(&src, &Overrides::default(), &RenderOptions { kernel, ..Default::default() })
}

/// The exported mesh of `cornell-box-mesh` (its glass sphere at level 4) in `dir/name`.
fn export_box(dir: &Path, name: &str) {
    rtow(dir, &["export", "cornell-box-mesh", "-o", name]).ok();
}

/// An OBJ file written by `rtow export` holds every corner bit for bit, so
/// the scene that reads it renders the image of the scene it came from,
/// with every kernel.
#[test]
fn an_exported_mesh_read_back_renders_the_identical_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    export_box(d, "box.obj");
    let generated = {
        let mut s = scene::preset("cornell-box-mesh").unwrap();
        s.render = obj_box("box.obj", 1.0).render;
        common::job(&s, common::scene_settings(&s), RenderOptions::default())
    };
    let want = render(&generated, None).unwrap().image;
    for kernel in [KernelChoice::Scalar, KernelChoice::Simd8, KernelChoice::Simd16] {
        let job = job_of(d, "scene.json", &obj_box("box.obj", 1.0), kernel).unwrap();
        assert_identical(&want, &render(&job, None).unwrap().image, &format!("OBJ mesh, {kernel:?}"));
    }
    // Scaled, the mesh is another (smaller) sphere: another image.
    let half = job_of(d, "half.json", &obj_box("box.obj", 0.5), KernelChoice::Simd).unwrap();
    assert_ne!(render(&half, None).unwrap().image.data, want.data);
}

/// Relative names are found beside the scene file, not in the working
/// directory; a file named twice (two names, one file) is read once; its
/// bytes are part of the render's identity.
#[test]
fn obj_files_are_found_beside_the_scene_and_hashed_into_its_identity() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("scenes")).unwrap();
    export_box(&d.join("scenes"), "box.obj");
    let mut s = obj_box("box.obj", 1.0);
    let mut twice = s.meshes[0].clone();
    twice.shape = MeshShape::Obj { file: "./box.obj".into(), scale: 0.25 };
    s.meshes.push(twice);
    let job = job_of(&d.join("scenes"), "scene.json", &s, KernelChoice::Simd).unwrap();
    let meshes = job.identity().settings["meshes"].clone();
    let entries: Vec<&str> = meshes.split(", ").collect();
    assert_eq!(entries.len(), 2, "{meshes}");
    assert!(entries[0].ends_with(" box.obj") && entries[1].ends_with(" ./box.obj"), "{meshes}");
    assert_eq!(entries[0][..16], entries[1][..16], "one file, one hash: {meshes}");
    // From another folder, by the CLI.
    rtow(d, &["render", "scenes/scene.json", "-o", "a.png", "-q"]).ok();
    // Other bytes under the name: another identity.
    let key = job.identity().key();
    let mut text = std::fs::read_to_string(d.join("scenes/box.obj")).unwrap();
    text.push_str("# another file\n");
    std::fs::write(d.join("scenes/box.obj"), text).unwrap();
    let again = job_of(&d.join("scenes"), "scene.json", &s, KernelChoice::Simd).unwrap();
    assert_ne!(key, again.identity().key());
    // A scene without OBJ files has no `meshes` setting (identities made
    // before meshes stay the same).
    let plain = scene::preset("cornell-box-mesh").unwrap();
    let job = Job::new(&plain, &Overrides::default(), &RenderOptions::default()).unwrap();
    assert!(!job.identity().settings.contains_key("meshes"));
}

/// Shards of a scene with an OBJ mesh merge into the one-process image; a
/// merge or resume that finds other bytes under the file's name refuses,
/// naming the file.
#[test]
fn shards_with_obj_meshes_merge_and_are_verified_against_the_files_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    export_box(d, "box.obj");
    scene::save_scene(&obj_box("box.obj", 1.0), &d.join("scene.json")).unwrap();
    for k in 1..=2 {
        let part = format!("part-{k}.rtfilm");
        rtow(d, &["render", "scene.json", "--spp", "4", "--shard", &format!("{k}/2"), "-o", &part, "-q"]).ok();
    }
    rtow(d, &["merge", "part-1.rtfilm", "part-2.rtfilm", "-o", "merged.png", "-q"]).ok();
    rtow(d, &["render", "scene.json", "--spp", "4", "-o", "whole.png", "-q"]).ok();
    assert_eq!(std::fs::read(d.join("merged.png")).unwrap(), std::fs::read(d.join("whole.png")).unwrap());
    rtow(d, &["render", "scene.json", "--spp", "2", "-o", "half.rtfilm", "-q"]).ok();
    rtow(d, &["render", "scene.json", "--spp", "4", "--resume", "half.rtfilm", "-o", "resumed.png", "-q"]).ok();
    assert_eq!(std::fs::read(d.join("resumed.png")).unwrap(), std::fs::read(d.join("whole.png")).unwrap());
    // Another mesh under the name.
    std::fs::write(d.join("box.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let r = rtow(d, &["merge", "part-1.rtfilm", "part-2.rtfilm", "-o", "again.png", "-q"]);
    let e = failure(&r, 2, "merge with another OBJ file");
    assert!(
        e.contains("part-1.rtfilm: cannot render it again to verify it: the OBJ file 'box.obj' read now is not the one it was rendered with (its bytes hash to "),
        "{e}"
    );
    assert!(!d.join("again.png").exists());
    let r = rtow(d, &["render", "scene.json", "--spp", "4", "--resume", "half.rtfilm", "-o", "more.png", "-q"]);
    let e = failure(&r, 2, "resume with another OBJ file");
    assert!(
        e.contains("half.rtfilm: the OBJ file 'box.obj' of this render is not the one it was rendered with"),
        "{e}"
    );
}

/// Every way an OBJ mesh can be wrong is one line naming the field and the
/// file (and, for its text, the line), exit status 2, nothing written.
#[test]
fn bad_obj_meshes_are_refused_naming_field_and_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(d.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    std::fs::write(d.join("far.obj"), "v 0 0 0\nv 6e5 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::create_dir(d.join("folder.obj")).unwrap();
    let case = |name: &str, shape: MeshShape, grouped: bool, needles: &[&str]| {
        let mut s = obj_box("tri.obj", 1.0);
        let mesh = Mesh { shape, material: s.meshes[0].material.clone() };
        if grouped {
            s.meshes.clear();
            s.groups = vec![scene::Group { translate: [5e5, 0.0, 0.0], meshes: vec![mesh], ..Default::default() }];
        } else {
            s.meshes[0] = mesh;
        }
        let file = format!("{name}.json");
        scene::save_scene(&s, &d.join(&file)).unwrap();
        let r = rtow(d, &["render", &file, "-o", &format!("{name}.png"), "-q"]);
        let e = failure(&r, 2, name);
        for n in needles {
            assert!(e.contains(n), "{name}: {e:?} does not say {n:?}");
        }
        assert!(!d.join(format!("{name}.png")).exists(), "{name}");
    };
    let obj = |file: &str, scale: f32| MeshShape::Obj { file: file.into(), scale };
    case("missing", obj("none.obj", 1.0), false, &["meshes[0].shape.obj.file", "'none.obj'", "not found"]);
    case("line", obj("bad.obj", 1.0), false, &["meshes[0].shape.obj.file", "bad.obj: line 4", "position index 4"]);
    case("folder", obj("folder.obj", 1.0), false, &["'folder.obj'", "is a folder, not an OBJ file"]);
    case("empty", obj("", 1.0), false, &["meshes[0].shape.obj.file", "empty name"]);
    case("zero", obj("tri.obj", 0.0), false, &["meshes[0].shape.obj.scale", "must be positive"]);
    case("negative", obj("tri.obj", -1.0), false, &["meshes[0].shape.obj.scale", "must be positive"]);
    case("scaled", obj("far.obj", 2.0), false, &["meshes[0].shape.obj.scale", "reaches 1.2e6"]);
    case("moved", obj("far.obj", 1.0), true, &["groups[0].translate", "meshes[0] once scaled and moved", "1.1e6"]);
    // A scene without a file (the library's `Job::new`) names OBJ files by
    // absolute path.
    let e = Job::new(&obj_box("tri.obj", 1.0), &Overrides::default(), &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("is a relative name, and the scene has no file"), "{e}");
    let abs = d.join("tri.obj").to_str().unwrap().to_string();
    Job::new(&obj_box(&abs, 1.0), &Overrides::default(), &RenderOptions::default()).unwrap();
    // `rtow export -o F.obj` writes generated meshes only.
    let e = scene::save_meshes_obj(&obj_box(&abs, 1.0), &d.join("out.obj")).unwrap_err();
    assert!(e.to_string().contains("meshes[0].shape.obj.file: names an OBJ file"), "{e}");
}

/// `final-mesh` converges to `final` as the level rises: with the same
/// samples, the image of book one's final with every sphere an icosphere
/// of level `N` differs from the spheres' image less at every level (the
/// facets' distance from the sphere falls about fourfold a level).
#[test]
fn tessellated_final_converges_to_final_as_the_level_rises() {
    let fin = scene::preset("final").unwrap();
    let s = common::settings(64, 36, 4, 8, 1);
    let want = common::image(&fin, s, KernelChoice::Simd);
    let mse = |level: u32| {
        let got = common::image(&fin.clone().tessellate(level).unwrap(), s, KernelChoice::Simd);
        let sum: f64 = got
            .data
            .iter()
            .zip(&want.data)
            .map(|(a, b)| (0..3).map(|k| (a[k] as f64 - b[k] as f64).powi(2)).sum::<f64>())
            .sum();
        sum / (3 * want.data.len()) as f64
    };
    let errors: Vec<f64> = (0..=3).map(mse).collect();
    eprintln!("image MSE against the spheres, levels 0 to 3: {errors:?}");
    for (level, w) in errors.windows(2).enumerate() {
        assert!(w[1] < 0.8 * w[0], "level {} is not closer to the spheres than level {level}: {errors:?}", level + 1);
    }
    assert!(errors[3] < errors[0] / 8.0, "{errors:?}");
}

/// Once prepared, a triangle of `final-mesh` (622,080 of them, in one tree)
/// holds at most 100 bytes: its plane and mesh, and its share of the tree's
/// nodes and lanes, counted from the arrays' capacities. (The build's peak
/// is `tests/memory.rs`'s.)
#[test]
fn a_prepared_triangle_holds_at_most_100_bytes_with_its_tree() {
    let src = SceneSource::open("final-mesh").unwrap();
    let o = Overrides { width: Some(16), height: Some(9), spp: Some(1), ..Overrides::default() };
    let job = Job::from_source(&src, &o, &RenderOptions::default()).unwrap();
    let shapes = &job.prepared().shapes;
    let n = shapes.triangles.len();
    assert_eq!(n, 622_080);
    assert!(shapes.trees.triangles.is_some(), "final-mesh's triangles get a tree");
    let per = shapes.triangle_bytes() as f64 / n as f64;
    eprintln!("final-mesh: {per:.2} bytes a triangle once prepared, its tree included");
    assert!(per <= 100.0, "{per:.2} bytes a triangle");
    assert!(per >= 56.0 + 20.0, "{per:.2} bytes a triangle: fewer than its lanes and plane take");
}
