//! `rtow bench --instructions`: instructions per ray of each kernel, counted
//! exactly by callgrind ([`super::callgrind`]), with saved baselines compared
//! exactly. The count does not depend on the machine's load, so this is the
//! cost a noisy CI can gate on, beside the image hash and the work counters.
//!
//! Each kernel is counted in a process of its own: the current executable,
//! re-run under `valgrind --tool=callgrind` with the job's settings and one
//! kernel (a caller says how, [`CountedProcess::child_args`]), which renders once
//! without writing an image ([`child_render`]) and prints what it rendered.
//! Its profile gives the render loop's instructions (every tile through its
//! kernel), the whole process's, and, in a build with the `phases` feature,
//! the render loop by phase. With the branch simulation (`--branch-sim`)
//! each of these also has its branches and mispredictions per ray.

use super::callgrind::{self, Cost, PhaseCount, Profile};
use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::job::{Job, RenderOptions};
use crate::kernel::Kernel;
use crate::provenance::Provenance;
use crate::render::render;
use crate::settings::Settings;
use serde::{Deserialize, Serialize};
use std::ffi::OsString;
use std::path::Path;

/// The value of [`InstructionsReport::schema`].
pub const INSTRUCTIONS_SCHEMA: &str = "rtow-instructions/1";

/// What a counted process rendered (the one line it prints).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChildRender {
    pub kernel: String,
    pub rays: u64,
    pub image_hash: String,
}

/// The counted process's work: `job` rendered once (no image written, no
/// counters); returns the line to print.
pub fn child_render(job: &Job) -> Result<String> {
    let r = render(job, None)?;
    r.stats.check_finite()?;
    let c = ChildRender { kernel: r.stats.kernel.to_string(), rays: r.stats.rays, image_hash: r.stats.image_hash };
    Ok(serde_json::to_string(&c).expect("serializes"))
}

/// One phase of the render loop, per ray.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseRow {
    pub phase: String,
    pub instructions: u64,
    pub per_ray: f64,
    /// Mispredicted branches per ray (with the branch simulation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mispredicts_per_ray: Option<f64>,
}

/// The branch simulation's counts of the render loop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Branches {
    /// Conditional and indirect branches executed.
    pub branches: u64,
    pub branches_per_ray: f64,
    /// Of those, mispredicted by callgrind's simulated predictor.
    pub mispredicts: u64,
    pub mispredicts_per_ray: f64,
}

/// One kernel's instructions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstructionsEntry {
    pub kernel: String,
    pub lanes: u32,
    pub rays: u64,
    pub image_hash: String,
    /// The render loop's instructions (every tile through its kernel): the
    /// figure baselines compare exactly.
    pub instructions: u64,
    pub per_ray: f64,
    /// Every instruction of the counted process (start-up, scene, BVH,
    /// render), for information.
    pub process_instructions: u64,
    pub process_per_ray: f64,
    /// The render loop by phase (a `phases` build's wavefront kernels only).
    pub phases: Option<Vec<PhaseRow>>,
    /// The render loop's branches and mispredictions (`--branch-sim` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branches: Option<Branches>,
    /// The command that was counted.
    pub command: Vec<String>,
}

/// What `rtow bench --instructions` measured (the JSON `--json` and `--save` write).
#[derive(Clone, Debug, Serialize)]
pub struct InstructionsReport {
    /// [`INSTRUCTIONS_SCHEMA`].
    pub schema: &'static str,
    pub scene: String,
    #[serde(flatten)]
    pub settings: Settings,
    pub threads: usize,
    /// `valgrind --version`.
    pub valgrind: String,
    pub kernels: Vec<InstructionsEntry>,
    pub provenance: Provenance,
    /// Why these counts are the baseline (`--save --reason`): one line kept
    /// with a committed baseline, e.g. what changed the counts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The longest [`InstructionsReport::reason`], in characters.
pub const MAX_REASON_CHARS: usize = 300;

/// Checks a baseline's reason: one line of text, not blank, at most
/// [`MAX_REASON_CHARS`] characters.
pub fn check_reason(reason: &str) -> Result<()> {
    if reason.trim().is_empty() {
        return Err(Error::invalid("--reason", "say in one line why these counts are the baseline"));
    }
    if reason.contains(['\n', '\r']) {
        return Err(Error::invalid("--reason", "one line: no line breaks"));
    }
    if reason.chars().count() > MAX_REASON_CHARS {
        return Err(Error::invalid("--reason", format!("at most {MAX_REASON_CHARS} characters, one line")));
    }
    Ok(())
}

/// How each kernel's counted process is run: the executable, its arguments
/// for a job, and callgrind's options.
pub struct CountedProcess<'a> {
    /// The executable re-run under callgrind (`rtow bench`: itself).
    pub program: &'a Path,
    /// Its arguments for a job of one kernel: a command that renders that job
    /// once and prints [`child_render`]'s line.
    pub child_args: &'a dyn Fn(&Job) -> Vec<OsString>,
    /// Also simulate the branch predictor (callgrind's `--branch-sim=yes`).
    pub branch_sim: bool,
}

/// Counts `kernels` on `job` (the scene `name`): each one's process is run as
/// `process` says, under callgrind; `on_kernel` sees each count as it is made.
pub fn count(
    job: &Job,
    name: &str,
    kernels: &[KernelChoice],
    process: &CountedProcess,
    mut on_kernel: impl FnMut(&InstructionsEntry),
) -> Result<InstructionsReport> {
    if kernels.is_empty() {
        return Err(Error::invalid("kernels", "name at least one kernel"));
    }
    let valgrind = callgrind::valgrind_version()?;
    let provenance = Provenance::collect();
    let mut entries = Vec::new();
    for &kernel in kernels {
        let job = job.with_options(&RenderOptions { kernel, ..*job.options() })?;
        let entry = count_kernel(&job, process)?;
        on_kernel(&entry);
        entries.push(entry);
    }
    Ok(InstructionsReport {
        schema: INSTRUCTIONS_SCHEMA,
        scene: name.to_string(),
        settings: *job.settings(),
        threads: job.threads(),
        valgrind,
        kernels: entries,
        provenance,
        reason: None,
    })
}

/// One kernel's count: `job` (of that kernel) rendered in a process of its
/// own under callgrind, its render loop, whole process, phases and branches per ray.
fn count_kernel(job: &Job, process: &CountedProcess) -> Result<InstructionsEntry> {
    let args = (process.child_args)(job);
    let (profile, stdout) = callgrind::count(process.program, &args, process.branch_sim)?;
    let child = counted_render(&stdout, job)?;
    let rays = child.rays as f64;
    let looped = profile.render_loop();
    let instructions = looped.instructions;
    if instructions == 0 {
        return Err(Error::System(format!(
            "the profile has no render loop ({} not found: a build without symbols?)",
            callgrind::RENDER_LOOP
        )));
    }
    let command = callgrind::command_line(process.program, &args, Path::new("callgrind.out"), process.branch_sim)
        .iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    Ok(InstructionsEntry {
        kernel: child.kernel,
        lanes: job.kernel().lanes(),
        rays: child.rays,
        image_hash: child.image_hash,
        instructions,
        per_ray: instructions as f64 / rays,
        process_instructions: profile.total,
        process_per_ray: profile.total as f64 / rays,
        phases: phase_rows(&profile, rays),
        branches: profile.branch_sim.then(|| Branches::per_ray(looped, rays)),
        command,
    })
}

/// What the counted process of `job` printed it rendered (its last line that
/// parses), checked: `job`'s kernel, and some rays.
fn counted_render(stdout: &str, job: &Job) -> Result<ChildRender> {
    let child: ChildRender = stdout
        .lines()
        .rev()
        .find_map(|l| serde_json::from_str(l).ok())
        .ok_or_else(|| Error::System(format!("the counted render printed no result: {stdout:?}")))?;
    if child.kernel != job.kernel().name() || child.rays == 0 {
        return Err(Error::System(format!(
            "the counted render ran the {} kernel for {} rays, not the {} kernel",
            child.kernel,
            child.rays,
            job.kernel().name()
        )));
    }
    Ok(child)
}

/// The render loop by phase, per ray of the `rays` traced (a `phases` build's
/// wavefront kernels only; mispredictions with the branch simulation).
fn phase_rows(profile: &Profile, rays: f64) -> Option<Vec<PhaseRow>> {
    profile.phases().map(|rows| {
        rows.into_iter()
            .map(|PhaseCount { phase, cost }| PhaseRow {
                phase,
                instructions: cost.instructions,
                per_ray: cost.instructions as f64 / rays,
                mispredicts_per_ray: profile.branch_sim.then(|| cost.mispredicts as f64 / rays),
            })
            .collect()
    })
}

impl Branches {
    /// The render loop's branch counts `looped`, and the same per ray of the `rays` traced.
    fn per_ray(looped: Cost, rays: f64) -> Branches {
        Branches {
            branches: looped.branches,
            branches_per_ray: looped.branches as f64 / rays,
            mispredicts: looped.mispredicts,
            mispredicts_per_ray: looped.mispredicts as f64 / rays,
        }
    }
}

impl InstructionsReport {
    /// The tables `rtow bench --instructions` prints: per kernel, then the phases.
    pub fn table(&self) -> String {
        let mut t = format!(
            "{:<7} {:>12} {:>16} {:>9} {:>12}  {}\n",
            "kernel", "rays", "instructions", "per ray", "process/ray", "image hash"
        );
        for e in &self.kernels {
            t += &format!(
                "{:<7} {:>12} {:>16} {:>9.2} {:>12.2}  {}\n",
                e.kernel, e.rays, e.instructions, e.per_ray, e.process_per_ray, e.image_hash
            );
        }
        t += "(instructions: the render loop, every tile through its kernel, counted by callgrind; process/ray: \
              every instruction of the process, start-up, scene and BVH included, per ray)\n";
        if self.kernels.iter().any(|e| e.branches.is_some()) {
            t +=
                &format!("\n{:<7} {:>14} {:>14} {:>12}\n", "kernel", "branches/ray", "mispredicts/ray", "mispredicted");
            for e in &self.kernels {
                if let Some(b) = &e.branches {
                    t += &format!(
                        "{:<7} {:>14.2} {:>14.3} {:>11.2}%\n",
                        e.kernel,
                        b.branches_per_ray,
                        b.mispredicts_per_ray,
                        100.0 * b.mispredicts as f64 / b.branches.max(1) as f64
                    );
                }
            }
            t += "(the render loop's conditional and indirect branches, callgrind's simulated predictor: it ranks \
                  changes; a real CPU predicts better)\n";
        }
        let with: Vec<&InstructionsEntry> = self.kernels.iter().filter(|e| e.phases.is_some()).collect();
        if let Some(first) = with.first() {
            t += &format!("\n{:<12}", "phase");
            for e in &with {
                t += &format!(" {:>16}", format!("{} /ray", e.kernel));
                if e.branches.is_some() {
                    t += &format!(" {:>8}", "mispr.");
                }
            }
            t += "\n";
            for (i, row) in first.phases.as_deref().unwrap_or_default().iter().enumerate() {
                t += &format!("{:<12}", row.phase);
                for e in &with {
                    let r = &e.phases.as_deref().unwrap_or_default()[i];
                    t += &format!(" {:>16}", format!("{:.1} ({:.0}%)", r.per_ray, 100.0 * r.per_ray / e.per_ray));
                    if let Some(m) = r.mispredicts_per_ray {
                        t += &format!(" {m:>8.3}");
                    }
                }
                t += "\n";
            }
            t += &format!("{:<12}", "render loop");
            for e in &with {
                t += &format!(" {:>16}", format!("{:.1}", e.per_ray));
                if let Some(b) = &e.branches {
                    t += &format!(" {:>8.3}", b.mispredicts_per_ray);
                }
            }
            t +=
                "\n(a `phases` build: the phases are kept out of line, which adds calls; compare phases with phases)\n";
        }
        t
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("report serializes") + "\n"
    }
}

/// What a saved instruction baseline must hold for each kernel.
#[derive(Clone, Debug, Deserialize)]
pub struct InstructionsBaselineEntry {
    pub kernel: String,
    pub rays: u64,
    pub image_hash: String,
    pub instructions: u64,
}

/// The build facts a count depends on.
#[derive(Clone, Debug, Deserialize)]
pub struct BaselineBuild {
    pub isa: String,
    pub features: Vec<String>,
    pub rustc: String,
}

/// A saved `rtow bench --instructions --save` report, as a comparison reads it.
#[derive(Clone, Debug, Deserialize)]
pub struct InstructionsBaseline {
    pub schema: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u64,
    pub sampler: String,
    /// The estimator (absent in baselines saved before there was a choice).
    #[serde(default)]
    pub estimator: Option<String>,
    pub threads: usize,
    pub kernels: Vec<InstructionsBaselineEntry>,
    pub provenance: BaselineBuild,
    /// Why these counts are the baseline (absent in baselines saved without `--reason`).
    #[serde(default)]
    pub reason: Option<String>,
}

impl InstructionsBaseline {
    pub fn load(path: &Path) -> Result<InstructionsBaseline> {
        let bytes = crate::limits::read_bounded(path, crate::limits::MAX_BASELINE_BYTES, "baseline")?;
        InstructionsBaseline::from_bytes(&bytes, path)
    }

    /// Parses an instruction baseline read from `path` and refuses impossible counts.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<InstructionsBaseline> {
        let parse = |m: String| Error::Parse { path: path.to_path_buf(), message: m };
        let schema: Option<String> = serde_json::from_slice::<serde_json::Value>(bytes)
            .ok()
            .and_then(|v| v.get("schema").and_then(|s| s.as_str()).map(str::to_string));
        if schema.as_deref() != Some(INSTRUCTIONS_SCHEMA) {
            return Err(parse(format!(
                "not an instruction baseline (schema {}): save one with `rtow bench --instructions --save`",
                schema.map_or("none".to_string(), |s| format!("'{}'", crate::output::clip(&s)))
            )));
        }
        let b: InstructionsBaseline = serde_json::from_slice(bytes).map_err(|e| {
            let text = e.to_string();
            let text = text.rsplit_once(" at line ").map_or(text.as_str(), |(t, _)| t);
            parse(format!("not an instruction baseline: {}", crate::output::clip_to(text, 160)))
        })?;
        for (i, k) in b.kernels.iter().enumerate() {
            let name = crate::output::clip(&k.kernel);
            if !["scalar", "simd8", "simd16"].contains(&k.kernel.as_str()) {
                return Err(parse(format!("kernels[{i}]: unknown kernel '{name}'")));
            }
            if b.kernels[..i].iter().any(|o| o.kernel == k.kernel) {
                return Err(parse(format!("kernel {name}: counted twice")));
            }
            if k.rays == 0 || k.instructions < k.rays {
                return Err(parse(format!(
                    "kernel {name}: {} instructions for {} rays is not a count",
                    k.instructions, k.rays
                )));
            }
            if k.image_hash.len() != 16 || !k.image_hash.bytes().all(|c| c.is_ascii_hexdigit()) {
                return Err(parse(format!(
                    "kernel {name}: '{}' is not an image hash",
                    crate::output::clip(&k.image_hash)
                )));
            }
        }
        if b.kernels.is_empty() {
            return Err(parse("the baseline has no kernel".into()));
        }
        Ok(b)
    }

    /// Checks, before anything is counted, that this baseline counted the
    /// same scene, settings and thread count, on a build of the same
    /// instruction set and features, and has one of `kernels`.
    pub fn check(&self, scene: &str, s: &Settings, threads: usize, kernels: &[KernelChoice]) -> Result<()> {
        let mine = Provenance::collect();
        let differs = |what: &str, theirs: &str, ours: &str| {
            Error::Input(format!("baseline {what} {} differs from this run's {ours}", crate::output::clip(theirs)))
        };
        if self.scene != scene {
            return Err(differs("scene", &self.scene, scene));
        }
        let theirs = format!(
            "{}x{} {} spp depth {} seed {} sampler {}",
            self.width, self.height, self.spp, self.max_depth, self.seed, self.sampler
        );
        let ours = format!(
            "{}x{} {} spp depth {} seed {} sampler {}",
            s.width,
            s.height,
            s.spp,
            s.max_depth,
            s.seed,
            s.sampler.name()
        );
        if theirs != ours {
            return Err(differs("settings", &theirs, &ours));
        }
        if let Some(e) = self.estimator.as_deref().filter(|&e| e != s.estimator.name()) {
            return Err(differs("estimator", e, s.estimator.name()));
        }
        if self.threads != threads {
            return Err(differs("thread count", &self.threads.to_string(), &threads.to_string()));
        }
        if self.provenance.isa != mine.isa {
            return Err(differs("instruction set", &self.provenance.isa, &mine.isa));
        }
        if self.provenance.features != mine.features {
            return Err(differs("features", &self.provenance.features.join(","), &mine.features.join(",")));
        }
        let names: Vec<&str> = kernels.iter().map(|&k| Kernel::resolve(k).name()).collect();
        if !self.kernels.iter().any(|b| names.contains(&b.kernel.as_str())) {
            return Err(Error::Input(format!("the baseline has none of the kernels counted ({})", names.join(", "))));
        }
        Ok(())
    }
}

/// One kernel against its instruction baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct InstructionsComparison {
    pub kernel: String,
    pub baseline: u64,
    pub instructions: u64,
    /// The most instructions that pass: the baseline's, plus the allowed rise.
    pub allowed: u64,
    pub baseline_per_ray: f64,
    pub per_ray: f64,
    pub image_same: bool,
    /// Exit status 1: the image changed or the count grew past `allowed`.
    pub regressed: bool,
}

/// Compares counts: a kernel regresses when its image changed or its count
/// rose by more than `max_rise_percent` of the baseline's (0: by one
/// instruction). A count rounds the allowance down: exact and the same on
/// every machine.
pub fn compare(
    report: &InstructionsReport,
    base: &InstructionsBaseline,
    max_rise_percent: f64,
) -> Vec<InstructionsComparison> {
    let mut out = Vec::new();
    for e in &report.kernels {
        let Some(b) = base.kernels.iter().find(|b| b.kernel == e.kernel) else { continue };
        let image_same = b.image_hash == e.image_hash && b.rays == e.rays;
        let allowed = b.instructions + allowance(b.instructions, max_rise_percent);
        out.push(InstructionsComparison {
            kernel: e.kernel.clone(),
            baseline: b.instructions,
            instructions: e.instructions,
            allowed,
            baseline_per_ray: b.instructions as f64 / b.rays as f64,
            per_ray: e.per_ray,
            image_same,
            regressed: !image_same || e.instructions > allowed,
        });
    }
    out
}

/// `percent` of `count`, rounded down (in millionths of a percent, so that
/// 0.5 means exactly five in a thousand).
fn allowance(count: u64, percent: f64) -> u64 {
    let micro = (percent * 1e6).round() as u128;
    (count as u128 * micro / 100_000_000) as u64
}

/// Checks `--max-rise`: a percentage from 0 to 100.
pub fn check_max_rise(percent: f64) -> Result<()> {
    if !(0.0..=100.0).contains(&percent) {
        return Err(Error::invalid("--max-rise", format!("{percent} is not a percentage from 0 to 100")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_allowance_is_exact_and_rounds_down() {
        assert_eq!(allowance(1_000, 0.5), 5);
        assert_eq!(allowance(1_999, 0.5), 9);
        assert_eq!(allowance(123_456_789, 0.0), 0);
        assert_eq!(allowance(709_827_165, 0.5), 3_549_135);
        assert_eq!(allowance(u64::MAX, 100.0), u64::MAX);
        assert!(check_max_rise(0.5).is_ok() && check_max_rise(-0.1).is_err() && check_max_rise(f64::NAN).is_err());
    }

    fn entry(kernel: &str, instructions: u64, image_hash: &str) -> InstructionsEntry {
        InstructionsEntry {
            kernel: kernel.into(),
            lanes: 8,
            rays: 1000,
            image_hash: image_hash.into(),
            instructions,
            per_ray: instructions as f64 / 1000.0,
            process_instructions: instructions + 1,
            process_per_ray: 0.0,
            phases: None,
            branches: None,
            command: Vec::new(),
        }
    }

    /// A count within the allowance passes, one instruction past it fails,
    /// and so does another image at any count.
    #[test]
    fn a_rise_past_the_allowance_or_another_image_regresses() {
        let report = |n: u64, hash: &str| InstructionsReport {
            schema: INSTRUCTIONS_SCHEMA,
            scene: "final".into(),
            settings: Settings::default(),
            threads: 1,
            valgrind: String::new(),
            kernels: vec![entry("simd8", n, hash)],
            provenance: Provenance::collect(),
            reason: None,
        };
        let mut saved = serde_json::to_value(report(200_000, "00000000000000aa")).unwrap();
        saved["reason"] = "test".into();
        let base = InstructionsBaseline::from_bytes(saved.to_string().as_bytes(), Path::new("b.json")).unwrap();
        assert_eq!(base.reason.as_deref(), Some("test"));
        let verdict = |n: u64, hash: &str, rise: f64| compare(&report(n, hash), &base, rise)[0].regressed;
        assert!(!verdict(200_000, "00000000000000aa", 0.0));
        assert!(verdict(200_001, "00000000000000aa", 0.0));
        assert!(!verdict(1, "00000000000000aa", 0.0));
        assert!(!verdict(201_000, "00000000000000aa", 0.5));
        assert!(verdict(201_001, "00000000000000aa", 0.5));
        assert!(verdict(200_000, "00000000000000ab", 0.5));
        assert_eq!(compare(&report(201_000, "00000000000000aa"), &base, 0.5)[0].allowed, 201_000);
    }

    #[test]
    fn a_reason_is_one_line() {
        assert!(check_reason("simd8: the walk's stack entry is 8 bytes smaller").is_ok());
        for bad in ["", "   ", "two\nlines", "a\r"] {
            assert!(check_reason(bad).is_err(), "{bad:?}");
        }
        assert!(check_reason(&"x".repeat(MAX_REASON_CHARS + 1)).is_err());
    }
}
