//! Where a figure comes from: which build (version, commit, compiler,
//! instruction set, lane width), on which machine (CPU model, cores), when
//! (UTC) and by which command. Every JSON rtow writes carries one
//! ([`Provenance::collect`]), so a statistics file alone says what was run,
//! on what and by which build (docs/figures.md states the schema).
//!
//! The build's facts are embedded at compile time by `build.rs`; the
//! machine's are read from the OS when a run starts.

use crate::kernel::{isa, HAS_SIMD16};
use serde::{Deserialize, Serialize};

/// The build, the machine, the time and the command of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The rtow version (`Cargo.toml`).
    pub rtow: String,
    /// The git commit the sources were built from (40 hex digits); `null`
    /// when the build did not come from a git checkout of rtow.
    pub commit: Option<String>,
    /// Whether the built sources had changes not in `commit` (`null`: unknown).
    pub modified: Option<bool>,
    /// The compiler, as `rustc -V` prints it.
    pub rustc: String,
    /// The target triple.
    pub target: String,
    /// The optimisation level and whether debug assertions were on (figures
    /// of a build with them on are not comparable with a release build's).
    pub opt_level: String,
    pub debug_assertions: bool,
    /// Cargo features that change what runs (`phases` keeps the wavefront's
    /// phases out of line: for profiling, not for timing).
    pub features: Vec<String>,
    /// The SIMD instruction set the build was compiled for ([`isa`]).
    pub isa: String,
    /// Lanes of the `simd` kernel in this build (8, or 16 with AVX-512).
    pub simd_lanes: u32,
    /// The CPU model the OS reports (`null` where it reports none).
    pub cpu: Option<String>,
    /// Logical cores of the machine, and those this process may run on
    /// (affinity, cgroup quota: a batch system's allocation).
    pub logical_cores: usize,
    pub available_cores: usize,
    pub os: String,
    /// When the run started, UTC, RFC 3339 (`2026-11-24T09:30:00Z`).
    pub date_utc: String,
    /// The process's command line, one argument per element.
    pub command_line: Vec<String>,
}

/// The git commit of this build, if known.
pub fn commit() -> Option<&'static str> {
    Some(env!("RTOW_BUILD_COMMIT")).filter(|c| !c.is_empty())
}

/// Whether the built sources differed from [`commit`] (`None`: unknown).
pub fn modified() -> Option<bool> {
    match env!("RTOW_BUILD_MODIFIED") {
        "true" => Some(true),
        "false" => Some(false),
        _ => None,
    }
}

/// The features of this build that change what runs.
pub fn features() -> Vec<String> {
    let mut f = Vec::new();
    if cfg!(feature = "cli") {
        f.push("cli".to_string());
    }
    if cfg!(feature = "phases") {
        f.push("phases".to_string());
    }
    f
}

/// `0.1.0 (commit 0123456789ab, modified)`: the version and commit, for `--version`.
pub fn version() -> String {
    let commit = match (commit(), modified()) {
        (Some(c), Some(true)) => format!("commit {}, modified", &c[..12.min(c.len())]),
        (Some(c), _) => format!("commit {}", &c[..12.min(c.len())]),
        (None, _) => "commit unknown".to_string(),
    };
    format!("{} ({commit})", env!("CARGO_PKG_VERSION"))
}

impl Provenance {
    /// This build, this machine, now, and this process's command line.
    pub fn collect() -> Provenance {
        let (cpu, logical) = cpu_info();
        let available = std::thread::available_parallelism().map_or(1, |n| n.get());
        Provenance {
            rtow: env!("CARGO_PKG_VERSION").to_string(),
            commit: commit().map(str::to_string),
            modified: modified(),
            rustc: env!("RTOW_BUILD_RUSTC").to_string(),
            target: env!("RTOW_BUILD_TARGET").to_string(),
            opt_level: env!("RTOW_BUILD_OPT_LEVEL").to_string(),
            debug_assertions: cfg!(debug_assertions),
            features: features(),
            isa: isa().to_string(),
            simd_lanes: if HAS_SIMD16 { 16 } else { 8 },
            cpu,
            logical_cores: logical.unwrap_or(available),
            available_cores: available,
            os: std::env::consts::OS.to_string(),
            date_utc: humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
            command_line: std::env::args_os().map(|a| a.to_string_lossy().into_owned()).collect(),
        }
    }
}

/// The CPU model and the number of logical cores, from `/proc/cpuinfo` (Linux).
fn cpu_info() -> (Option<String>, Option<usize>) {
    let Ok(text) = std::fs::read_to_string("/proc/cpuinfo") else { return (None, None) };
    parse_cpuinfo(&text)
}

fn parse_cpuinfo(text: &str) -> (Option<String>, Option<usize>) {
    let field = |line: &str, key: &str| -> Option<String> {
        let (k, v) = line.split_once(':')?;
        (k.trim() == key).then(|| v.trim().to_string())
    };
    let model = text.lines().find_map(|l| field(l, "model name").or_else(|| field(l, "Model")));
    let cores = text.lines().filter(|l| field(l, "processor").is_some()).count();
    (model.filter(|m| !m.is_empty()), (cores > 0).then_some(cores))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpuinfo_gives_the_model_and_the_logical_cores() {
        let text = "processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD EPYC 7B13\n\n\
                    processor\t: 1\nmodel name\t: AMD EPYC 7B13\n";
        assert_eq!(parse_cpuinfo(text), (Some("AMD EPYC 7B13".to_string()), Some(2)));
        assert_eq!(parse_cpuinfo(""), (None, None));
    }

    #[test]
    fn a_provenance_names_this_build_and_this_process() {
        let p = Provenance::collect();
        assert_eq!(p.rtow, env!("CARGO_PKG_VERSION"));
        assert!(p.rustc.starts_with("rustc "), "{}", p.rustc);
        assert_eq!(p.isa, isa());
        assert!(p.logical_cores >= 1 && p.available_cores >= 1);
        assert!(p.date_utc.ends_with('Z') && p.date_utc.len() == 20, "{}", p.date_utc);
        assert!(!p.command_line.is_empty());
        if let Some(c) = &p.commit {
            assert!(c.len() == 40 && c.bytes().all(|b| b.is_ascii_hexdigit()), "{c}");
        }
    }
}
