//! What a figure needs to know about the build that made it (see
//! `src/provenance.rs`): the git commit of the sources, whether the sources
//! differed from it, and the compiler. Outside a git checkout of rtow itself
//! (a crates.io package, a tarball, a path dependency inside another
//! repository) the commit comes from `.cargo_vcs_info.json` when cargo
//! packaged one, else it is unknown; the build never fails for it.
//!
//! Rebuild triggers: the script reruns (and the rtow crate is recompiled)
//! only when the commit can have changed (HEAD, the branch's ref, the packed
//! refs) or when a file that goes into the build changes, which recompiles
//! the crate anyway. Editing the docs, staging or a `git status` does not.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The files whose changes make the build differ from its commit.
const SOURCES: &[&str] = &["src", "build.rs", "Cargo.toml", "Cargo.lock", ".cargo"];

fn run(program: &str, dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new(program)
        .args(args)
        .current_dir(dir)
        // A read-only look: git must not refresh the index (that would touch a
        // file and could make the next build rerun this script).
        .env("GIT_OPTIONAL_LOCKS", "0")
        .output()
        .ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn rerun_if_exists(path: &Path) {
    if path.exists() {
        println!("cargo:rerun-if-changed={}", path.display());
    }
}

/// The commit and whether the sources differ from it, when `dir` is the top
/// of a git work tree.
fn from_git(dir: &Path) -> Option<(String, bool)> {
    let top = run("git", dir, &["rev-parse", "--show-toplevel"])?;
    if std::fs::canonicalize(&top).ok()? != std::fs::canonicalize(dir).ok()? {
        return None; // rtow inside someone else's repository: that commit is not rtow's
    }
    let commit = run("git", dir, &["rev-parse", "--verify", "HEAD"])?;
    let git_path = |p: &str| run("git", dir, &["rev-parse", "--git-path", p]).map(|s| dir.join(s));
    for p in ["HEAD", "packed-refs"] {
        if let Some(p) = git_path(p) {
            rerun_if_exists(&p);
        }
    }
    if let Some(branch) = run("git", dir, &["symbolic-ref", "-q", "HEAD"]) {
        if let Some(p) = git_path(&branch) {
            rerun_if_exists(&p);
        }
    }
    let mut args = vec!["status", "--porcelain", "--untracked-files=no", "--"];
    args.extend_from_slice(SOURCES);
    let modified = run("git", dir, &args).is_some_and(|s| !s.is_empty());
    Some((commit, modified))
}

/// The commit cargo recorded when it packaged the crate.
fn from_package(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join(".cargo_vcs_info.json")).ok()?;
    let at = text.find("\"sha1\"")?;
    let rest = &text[at + 6..];
    let start = rest.find('"')? + 1;
    let sha: String = rest[start..].chars().take_while(|c| c.is_ascii_hexdigit()).collect();
    (sha.len() == 40).then_some(sha)
}

fn main() {
    let dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=build.rs");
    for s in SOURCES {
        rerun_if_exists(&dir.join(s));
    }
    rerun_if_exists(&dir.join(".cargo_vcs_info.json"));
    let (commit, modified) = match from_git(&dir) {
        Some((c, m)) => (c, if m { "true" } else { "false" }),
        None => match from_package(&dir) {
            Some(c) => (c, "unknown"),
            None => (String::new(), "unknown"),
        },
    };
    println!("cargo:rustc-env=RTOW_BUILD_COMMIT={commit}");
    println!("cargo:rustc-env=RTOW_BUILD_MODIFIED={modified}");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = run(&rustc, &dir, &["-V"]).unwrap_or_default();
    println!("cargo:rustc-env=RTOW_BUILD_RUSTC={version}");
    let target = std::env::var("TARGET").unwrap_or_default();
    println!("cargo:rustc-env=RTOW_BUILD_TARGET={target}");
    let opt = std::env::var("OPT_LEVEL").unwrap_or_default();
    println!("cargo:rustc-env=RTOW_BUILD_OPT_LEVEL={opt}");
}
