use rtow::{Job, Overrides, RenderOptions};

fn main() -> rtow::Result<()> {
    let scene = rtow::scene::preset("final").expect("a built-in scene");
    // Or a file: rtow::scene::load_scene(Path::new("final.json"))?
    let overrides = Overrides { width: Some(64), height: Some(36), spp: Some(4), ..Default::default() };
    let job = Job::new(&scene, &overrides, &RenderOptions::default())?; // checks everything, once
    println!("{}", job.explain());
    let rendered = rtow::render(&job, None)?;
    let stats = &rendered.stats;
    println!("{} rays, {:.1} Mrays/s, {} kernel on {}", stats.rays, stats.mrays_per_s, stats.kernel, rtow::isa());
    let png: Vec<u8> = rendered.image.png_bytes(job.default_gamma()); // or image.save(path, gamma)
    assert!(!png.is_empty());
    Ok(())
}
