//! Instructions, counted exactly: a process run under valgrind's callgrind
//! and its profile read back (`rtow bench --instructions`).
//!
//! Callgrind counts every instruction the process executes, whatever the
//! machine's load, so a count is the same from run to run (the render loop's
//! exactly; the whole process's within a few thousand instructions of
//! start-up). The render loop is the instructions spent inside
//! `rtow::render::tile_work` (every tile through its kernel: camera rays,
//! traversal, scatter, film); the rest of the process (start-up, scene, BVH,
//! output) is counted apart. A build with the `phases` feature keeps the
//! wavefront's phases out of line, and the profile attributes the render
//! loop to them ([`PHASES`]).
//!
//! The profile is callgrind's own output format (`callgrind_annotate` reads
//! the same files): per function, its own cost and the inclusive cost of
//! each call it makes. With `--branch-sim=yes` ([`command_line`]'s
//! `branch_sim`) callgrind also simulates a branch predictor and counts, per
//! function, the conditional and indirect branches executed (`Bc`, `Bi`) and
//! mispredicted (`Bcm`, `Bim`): a deterministic stand-in for the
//! mispredictions a real CPU suffers (its predictor is better, so the counts
//! rank changes rather than predict cycles).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::Path;
use std::process::Command;

/// The function whose inclusive cost is the render loop (see `render.rs`).
pub const RENDER_LOOP: &str = "rtow::render::tile_work";

/// The phases of the wavefront kernel and the functions that are each one
/// (out of line in a `phases` build). A phase's instructions are those of
/// its functions and their callees, less what they spend in another phase
/// (scatter calls compaction). "rest" is the render loop less the phases.
pub const PHASES: &[(&str, &[&str])] = &[
    ("traversal", &["rtow::geometry::shapes::Shapes::closest"]),
    ("scatter", &["rtow::kernel::wavefront::scatter"]),
    ("camera rays", &["rtow::kernel::wavefront::generate"]),
    ("film", &["rtow::film::TileFilm::add", "rtow::film::TileFilm::add_rounds"]),
    ("compaction", &["rtow::kernel::wavefront::Paths::append"]),
];

/// What callgrind counted for a piece of code: instructions and, with the
/// branch simulation, branches executed and mispredicted (conditional and
/// indirect together; 0 without it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Cost {
    pub instructions: u64,
    pub branches: u64,
    pub mispredicts: u64,
}

impl std::ops::Add for Cost {
    type Output = Cost;
    fn add(self, o: Cost) -> Cost {
        Cost {
            instructions: self.instructions + o.instructions,
            branches: self.branches + o.branches,
            mispredicts: self.mispredicts + o.mispredicts,
        }
    }
}

impl std::ops::Sub for Cost {
    type Output = Cost;
    /// Saturating: a part never costs more than its whole.
    fn sub(self, o: Cost) -> Cost {
        Cost {
            instructions: self.instructions.saturating_sub(o.instructions),
            branches: self.branches.saturating_sub(o.branches),
            mispredicts: self.mispredicts.saturating_sub(o.mispredicts),
        }
    }
}

impl std::iter::Sum for Cost {
    fn sum<I: Iterator<Item = Cost>>(it: I) -> Cost {
        it.fold(Cost::default(), |a, b| a + b)
    }
}

/// One phase's cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseCount {
    pub phase: String,
    pub cost: Cost,
}

/// A function's own cost and the inclusive cost of the calls it makes.
#[derive(Clone, Debug, Default)]
struct Function {
    own: Cost,
    calls: BTreeMap<String, Cost>,
}

/// Where each counted event sits on a cost line (after the positions).
#[derive(Clone, Copy, Debug)]
struct Events {
    ir: usize,
    /// `Bc`, `Bcm`, `Bi`, `Bim`: present with `--branch-sim=yes`.
    branches: Option<[usize; 4]>,
}

impl Events {
    fn parse(line: &str) -> Option<Events> {
        let names: Vec<&str> = line.split_whitespace().collect();
        let at = |e: &str| names.iter().position(|&n| n == e);
        let branches = match (at("Bc"), at("Bcm"), at("Bi"), at("Bim")) {
            (Some(a), Some(b), Some(c), Some(d)) => Some([a, b, c, d]),
            _ => None,
        };
        Some(Events { ir: at("Ir")?, branches })
    }

    /// The cost of the numbers `v` (missing trailing numbers are zero).
    fn cost(&self, v: &[u64]) -> Cost {
        let get = |i: usize| v.get(i).copied().unwrap_or(0);
        let (branches, mispredicts) = match self.branches {
            Some([bc, bcm, bi, bim]) => (get(bc) + get(bi), get(bcm) + get(bim)),
            None => (0, 0),
        };
        Cost { instructions: get(self.ir), branches, mispredicts }
    }
}

/// A callgrind profile: the total and the cost of every function.
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// Every instruction of the process.
    pub total: u64,
    /// Whether the profile has the branch simulation's counts.
    pub branch_sim: bool,
    functions: BTreeMap<String, Function>,
}

/// Whether the function `name` (as callgrind writes it) is `path`: the path,
/// (an impl's `<Type>::` read as `Type::`), followed by nothing, a generic
/// list, a recursion mark or a hash.
fn is(name: &str, path: &str) -> bool {
    // `<rtow::film::TileFilm>::add` (an impl's path) reads as `rtow::film::TileFilm::add`.
    let plain = match name.strip_prefix('<') {
        Some(rest) => rest.replacen(">::", "::", 1),
        None => name.to_string(),
    };
    plain.strip_prefix(path).is_some_and(|rest| rest.is_empty() || rest.starts_with("::") || rest.starts_with('\''))
}

impl Profile {
    /// Parses callgrind's output format (`events:` with `Ir` and, from a
    /// branch simulation, `Bc Bcm Bi Bim`; any `positions:`, name compression).
    pub fn parse(text: &str) -> std::result::Result<Profile, String> {
        let mut p = Profile::default();
        let mut names: BTreeMap<String, String> = BTreeMap::new();
        let mut positions = 1usize;
        let mut events: Option<Events> = None;
        let mut current = String::new();
        let mut callee: Option<String> = None;
        let mut call_pending = false;
        let mut total: Option<u64> = None;
        // `(id) name` defines id; `(id)` refers to it.
        let mut name_of = |spec: &str| -> String {
            let spec = spec.trim();
            match spec.strip_prefix('(').and_then(|r| r.split_once(')')) {
                Some((id, rest)) if !rest.trim().is_empty() => {
                    names.insert(id.to_string(), rest.trim().to_string());
                    rest.trim().to_string()
                }
                Some((id, _)) => names.get(id).cloned().unwrap_or_default(),
                None => spec.to_string(),
            }
        };
        for (n, line) in text.lines().enumerate() {
            let bad = |m: &str| format!("callgrind output, line {}: {m}", n + 1);
            if let Some(v) = line.strip_prefix("positions:") {
                positions = v.split_whitespace().count().max(1);
            } else if let Some(v) = line.strip_prefix("events:") {
                events = Events::parse(v);
                match events {
                    None => return Err(bad("no Ir event")),
                    Some(e) => p.branch_sim = e.branches.is_some(),
                }
            } else if let Some(v) = line.strip_prefix("fn=") {
                current = name_of(v);
                p.functions.entry(current.clone()).or_default();
            } else if let Some(v) = line.strip_prefix("cfn=") {
                callee = Some(name_of(v));
            } else if line.starts_with("calls=") {
                call_pending = true;
            } else if let Some(v) = line.strip_prefix("summary:").or_else(|| line.strip_prefix("totals:")) {
                let e = events.ok_or_else(|| bad("a total before the events line"))?;
                let v: Vec<u64> = v
                    .split_whitespace()
                    .map(|x| x.parse::<u64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| bad("total"))?;
                let t = e.cost(&v).instructions;
                total = Some(total.map_or(t, |s: u64| s.max(t)));
            } else if line.starts_with(|c: char| c.is_ascii_digit() || c == '+' || c == '-' || c == '*') {
                let e = events.ok_or_else(|| bad("a cost before the events line"))?;
                let v: Vec<u64> = line
                    .split_whitespace()
                    .skip(positions)
                    .map(|x| x.parse::<u64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| bad("cost"))?;
                let cost = e.cost(&v);
                let f = p.functions.entry(current.clone()).or_default();
                if call_pending {
                    let c = f.calls.entry(callee.clone().unwrap_or_default()).or_default();
                    *c = *c + cost;
                    call_pending = false;
                } else {
                    f.own = f.own + cost;
                }
            } else if let Some(v) = line.strip_prefix("fl=").or_else(|| line.strip_prefix("fi=")) {
                let _ = v; // file names: not needed (costs are summed per function)
            }
        }
        p.total = match total {
            Some(t) => t,
            None => p.functions.values().map(|f| f.own.instructions).sum(),
        };
        if events.is_none() {
            return Err("not a callgrind profile (no events line)".into());
        }
        Ok(p)
    }

    /// The cost of the functions that are `path` and their callees (a call
    /// between two of them is counted once).
    pub fn inclusive(&self, path: &str) -> Cost {
        self.functions
            .iter()
            .filter(|(name, _)| is(name, path))
            .map(|(_, f)| f.own + f.calls.iter().filter(|(c, _)| !is(c, path)).map(|(_, &x)| x).sum::<Cost>())
            .sum()
    }

    /// The render loop's cost ([`RENDER_LOOP`]).
    pub fn render_loop(&self) -> Cost {
        self.inclusive(RENDER_LOOP)
    }

    /// The render loop by phase, "rest" last; `None` when the traversal is
    /// not out of line in the profile (not a `phases` build, or the scalar kernel).
    pub fn phases(&self) -> Option<Vec<PhaseCount>> {
        let in_phase = |name: &str| PHASES.iter().position(|(_, fs)| fs.iter().any(|f| is(name, f)));
        let mut counts = vec![Cost::default(); PHASES.len()];
        let mut seen = vec![false; PHASES.len()];
        for (name, f) in &self.functions {
            let Some(i) = in_phase(name) else { continue };
            seen[i] = true;
            // Its own cost and its calls, less calls into another phase's functions.
            let into_other = |c: &str| in_phase(c).is_some_and(|j| j != i);
            counts[i] =
                counts[i] + f.own + f.calls.iter().filter(|(c, _)| !into_other(c)).map(|(_, &x)| x).sum::<Cost>();
        }
        // The wavefront's phases are out of line only in a phases build; the
        // scalar kernel has its film out of line there, but not its traversal.
        if !seen[0] {
            return None;
        }
        let loop_total = self.render_loop();
        let mut rows: Vec<PhaseCount> = PHASES
            .iter()
            .zip(&counts)
            .map(|((phase, _), &cost)| PhaseCount { phase: phase.to_string(), cost })
            .collect();
        let rest = loop_total - counts.iter().copied().sum();
        rows.push(PhaseCount { phase: "rest".to_string(), cost: rest });
        Some(rows)
    }
}

/// The valgrind to run, checked before any work: its version line.
pub fn valgrind_version() -> Result<String> {
    let missing = |why: String| {
        Error::System(format!(
            "valgrind {why}: --instructions counts instructions with valgrind's callgrind; install valgrind \
             (Debian/Ubuntu: apt-get install valgrind) or measure time without --instructions"
        ))
    };
    let out =
        Command::new("valgrind").arg("--version").output().map_err(|e| missing(format!("cannot be run ({e})")))?;
    if !out.status.success() {
        return Err(missing(format!("--version failed ({})", out.status)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Refuses a build valgrind cannot run: one compiled for AVX-512 (a native
/// build on a CPU that has it), which valgrind does not know; says how to
/// build one it can count.
pub fn check_countable_build() -> Result<()> {
    if cfg!(target_feature = "avx512f") {
        return Err(Error::System(
            "this build uses AVX-512 (built for this CPU), which valgrind does not know: count a build for \
             x86-64-v3: RUSTFLAGS=\"-C target-cpu=x86-64-v3\" cargo build --release --target x86_64-unknown-linux-gnu \
             --target-dir target/isa-v3, then run target/isa-v3/x86_64-unknown-linux-gnu/release/rtow bench ... \
             --instructions (rtow's own gate, benches/instructions/gate, builds it itself)"
                .into(),
        ));
    }
    Ok(())
}

/// The callgrind command line that counts `program` with `args`, writing
/// the profile to `profile`; `branch_sim` adds the branch predictor's simulation.
pub fn command_line(program: &Path, args: &[OsString], profile: &Path, branch_sim: bool) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec!["valgrind".into(), "--tool=callgrind".into(), "-q".into(), "--dump-line=no".into()];
    if branch_sim {
        v.push("--branch-sim=yes".into());
    }
    let mut out = OsString::from("--callgrind-out-file=");
    out.push(profile);
    v.push(out);
    v.push(program.into());
    v.extend(args.iter().cloned());
    v
}

/// Runs `program args` under callgrind (with the branch simulation when
/// `branch_sim`); returns its profile and what it printed on stdout. A
/// failure of the program or of valgrind is an error (exit status 1) with
/// the end of what it said.
pub fn count(program: &Path, args: &[OsString], branch_sim: bool) -> Result<(Profile, String)> {
    let dir = tempfile::tempdir().map_err(|e| Error::System(format!("cannot make a temporary folder: {e}")))?;
    let profile = dir.path().join("callgrind.out");
    let cmd = command_line(program, args, &profile, branch_sim);
    let out = Command::new(&cmd[0])
        .args(&cmd[1..])
        .output()
        .map_err(|e| Error::System(format!("cannot run valgrind: {e}")))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let tail: Vec<&str> = stderr.lines().rev().take(4).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        let sigill = stderr.contains("SIGILL") || stderr.contains("unhandled instruction");
        return Err(Error::System(format!(
            "the render under callgrind failed ({}){}: {}",
            out.status,
            if sigill {
                " on an instruction valgrind does not know: count a build for an older CPU, e.g. \
                 RUSTFLAGS=\"-C target-cpu=x86-64-v3\" cargo build --release"
            } else {
                ""
            },
            crate::output::clip_to(&tail.join(" | "), 400)
        )));
    }
    let text = std::fs::read_to_string(&profile)
        .map_err(|e| Error::System(format!("callgrind wrote no profile ({}): {e}", profile.display())))?;
    let profile = Profile::parse(&text).map_err(Error::System)?;
    Ok((profile, String::from_utf8_lossy(&out.stdout).into_owned()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile in callgrind's format with name compression: main calls
    /// the render loop, which calls scatter (which calls append) and the traversal.
    const PROFILE: &str = "version: 1\ncreator: callgrind-3.19.0\npositions: line\nevents: Ir\nsummary: 1000\n\n\
        fl=(1) a.rs\nfn=(1) main\n1 100\ncfn=(2) rtow::render::tile_work\ncalls=2 5\n2 900\n\n\
        fn=(2)\n5 40\ncfn=(3) rtow::kernel::wavefront::scatter::<wide::f32x8>\ncalls=10 7\n6 300\n\
        cfn=(4) <rtow::geometry::shapes::Shapes>::closest::<wide::f32x8>\ncalls=10 8\n7 560\n\n\
        fn=(3)\n7 250\ncfn=(5) rtow::kernel::wavefront::Paths::append\ncalls=10 9\n8 50\n\n\
        fn=(5)\n9 50\n\nfn=(4)\n8 560\n\ntotals: 1000\n";

    #[test]
    fn the_render_loop_and_its_phases_from_a_profile() {
        let p = Profile::parse(PROFILE).unwrap();
        assert_eq!(p.total, 1000);
        assert!(!p.branch_sim);
        assert_eq!(p.render_loop().instructions, 900);
        let phases = p.phases().unwrap();
        let get = |name: &str| phases.iter().find(|r| r.phase == name).unwrap().cost.instructions;
        assert_eq!((get("traversal"), get("scatter"), get("compaction")), (560, 250, 50));
        assert_eq!((get("camera rays"), get("film"), get("rest")), (0, 0, 40));
        assert_eq!(phases.iter().map(|r| r.cost.instructions).sum::<u64>(), 900);
    }

    /// The same profile with the branch simulation's events, in callgrind's
    /// order (`Ir Bc Bcm Bi Bim`): the branches and mispredictions follow
    /// the instructions through the calls and phases.
    #[test]
    fn branches_and_mispredictions_from_a_branch_simulation() {
        let text = "version: 1\npositions: line\nevents: Ir Bc Bcm Bi Bim\nsummary: 1000 200 20 10 1\n\n\
            fn=(1) main\n1 100 10 1\ncfn=(2) rtow::render::tile_work\ncalls=2 5\n2 900 190 19 10 1\n\n\
            fn=(2)\n5 40 4 2 1 1\ncfn=(3) rtow::kernel::wavefront::scatter::<wide::f32x8>\ncalls=10 7\n6 300 60 7 9\n\
            cfn=(4) <rtow::geometry::shapes::Shapes>::closest::<wide::f32x8>\ncalls=10 8\n7 560 126 10\n\n\
            fn=(3)\n7 300 60 7 9\n\nfn=(4)\n8 560 126 10\n\ntotals: 1000 200 20 10 1\n";
        let p = Profile::parse(text).unwrap();
        assert!(p.branch_sim);
        assert_eq!(p.total, 1000);
        // The loop's own line (1 of 1 indirect mispredicted, 2 of 4 conditional) and its two calls.
        assert_eq!(
            p.render_loop(),
            Cost { instructions: 900, branches: 4 + 1 + 60 + 9 + 126, mispredicts: 2 + 1 + 7 + 10 }
        );
        let phases = p.phases().unwrap();
        let get = |name: &str| phases.iter().find(|r| r.phase == name).unwrap().cost;
        assert_eq!(get("traversal"), Cost { instructions: 560, branches: 126, mispredicts: 10 });
        assert_eq!(get("scatter"), Cost { instructions: 300, branches: 69, mispredicts: 7 });
        assert_eq!(get("rest"), Cost { instructions: 40, branches: 5, mispredicts: 3 });
    }

    #[test]
    fn names_match_whole_paths_only() {
        assert!(is("rtow::render::tile_work", RENDER_LOOP));
        assert!(is("rtow::render::tile_work::<f32, ()>", RENDER_LOOP));
        assert!(is("rtow::render::tile_work'2", RENDER_LOOP));
        assert!(!is("rtow::render::tile_works", RENDER_LOOP));
        assert!(is("<rtow::film::TileFilm>::add", "rtow::film::TileFilm::add"));
        assert!(Profile::parse("no profile here").is_err());
        // Without the traversal out of line (the scalar kernel): no phases.
        let scalar =
            "events: Ir\nfn=(1) rtow::render::tile_work\n1 10\ncfn=(2) rtow::film::TileFilm::add\ncalls=1 2\n1 5\nfn=(2)\n2 5\n";
        let p = Profile::parse(scalar).unwrap();
        assert_eq!((p.render_loop().instructions, p.phases()), (15, None));
        assert!(Profile::parse("events: Dr\n").is_err());
    }
}
