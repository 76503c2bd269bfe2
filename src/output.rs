//! A run's outputs as one transaction.
//!
//! Everything rtow writes in a run (`render`: `-o`, `--float`, `--stats-json`;
//! `bench`: `--json`, `--save`; `export -o`) goes through [`Outputs`]:
//!
//! 1. **Checked up front**, before any expensive work ([`Outputs::add`]): every
//!    path is distinct from the others and from every input of the run (exit
//!    status 2: the arguments contradict each other), is not a folder, its
//!    folder exists and takes a new file, and an existing file there is a
//!    regular file we may write (a write-protected file is refused: exit
//!    status 1).
//! 2. **Staged** ([`Outputs::stage`]): each output is written to a temporary
//!    file `.rtow-XXXXXX.tmp` next to its target and synced.
//! 3. **Committed** ([`Outputs::commit`]) only when all were staged: renamed
//!    into place together. Should a rename fail, the targets already replaced
//!    get their previous contents back (kept as hard links until the commit
//!    ends), so a run replaces all of its outputs or none.
//!
//! **One run per output at a time.** [`Outputs::add`] takes a lock file
//! `<output>.lock` beside each output (created exclusively, as git's
//! `index.lock`; it holds the process id and host name) and the commit
//! removes it. A second run that would write the same file while the first
//! holds it is refused (exit status 1) before any work, so two runs never mix
//! their outputs. A lock left by a process of this host that no longer runs
//! (killed with SIGKILL) is taken over; one from another host must be removed
//! by hand, as the message says.
//!
//! Temporary and lock files are removed when the run fails (dropping an
//! uncommitted [`Outputs`]) and on SIGINT, SIGTERM or SIGHUP
//! ([`install_signal_cleanup`]: the process says so in one line on stderr and
//! exits with status 128 + the signal: 130, 143, 129). A signal that arrives
//! during a commit waits for it to finish, so the outputs are either all old
//! or all new. SIGXFSZ (a file-size limit, as batch systems set them) is
//! ignored, so an output over the limit is the ordinary write error "File too
//! large" with the same cleanup, not a silent death. SIGKILL cannot be
//! caught: it may leave `.rtow-*.tmp` and `.lock` files (never a half-written
//! output).
//!
//! **Symlinks.** An output path that is a symbolic link is followed: the file
//! it points to is replaced atomically (in the link target's folder) and the
//! link stays. A link to a missing file is refused. Inputs are compared with
//! outputs after following links (and by device and inode on Unix), so a
//! link or a hard link to the scene cannot overwrite it.
//!
//! A replaced file keeps its permissions; a new one gets 0666 less the umask,
//! as `File::create` gives.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Mutex, MutexGuard};

/// Temporary files of staged, uncommitted outputs and the lock files of
/// uncommitted runs: what a signal removes.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Whether a transaction of this process has committed (what the one line
/// on an interruption says).
static COMMITTED: AtomicBool = AtomicBool::new(false);

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// What an interrupted run says on stderr, in one line.
pub fn interrupted_message(signal: &str, committed: bool) -> String {
    if committed {
        format!("rtow: interrupted by {signal} after its outputs were written")
    } else {
        format!("rtow: interrupted by {signal}: no output was written, every output file left as it was")
    }
}

/// Installs a SIGINT / SIGTERM / SIGHUP handler (once per process) that
/// removes every staged temporary file and lock file, says so in one line on
/// stderr and exits with status 128 + the signal (130, 143, 129); a signal
/// during a commit waits for the commit to finish. SIGXFSZ is ignored, so
/// that a file-size limit is an ordinary write error. Call it at the start
/// of a program that writes outputs (the `rtow` binary does).
pub fn install_signal_cleanup() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        #[cfg(unix)]
        {
            use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM, SIGXFSZ};
            // A handler that does nothing: the write that crossed the limit
            // then fails with EFBIG ("File too large") and the run cleans up.
            let _ = signal_hook::flag::register(SIGXFSZ, std::sync::Arc::new(AtomicBool::new(false)));
            let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else { return };
            std::thread::spawn(move || {
                for sig in signals.forever() {
                    let name = signal_name(sig);
                    // A render in rounds stops at the end of its round and
                    // writes a film to resume; a second signal quits at once.
                    if GRACEFUL.load(Ordering::SeqCst)
                        && STOP.compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst).is_ok()
                    {
                        let _ = writeln!(
                            std::io::stderr(),
                            "rtow: {name}: finishing the current round of samples to write a film to resume \
                             ({name} again quits now, writing nothing)"
                        );
                        continue;
                    }
                    // Held until exit: no commit can start or be half done.
                    let list = pending();
                    for p in list.iter() {
                        let _ = std::fs::remove_file(p);
                    }
                    // A closed terminal (SIGHUP) may make stderr fail: never panic on it.
                    let _ =
                        writeln!(std::io::stderr(), "{}", interrupted_message(name, COMMITTED.load(Ordering::SeqCst)));
                    std::process::exit(128 + sig);
                }
            });
        }
    });
}

/// Set while a run can stop gracefully ([`Graceful`]).
static GRACEFUL: AtomicBool = AtomicBool::new(false);

/// The signal that asked a graceful run to stop (0: none).
static STOP: AtomicI32 = AtomicI32::new(0);

#[cfg(unix)]
fn signal_name(sig: i32) -> &'static str {
    use signal_hook::consts::{SIGINT, SIGTERM};
    match sig {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "SIGHUP",
    }
}

/// While one is alive, the first SIGINT, SIGTERM or SIGHUP does not end the
/// process (with [`install_signal_cleanup`]'s handler installed): it is
/// recorded for [`stop_signal`], and the run (a render in
/// rounds) stops at its next safe point, writes what it has and exits with
/// 128 + the signal itself. A second signal ends the process as usual.
pub struct Graceful(());

impl Graceful {
    /// Starts graceful handling (one at a time; a signal recorded before is forgotten).
    pub fn enter() -> Graceful {
        STOP.store(0, Ordering::SeqCst);
        GRACEFUL.store(true, Ordering::SeqCst);
        Graceful(())
    }
}

/// The signal recorded by a [`Graceful`] run, if any.
pub fn stop_signal() -> Option<(&'static str, i32)> {
    match STOP.load(Ordering::SeqCst) {
        0 => None,
        #[cfg(unix)]
        sig => Some((signal_name(sig), sig)),
        #[cfg(not(unix))]
        sig => Some(("signal", sig)),
    }
}

impl Drop for Graceful {
    fn drop(&mut self) {
        GRACEFUL.store(false, Ordering::SeqCst);
    }
}

/// The lock file of output `target`: `<target>.lock`.
fn lock_path(target: &Path) -> PathBuf {
    let mut name = target.file_name().unwrap_or_default().to_os_string();
    name.push(".lock");
    target.with_file_name(name)
}

fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname").map(|s| s.trim().to_string()).unwrap_or_default()
}

/// Whether the lock file `lock` was left by a process of this host that no
/// longer runs (a run killed by SIGKILL).
fn stale(lock: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(lock) else { return false };
    let mut words = text.split_whitespace();
    let (Some(pid), Some(host)) = (words.next().and_then(|w| w.parse::<u32>().ok()), words.next()) else {
        return false;
    };
    let here = host_name();
    !here.is_empty() && host == here && Path::new("/proc/self").exists() && !Path::new(&format!("/proc/{pid}")).exists()
}

/// Takes the lock of output `target` (`shown` as the user gave it).
fn take_lock(shown: &Path, target: &Path) -> Result<PathBuf> {
    let lock = lock_path(target);
    let mut retried = false;
    loop {
        let mut list = pending();
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&lock) {
            Ok(mut f) => {
                list.push(lock.clone());
                let _ = writeln!(f, "{} {}", std::process::id(), host_name());
                return Ok(lock);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                drop(list);
                if !retried && stale(&lock) {
                    let _ = std::fs::remove_file(&lock);
                    retried = true;
                    continue;
                }
                let who = std::fs::read_to_string(&lock).unwrap_or_default();
                let who = clip(who.trim());
                return Err(output_error(
                    shown,
                    format!(
                        "another run is writing it (lock file {}{}); if no run is, remove the lock file",
                        lock.display(),
                        if who.is_empty() { String::new() } else { format!(", process and host: {who}") }
                    ),
                ));
            }
            Err(e) => return Err(output_error(shown, format!("cannot create its lock file {}: {e}", lock.display()))),
        }
    }
}

fn release_lock(lock: &Path) {
    let _ = std::fs::remove_file(lock);
    pending().retain(|q| q != lock);
}

fn output_error(path: &Path, message: impl std::fmt::Display) -> Error {
    // tempfile appends ` at path "<dir>/.rtow-XXXX.tmp"`; the temporary name
    // means nothing to the user, the target path is already in the message.
    let message = message.to_string();
    let message = message.split(" at path ").next().unwrap_or_default().to_string();
    Error::Output { path: path.to_path_buf(), message }
}

/// The folder `path` will be written in, checked to exist.
fn target_dir(path: &Path) -> Result<&Path> {
    if path.is_dir() {
        return Err(output_error(path, "is a directory"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.exists() {
        return Err(output_error(path, format!("folder {} does not exist", dir.display())));
    }
    if !dir.is_dir() {
        return Err(output_error(path, format!("{} is not a folder", dir.display())));
    }
    Ok(dir)
}

fn temp_in(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let mut b = tempfile::Builder::new();
    b.prefix(".rtow-").suffix(".tmp");
    // tempfile creates files readable by the owner only (0600); outputs are
    // ordinary files, so ask for 0666 and let the umask decide, as `File::create` does.
    #[cfg(unix)]
    b.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    b.tempfile_in(dir)
}

/// Where writing `path` lands: symlinks followed (a dangling one refused).
fn resolve(path: &Path) -> Result<PathBuf> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path)
            .map_err(|_| output_error(path, "is a symbolic link to a file that does not exist (refused)")),
        _ => Ok(path.to_path_buf()),
    }
}

/// A name for the file at `path` that is equal for equal files: the
/// canonical folder plus the file name (the file need not exist).
fn identity(path: &Path) -> Option<PathBuf> {
    if let Ok(c) = std::fs::canonicalize(path) {
        return Some(c);
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(dir).ok()?.join(path.file_name()?))
}

#[cfg(unix)]
fn same_inode(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_inode(_: &Path, _: &Path) -> bool {
    false
}

fn same_file(a: &Path, b: &Path) -> bool {
    same_inode(a, b) || matches!((identity(a), identity(b)), (Some(x), Some(y)) if x == y)
}

/// At most the first 40 characters of an input's text, for a message (an
/// error line never repeats an unbounded input).
pub fn clip(text: &str) -> String {
    clip_to(text, 40)
}

/// At most the first `n` characters of `text`, `...` marking a cut.
pub fn clip_to(text: &str, n: usize) -> String {
    match text.char_indices().nth(n) {
        Some((i, _)) => format!("{}...", &text[..i]),
        None => text.to_string(),
    }
}

/// `text` safe to print: every control character (C0, DEL, C1) written as
/// Rust escapes it (`\n`, `\t`, `\u{1b}`) and every Unicode bidirectional
/// control as `\u{202e}`, so a string from an input (an image's file name in
/// a scene file, a key the parser quotes) can never move the cursor, recolour
/// or reorder a terminal's line. Everything else, `\` included, is kept, so
/// escaping twice changes nothing.
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    let unsafe_char = |c: char| {
        c.is_control()
            || matches!(c, '\u{61c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if !text.chars().any(unsafe_char) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_debug());
        } else if unsafe_char(c) {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// Checks that the extension of `path` is one of `allowed` (lower case,
/// without the dot); otherwise a usage error (exit status 2) naming them.
pub fn check_extension(path: &Path, allowed: &[&str], flag: &str) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        Ok(())
    } else {
        let list: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
        Err(Error::invalid(flag, format!("{}: unsupported file type; use {}", path.display(), list.join(" or "))))
    }
}

struct Staged {
    /// As the user gave it (for messages).
    shown: PathBuf,
    /// Where the bytes land (symlinks followed).
    target: PathBuf,
    flag: String,
    /// The staged temporary file.
    temp: Option<PathBuf>,
    /// This run's lock file of the output (see the module documentation).
    lock: PathBuf,
    /// Taken out of the transaction ([`Outputs::forget`]).
    forgotten: bool,
}

/// A run's outputs: checked, staged and committed together (see the module
/// documentation). Dropping it uncommitted removes what was staged.
#[derive(Default)]
pub struct Outputs {
    /// The run's inputs: what they are, and the one output flag that may
    /// replace the input (a film resumed in place), if any.
    inputs: Vec<(PathBuf, String, Option<String>)>,
    outputs: Vec<Staged>,
}

/// Which output of an [`Outputs`] to stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutputId(usize);

impl Outputs {
    pub fn new() -> Self {
        Outputs::default()
    }

    /// Declares an input of the run (a scene file, a baseline): no output may
    /// be the same file. Call before [`Outputs::add`].
    pub fn input(&mut self, path: &Path, what: &str) {
        self.inputs.push((path.to_path_buf(), what.to_string(), None));
    }

    /// Declares an input that the output named `flag` (and only it) may
    /// replace: a film resumed in place (read whole before the run writes).
    pub fn input_replaceable_by(&mut self, path: &Path, what: &str, flag: &str) {
        self.inputs.push((path.to_path_buf(), what.to_string(), Some(flag.to_string())));
    }

    /// Checks `path` as an output of the run (see the module documentation);
    /// `flag` names it in messages (`-o`, `--float`).
    pub fn add(&mut self, path: &Path, flag: &str) -> Result<OutputId> {
        let target = resolve(path)?;
        for (input, what, replaceable_by) in &self.inputs {
            if replaceable_by.as_deref() != Some(flag) && same_file(&target, input) {
                return Err(Error::invalid(
                    flag,
                    format!("{} is the {what} {}: it would be overwritten", path.display(), input.display()),
                ));
            }
        }
        for o in &self.outputs {
            if same_file(&target, &o.target) {
                return Err(Error::invalid(
                    flag,
                    format!(
                        "{} is the same file as {} {}: one would be lost",
                        path.display(),
                        o.flag,
                        o.shown.display()
                    ),
                ));
            }
        }
        let dir = target_dir(&target).map_err(|e| match e {
            Error::Output { message, .. } => output_error(path, message),
            e => e,
        })?;
        if let Ok(meta) = std::fs::metadata(&target) {
            if !meta.is_file() {
                return Err(output_error(path, "exists and is not a regular file (refused)"));
            }
            if meta.permissions().readonly() {
                return Err(output_error(path, "is write-protected (refused; make it writable to replace it)"));
            }
            // Another user's file, or a folder that forbids it: open to write
            // without truncating (the file is not changed).
            std::fs::OpenOptions::new().write(true).open(&target).map_err(|e| output_error(path, e))?;
        }
        temp_in(dir).map_err(|e| output_error(path, e))?;
        let lock = take_lock(path, &target)?;
        self.outputs.push(Staged {
            shown: path.to_path_buf(),
            target,
            flag: flag.to_string(),
            temp: None,
            lock,
            forgotten: false,
        });
        Ok(OutputId(self.outputs.len() - 1))
    }

    /// Writes the contents of output `id` to its temporary file (replacing
    /// any staged before).
    pub fn stage(&mut self, id: OutputId, bytes: &[u8]) -> Result<()> {
        let o = &mut self.outputs[id.0];
        let fail = |e: &dyn std::fmt::Display| output_error(&o.shown, e);
        let dir = target_dir(&o.target).map_err(|_| fail(&"its folder is gone"))?;
        let (mut file, tmp) = {
            let mut list = pending();
            let t = temp_in(dir).map_err(|e| fail(&e))?;
            let (file, tmp) = t.keep().map_err(|e| fail(&e.error))?;
            list.push(tmp.clone());
            (file, tmp)
        };
        if let Some(old) = o.temp.replace(tmp.clone()) {
            remove_temp(&old);
        }
        if let Ok(meta) = std::fs::metadata(&o.target) {
            file.set_permissions(meta.permissions()).map_err(|e| fail(&e))?;
        }
        file.write_all(bytes).map_err(|e| fail(&e))?;
        file.sync_all().map_err(|e| fail(&e))?;
        Ok(())
    }

    /// Writes output `id` now, atomically (staged, then renamed into place),
    /// outside the transaction: a preview of an image still being rendered.
    /// The output keeps its lock and must be staged again before the commit.
    pub fn publish(&mut self, id: OutputId, bytes: &[u8]) -> Result<()> {
        self.stage(id, bytes)?;
        let mut list = pending();
        let o = &mut self.outputs[id.0];
        let tmp = o.temp.take().expect("staged above");
        list.retain(|p| p != &tmp);
        std::fs::rename(&tmp, &o.target).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            output_error(&o.shown, e)
        })
    }

    /// Takes output `id` out of the transaction: it is not written, its lock
    /// is released (a render stopped by a signal writes only its film).
    pub fn forget(&mut self, id: OutputId) {
        let o = &mut self.outputs[id.0];
        if let Some(t) = o.temp.take() {
            remove_temp(&t);
        }
        release_lock(&o.lock);
        o.forgotten = true;
    }

    /// Renames every staged output into place; all or none (see the module
    /// documentation). Every output must have been staged.
    pub fn commit(mut self) -> Result<()> {
        // Test hook (tests/suite/hostile.rs): hold the staged files for a while so a
        // test can signal the process between staging and commit.
        if let Some(ms) = std::env::var("RTOW_TEST_PAUSE_BEFORE_COMMIT_MS").ok().and_then(|v| v.parse().ok()) {
            std::thread::sleep(std::time::Duration::from_millis(ms));
        }
        let mut list = pending();
        self.outputs.retain(|o| !o.forgotten);
        if let Some(o) = self.outputs.iter().find(|o| o.temp.is_none()) {
            return Err(output_error(&o.shown, "was never written (internal error)"));
        }
        // Previous contents, as hard links, so that a failed rename can be undone.
        let mut backups: Vec<Option<PathBuf>> = Vec::new();
        let mut done = 0;
        let mut failure = None;
        for o in &self.outputs {
            let backup = o.target.is_file().then(|| backup_of(&o.target)).flatten();
            backups.push(backup);
            let tmp = o.temp.as_ref().expect("checked above");
            if let Err(e) = std::fs::rename(tmp, &o.target) {
                failure = Some(output_error(&o.shown, e));
                break;
            }
            done += 1;
        }
        if failure.is_some() {
            for (o, b) in self.outputs[..done].iter().zip(&backups) {
                match b {
                    Some(b) => {
                        let _ = std::fs::rename(b, &o.target);
                    }
                    None => {
                        let _ = std::fs::remove_file(&o.target);
                    }
                }
            }
        }
        for b in backups.iter().flatten() {
            let _ = std::fs::remove_file(b);
        }
        for o in &mut self.outputs {
            if let Some(t) = o.temp.take() {
                let _ = std::fs::remove_file(&t);
                list.retain(|p| p != &t);
            }
            let _ = std::fs::remove_file(&o.lock);
            list.retain(|p| p != &o.lock);
        }
        if failure.is_none() {
            COMMITTED.store(true, Ordering::SeqCst);
        }
        self.outputs.clear();
        drop(list);
        match failure {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// A hard link to `target` under a temporary name in its folder.
fn backup_of(target: &Path) -> Option<PathBuf> {
    let dir = target_dir(target).ok()?;
    let (_, tmp) = temp_in(dir).ok()?.keep().ok()?;
    std::fs::remove_file(&tmp).ok()?;
    std::fs::hard_link(target, &tmp).ok()?;
    Some(tmp)
}

fn remove_temp(p: &Path) {
    let _ = std::fs::remove_file(p);
    pending().retain(|q| q != p);
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for o in self.outputs.iter_mut().filter(|o| !o.forgotten) {
            if let Some(t) = o.temp.take() {
                remove_temp(&t);
            }
            release_lock(&o.lock);
        }
    }
}

/// Writes `bytes` to `path` atomically: a transaction of one output.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut out = Outputs::new();
    let id = out.add(path, "output")?;
    out.stage(id, bytes)?;
    out.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_once() {
        assert_eq!(printable("earth map.jpg"), "earth map.jpg");
        let hostile = "a\u{1b}[31mred\u{7}\nb\tc\u{9b}d\u{202e}gpj.exe\\x";
        let shown = printable(hostile);
        assert_eq!(shown, "a\\u{1b}[31mred\\u{7}\\nb\\tc\\u{9b}d\\u{202e}gpj.exe\\x");
        assert!(!shown.chars().any(char::is_control));
        assert_eq!(printable(&shown), shown, "escaping is idempotent");
    }

    /// Checks `path` as the one output of a run.
    fn check_writable(path: &Path) -> Result<()> {
        Outputs::new().add(path, "output").map(|_| ())
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces_without_leaving_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(names(dir.path()), ["a.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn new_files_get_the_permissions_file_create_gives() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let ours = dir.path().join("ours");
        let std_made = dir.path().join("std");
        write_atomic(&ours, b"x").unwrap();
        std::fs::File::create(&std_made).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&ours), mode(&std_made));
        // A replaced file keeps the permissions its owner gave it.
        std::fs::set_permissions(&ours, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&ours, b"y").unwrap();
        assert_eq!(mode(&ours), 0o640);
    }

    #[test]
    fn unwritable_targets_are_output_errors_and_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("file"), b"").unwrap();
        for (target, says) in [
            (dir.path().join("missing/a.png"), "does not exist"),
            (dir.path().join("file/a.png"), "is not a folder"),
            (dir.path().to_path_buf(), "is a directory"),
        ] {
            for r in [check_writable(&target), write_atomic(&target, b"x")] {
                let e = r.unwrap_err();
                assert_eq!(e.exit_code(), 1, "{e}");
                let msg = e.to_string();
                assert!(msg.contains(says), "{msg}");
                assert!(!msg.contains(".rtow-"), "temporary name leaked: {msg}");
            }
        }
        assert_eq!(names(dir.path()), ["file"]);
    }

    #[test]
    fn outputs_must_differ_from_each_other_and_from_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("scene.json"), b"{}").unwrap();
        let mut o = Outputs::new();
        o.input(&d.join("scene.json"), "scene file");
        // The same file under another spelling is still the same file.
        let e = o.add(&d.join(".").join("scene.json"), "-o").unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("overwritten"), "{e}");
        o.add(&d.join("a.png"), "-o").unwrap();
        let e = o.add(&d.join("./a.png"), "--float").unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("same file as -o"), "{e}");
        #[cfg(unix)]
        {
            std::fs::hard_link(d.join("scene.json"), d.join("link.json")).unwrap();
            assert!(o.add(&d.join("link.json"), "--stats-json").is_err());
            std::os::unix::fs::symlink(d.join("scene.json"), d.join("sym.json")).unwrap();
            assert!(o.add(&d.join("sym.json"), "--stats-json").is_err());
        }
        assert_eq!(std::fs::read(d.join("scene.json")).unwrap(), b"{}");
    }

    #[cfg(unix)]
    #[test]
    fn write_protected_and_special_files_are_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ro.png");
        std::fs::write(&p, b"keep").unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o444)).unwrap();
        let e = write_atomic(&p, b"new").unwrap_err();
        assert_eq!(e.exit_code(), 1);
        assert!(e.to_string().contains("write-protected"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"keep");
        let e = check_writable(Path::new("/dev/null")).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_output_replaces_its_target_and_stays_a_link() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("real")).unwrap();
        std::fs::write(d.join("real/a.txt"), b"old").unwrap();
        std::os::unix::fs::symlink(d.join("real/a.txt"), d.join("link.txt")).unwrap();
        write_atomic(&d.join("link.txt"), b"new").unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.txt")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(d.join("real/a.txt")).unwrap(), b"new");
        assert_eq!(names(&d.join("real")), ["a.txt"]);
        std::os::unix::fs::symlink(d.join("missing"), d.join("dangling.txt")).unwrap();
        let e = check_writable(&d.join("dangling.txt")).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
    }

    #[test]
    fn nothing_is_replaced_unless_everything_is_staged() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a"), b"old a").unwrap();
        std::fs::write(d.join("b"), b"old b").unwrap();
        {
            let mut o = Outputs::new();
            let a = o.add(&d.join("a"), "-o").unwrap();
            let _b = o.add(&d.join("b"), "--float").unwrap();
            o.stage(a, b"new a").unwrap();
            // The second output's encoding fails: the run drops its outputs.
        }
        assert_eq!(std::fs::read(d.join("a")).unwrap(), b"old a");
        assert_eq!(names(d), ["a", "b"]);
        let mut o = Outputs::new();
        let a = o.add(&d.join("a"), "-o").unwrap();
        let b = o.add(&d.join("b"), "--float").unwrap();
        o.stage(a, b"new a").unwrap();
        o.stage(b, b"new b").unwrap();
        assert!(pending().iter().any(|p| p.starts_with(d)));
        o.commit().unwrap();
        assert_eq!(std::fs::read(d.join("a")).unwrap(), b"new a");
        assert_eq!(std::fs::read(d.join("b")).unwrap(), b"new b");
        assert_eq!(names(d), ["a", "b"]);
        assert!(!pending().iter().any(|p| p.starts_with(d)));
    }

    #[test]
    fn a_failed_rename_restores_the_outputs_already_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a"), b"old a").unwrap();
        let mut o = Outputs::new();
        let a = o.add(&d.join("a"), "-o").unwrap();
        let b = o.add(&d.join("b"), "--float").unwrap();
        o.stage(a, b"new a").unwrap();
        o.stage(b, b"new b").unwrap();
        // Between staging and commit, b's target becomes a non-empty folder: its rename fails.
        std::fs::create_dir(d.join("b")).unwrap();
        std::fs::write(d.join("b/x"), b"").unwrap();
        assert_eq!(o.commit().unwrap_err().exit_code(), 1);
        assert_eq!(std::fs::read(d.join("a")).unwrap(), b"old a");
        assert_eq!(names(d), ["a", "b"]);
    }
}
