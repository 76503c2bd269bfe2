//! Instanced meshes in scenes: an OBJ mesh that several groups place is
//! held once and searched in its own frame, and the image is the image of
//! the same scene with every placement flattened (up to the rounding of
//! the move into the frame), the same bits from every kernel and width
//! under every estimator.

use crate::common::{assert_identical, rtow};
use rtow::internals::geometry::Primitive;
use rtow::scene::{self, Group, Material, Mesh, MeshShape, Scene, SceneSource};
use rtow::{render, EstimatorChoice, Job, KernelChoice, Overrides, RenderOptions};
use std::path::Path;

/// `cornell-box-mesh` without its glass sphere, and the OBJ meshes `files`
/// placed by three groups (turned, moved, each its own material).
fn placed(files: [&str; 3]) -> Scene {
    let mut s = scene::preset("cornell-box-mesh").unwrap();
    let glass = s.meshes.pop().unwrap().material;
    let materials = [
        glass,
        Material::Metal { albedo: [0.8, 0.6, 0.2], fuzz: 0.05 },
        Material::Lambertian { albedo: rtow::scene::Texture::Solid([0.2, 0.7, 0.3]) },
    ];
    let places = [(0.0, [100.0, 0.0, 200.0]), (30.0, [250.0, 150.0, 150.0]), (-75.0, [150.0, 230.0, 330.0])];
    for ((file, (rotate_y, translate)), material) in files.iter().zip(places).zip(materials) {
        s.groups.push(Group {
            rotate_y,
            translate,
            meshes: vec![Mesh { shape: MeshShape::Obj { file: file.to_string(), scale: 0.5 }, material }],
            ..Group::default()
        });
    }
    s.render.width = Some(40);
    s.render.height = Some(40);
    s.render.samples_per_pixel = Some(4);
    s.render.max_depth = Some(8);
    s
}

/// Writes `scene` to `dir/name` and resolves its job as `rtow render` would.
fn job_of(dir: &Path, name: &str, scene: &Scene, kernel: KernelChoice, estimator: EstimatorChoice) -> Job {
    let path = dir.join(name);
    scene::save_scene(scene, &path).unwrap();
    let src = SceneSource::open(path.to_str().unwrap()).unwrap();
    let overrides = Overrides { estimator: Some(estimator), ..Overrides::default() };
    Job::from_source(&src, &overrides, &RenderOptions { kernel, ..Default::default() }).unwrap()
}

/// Three placements of one file are instances of one shared mesh; three
/// copies of the file are three meshes, flattened. Both images agree but
/// for the rounding of the move into the mesh's frame (the last bits of
/// some pixels, and the rare path it sends elsewhere); the instanced image
/// is the same bits from every kernel.
#[test]
fn placements_of_one_mesh_are_instances_and_render_the_flattened_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rtow(d, &["export", "cornell-box-mesh", "-o", "box.obj"]).ok();
    for copy in ["box2.obj", "box3.obj"] {
        std::fs::copy(d.join("box.obj"), d.join(copy)).unwrap();
    }
    let shared = placed(["box.obj"; 3]);
    let copies = placed(["box.obj", "box2.obj", "box3.obj"]);
    for estimator in [EstimatorChoice::Bsdf, EstimatorChoice::Book, EstimatorChoice::NeeMis] {
        let flat = job_of(d, "copies.json", &copies, KernelChoice::Simd, estimator);
        assert_eq!((flat.plan().instances, flat.plan().shared_meshes), (0, 0));
        let flat = render(&flat, None).unwrap().image;
        let mut images = Vec::new();
        for kernel in [KernelChoice::Scalar, KernelChoice::Simd8, KernelChoice::Simd16] {
            let job = job_of(d, "shared.json", &shared, kernel, estimator);
            assert_eq!((job.plan().instances, job.plan().shared_meshes), (3, 1));
            images.push(render(&job, None).unwrap().image);
        }
        for (image, kernel) in images[1..].iter().zip(["simd8", "simd16"]) {
            assert_identical(&images[0], image, &format!("instances, {estimator:?}, {kernel} against scalar"));
        }
        // Two seeds of this render differ by an MSE of about 1e-2.
        let mse = rtow::instruments::converge::error_metrics(&images[0], &flat).mse;
        eprintln!("{estimator:?}: instanced against flattened, MSE {mse:e}");
        assert!(mse < 1e-6, "{estimator:?}: MSE {mse} against the flattened image");
    }
}

/// A shared mesh is held once: its triangles counted once toward the
/// scene's bound, its tree built once; a placement by one group alone, a
/// light or a mesh with vertex normals is flattened as before.
#[test]
fn only_meshes_placed_twice_flat_shaded_and_not_lights_are_shared() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rtow(d, &["export", "cornell-box-mesh", "-o", "box.obj"]).ok();
    let shared = placed(["box.obj"; 3]);
    let job = job_of(d, "a.json", &shared, KernelChoice::Simd, EstimatorChoice::Bsdf);
    assert_eq!(job.prepared().shapes.instances.count(), 3);
    assert_eq!(job.prepared().shapes.triangles.len(), 0, "no placement flattened");
    // One placement: flattened.
    let mut once = shared.clone();
    once.groups.truncate(once.groups.len() - 2);
    let job = job_of(d, "b.json", &once, KernelChoice::Simd, EstimatorChoice::Bsdf);
    assert_eq!(job.plan().instances, 0);
    // Lights are sampled in world space: flattened.
    let mut lights = shared.clone();
    for g in lights.groups.iter_mut().filter(|g| !g.meshes.is_empty()) {
        g.meshes[0].material = Material::DiffuseLight { emit: [4.0; 3], one_sided: false };
    }
    let job = job_of(d, "c.json", &lights, KernelChoice::Simd, EstimatorChoice::NeeMis);
    assert_eq!(job.plan().instances, 0);
}
