//! A run's staging folder: where one output is written before it is placed.
//!
//! `.NAME.specchio-HEX` beside the target `NAME`, where `HEX` is 128 random bits: made with an
//! exclusive `mkdir` (a name that exists, a planted link included, is never taken over), never
//! reused. It holds the output under its final name, and [`TOKEN`], a file whose text repeats
//! `HEX` and which the run keeps locked (`flock`) for as long as it lives. That is the proof of
//! ownership: a later run removes a staging folder only when it finds the token with the
//! folder's own `HEX` in it and can take its lock, that is, when the run that made it is gone
//! (killed before it could clean up). A name that merely looks like a staging folder, a link of
//! that shape, or a folder whose run still lives (in whatever PID namespace) is never touched.
//!
//! Just before a run swaps its output with an earlier one, it rewrites the token to say that
//! the folder may now hold that earlier output. A run killed after that point leaves a folder
//! that may hold the user's files written into the old output, so the sweep does not simply
//! remove it: it removes what the earlier output's manifest lists and moves anything else to
//! `NAME.kept-N`, as a run that lives does (`manifest::recover`).
//!
//! Not `tempfile::TempDir`: it would give the random name and the exclusive `mkdir`, but its
//! drop removes the folder by path, recursively, whatever is in it; here a folder is removed
//! only by its manifest, through a held handle, and a dead run's folder only once its lock
//! proves the run gone. Keeping a `TempDir` just for its name would leave a dozen lines of
//! ours for a dependency whose main behaviour must be switched off.

use std::fs::{self, File};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use super::dir::Dir;
use super::sys;

/// The file in every staging folder that names it and carries its run's lock.
pub const TOKEN: &str = ".specchio-stage";
/// Between the target's name and the random part, in a staging folder's name.
const INFIX: &str = ".specchio-";
/// The random part: 128 bits as 32 lower-case hex digits.
const HEX_DIGITS: usize = 32;
/// The most bytes of the target's name a staging folder's name repeats.
const NAME_BYTES: usize = 160;

/// This process's staging folders, by their random part, and whether each is one the cleaner
/// must leave (its output is being placed, or it may hold an earlier output): what
/// [`remove_live`] removes when a second signal ends the process at once.
static LIVE: Mutex<Vec<(String, PathBuf, bool)>> = Mutex::new(Vec::new());

/// The registry, whatever a thread that panicked holding it left (it is only ever pushed to,
/// flagged and removed from, each a whole step).
fn live() -> MutexGuard<'static, Vec<(String, PathBuf, bool)>> {
    LIVE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Takes staging folder `hex` out of the registry: it is gone, or the user's now.
fn forget(hex: &str) {
    live().retain(|(h, ..)| h != hex);
}

/// Removes this process's staging folders that hold nothing but its own output, for a process
/// about to end at once: a second signal does not wait for the run's next check, so the
/// transaction that would remove them is never dropped. One whose output is being placed is
/// left (a removal racing the rename would empty the placed output: the registry's lock puts
/// one before the other), and so is one that may hold an earlier output (its run was swapping
/// it with the target), for the next run's sweep, which recovers it by its manifest; as
/// after SIGKILL. Best effort: a file the run writes meanwhile can make a removal fail once,
/// so each is tried three times.
pub fn remove_live() {
    let live = live();
    remove_unmarked(&live);
    // Kept locked: the process ends at once, and a stage must not be placed (renamed out)
    // between a removal that failed and the end.
    std::mem::forget(live);
}

/// [`remove_live`] over `stages`.
fn remove_unmarked(stages: &[(String, PathBuf, bool)]) {
    for (_, dir, left) in stages {
        if *left {
            continue;
        }
        for _ in 0..3 {
            if fs::remove_dir_all(dir).is_ok() || fs::symlink_metadata(dir).is_err() {
                break;
            }
        }
    }
}

/// One output's staging folder, owned by this run: dropped, it is removed with everything in
/// it (unless [`Stage::keep`] was called because it holds what must not be lost).
#[derive(Debug)]
pub struct Stage {
    dir: PathBuf,
    /// The folder, open: what is renamed and removed in it is addressed through this handle.
    handle: Dir,
    hex: String,
    /// The token file, open and locked: closing it (this run ending, however) frees the lock.
    lock: Option<File>,
    keep: bool,
}

impl Stage {
    /// Makes a fresh staging folder for the target `name` in `parent`.
    pub fn create(parent: &Path, name: &str) -> io::Result<Stage> {
        let hex = random_hex()?;
        let dir = parent.join(format!(".{}{INFIX}{hex}", short(name)));
        fs::create_dir(&dir)?;
        let handle = Dir::open(&dir)?;
        let mut stage = Stage {
            dir,
            handle,
            hex,
            lock: None,
            keep: false,
        };
        // Lock before the text is written: a sweeper that reads a matching token always finds
        // it locked while this run lives.
        let mut token = sys::create_new(&stage.dir.join(TOKEN))?;
        if !sys::try_lock(&token).unwrap_or(true) {
            return Err(io::Error::other(
                "a new staging token is locked by another file",
            ));
        }
        token.write_all(token_text(&stage.hex).as_bytes())?;
        stage.lock = Some(token);
        live().push((stage.hex.clone(), stage.dir.clone(), false));
        Ok(stage)
    }

    /// The staging folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The staging folder, open.
    pub fn handle(&self) -> &Dir {
        &self.handle
    }

    /// Leaves the folder to the sweep if a second signal comes from now on: its output is
    /// about to be renamed out of it (`replace::place`).
    pub fn mark_placing(&self) {
        for (hex, _, left) in live().iter_mut() {
            *left |= *hex == self.hex;
        }
    }

    /// Says in the token, before an earlier output is swapped in here, that a sweep must
    /// recover this folder by manifest rather than remove it.
    pub fn mark_may_hold_earlier_output(&mut self) -> io::Result<()> {
        use std::io::Seek;
        // First in the registry: from here a second signal leaves the folder to the sweep.
        self.mark_placing();
        let token = self.lock.as_mut().expect("a created stage holds its token");
        token.set_len(0)?;
        token.rewind()?;
        token.write_all(swapping_text(&self.hex).as_bytes())
    }

    /// Leaves the folder and its token on disk and frees the lock, as a killed run does (for
    /// the tests of the sweep).
    #[cfg(test)]
    pub fn abandon(mut self) {
        self.keep = true;
    }

    /// Leaves the folder on disk when dropped (it holds a user's files the run could not put
    /// back; the error that says so names it). Its token goes first, so that no later run
    /// takes it for a dead run's staging and sweeps it: it is the user's now.
    pub fn keep(&mut self) {
        forget(&self.hex);
        let _ = fs::remove_file(self.dir.join(TOKEN));
        self.keep = true;
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        if !self.keep {
            // Best effort: a folder that will not go is swept by a later run once this one's
            // lock is free. `remove_dir_all` does not follow links.
            let _ = fs::remove_dir_all(&self.dir);
        }
        forget(&self.hex);
        self.lock.take();
    }
}

/// Removes the staging folders for `name` in `parent` whose run is gone: each must be a real
/// folder (not a link) named `.NAME.specchio-HEX`, hold a [`TOKEN`] (not a link) whose text
/// names the same `HEX`, and have that token's lock free. Best effort: what cannot be read or
/// removed is left.
pub fn sweep_dead(parent: &Path, name: &str) {
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    let prefix = format!(".{}{INFIX}", short(name));
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(hex) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)) else {
            continue;
        };
        if !is_hex(hex) || !entry.file_type().is_ok_and(|t| t.is_dir()) {
            continue;
        }
        let dir = entry.path();
        let Ok(Some((_lock, may_hold_output))) = dead_token(&dir, hex) else {
            continue;
        };
        // Handled while we hold the dead run's lock, so two sweepers cannot both start.
        if may_hold_output {
            let recovered = Dir::open(&dir)
                .map(|d| super::manifest::recover(&d, name, &parent.join(name)))
                .unwrap_or(false);
            if !recovered {
                // What could not be moved aside stays, token removed: it is the user's now.
                let _ = fs::remove_file(dir.join(TOKEN));
                continue;
            }
        }
        let _ = fs::remove_dir_all(&dir);
    }
}

/// The token of `dir`, locked by us, when it names `hex` and its run is gone, and whether it
/// says the folder may hold an earlier output.
fn dead_token(dir: &Path, hex: &str) -> io::Result<Option<(File, bool)>> {
    let mut token = sys::open_no_follow(&dir.join(TOKEN))?;
    if !token.metadata()?.is_file() {
        return Ok(None);
    }
    let mut text = String::new();
    (&mut token).take(256).read_to_string(&mut text)?;
    let may_hold_output = match text {
        t if t == token_text(hex) => false,
        t if t == swapping_text(hex) => true,
        _ => return Ok(None),
    };
    Ok(sys::try_lock(&token)?.then_some((token, may_hold_output)))
}

/// At most [`NAME_BYTES`] of the target's name, so that a staging folder's name stays within
/// the 255 bytes file systems allow (two targets sharing a long prefix then share a sweep,
/// which is safe: a sweep removes only what dead runs provably made).
fn short(name: &str) -> &str {
    let mut end = name.len().min(NAME_BYTES);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

fn token_text(hex: &str) -> String {
    format!("specchio staging folder {hex}: its run holds this file locked\n")
}

fn swapping_text(hex: &str) -> String {
    format!(
        "{}it may hold an earlier output: recover it by its manifest\n",
        token_text(hex)
    )
}

fn is_hex(s: &str) -> bool {
    s.len() == HEX_DIGITS && s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// 128 bits from the operating system's random source, as hex.
pub(super) fn random_hex() -> io::Result<String> {
    let mut bytes = [0u8; HEX_DIGITS / 2];
    getrandom::fill(&mut bytes).map_err(|e| io::Error::other(e.to_string()))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry follows each stage's life (made, placing, swapping, kept, dropped), and
    /// what a second signal removes is every stage but one being placed or that may hold an
    /// earlier output. (The
    /// test removes from a list of its own: the registry is the whole process's, and other
    /// tests' stages live in it meanwhile.)
    #[test]
    fn a_second_signal_removes_the_stages_that_hold_only_this_runs_output() {
        let d = scratch("live");
        let flag = |stage: &Stage| {
            let found = live().iter().find(|(h, ..)| *h == stage.hex).map(|e| e.2);
            found
        };
        let (plain, mut swapping) = (
            Stage::create(&d, "a").unwrap(),
            Stage::create(&d, "b").unwrap(),
        );
        let placing = Stage::create(&d, "p").unwrap();
        fs::write(plain.dir().join("frame.exr"), b"ours").unwrap();
        swapping.mark_may_hold_earlier_output().unwrap();
        placing.mark_placing();
        assert_eq!((flag(&plain), flag(&swapping)), (Some(false), Some(true)));
        assert_eq!(flag(&placing), Some(true));
        let ours = [&plain.hex, &swapping.hex, &placing.hex];
        let mine: Vec<_> = (live().iter())
            .filter(|(h, ..)| ours.contains(&h))
            .cloned()
            .collect();
        remove_unmarked(&mine);
        assert!(!plain.dir().exists(), "the run's own output goes");
        assert!(
            placing.dir().join(TOKEN).is_file(),
            "a stage being placed is left"
        );
        drop(placing);
        assert!(
            swapping.dir().join(TOKEN).is_file(),
            "a swapping stage is the sweep's"
        );
        let mut kept = Stage::create(&d, "c").unwrap();
        kept.keep();
        assert_eq!(flag(&kept), None, "a kept stage is the user's");
        let hex = plain.hex.clone();
        drop(plain);
        assert!(
            live().iter().all(|(h, ..)| *h != hex),
            "a dropped stage is forgotten"
        );
        drop((swapping, kept));
        fs::remove_dir_all(&d).unwrap();
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("specchio-stage-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    /// A live stage is never swept, a dead one is, and nothing merely shaped like one is:
    /// a folder of that name without a token, with another stage's token, or a link.
    #[cfg(target_os = "linux")]
    #[test]
    fn only_a_dead_runs_own_stage_is_swept() {
        let _serial = crate::output::serial_with_children();
        let d = scratch("sweep");
        let live = Stage::create(&d, "out").unwrap();
        let dead = Stage::create(&d, "out").unwrap();
        let dead_dir = dead.dir().to_owned();
        // A killed run: its folder stays, its lock goes (the descriptor is closed).
        dead.abandon();
        let fake = d.join(format!(".out{INFIX}{}", "0".repeat(32)));
        fs::create_dir(&fake).unwrap();
        fs::write(fake.join("notes.txt"), b"mine").unwrap();
        let borrowed = d.join(format!(".out{INFIX}{}", "1".repeat(32)));
        fs::create_dir(&borrowed).unwrap();
        fs::copy(live.dir().join(TOKEN), borrowed.join(TOKEN)).unwrap();
        let link = d.join(format!(".out{INFIX}{}", "2".repeat(32)));
        std::os::unix::fs::symlink(&dead_dir, &link).unwrap();
        let other = d.join(".out.partial-99999-notes");
        fs::write(&other, b"mine").unwrap();

        // A stage kept for the user (it holds what a failed replace could not put back)
        // loses its token: no later sweep takes it for a dead run's.
        let mut kept = Stage::create(&d, "out").unwrap();
        let kept_dir = kept.dir().to_owned();
        fs::write(kept_dir.join("old-output.txt"), b"theirs").unwrap();
        kept.keep();
        drop(kept);

        sweep_dead(&d, "out");
        assert!(
            kept_dir.join("old-output.txt").is_file(),
            "a kept stage stays"
        );
        assert!(live.dir().join(TOKEN).is_file(), "a live stage is kept");
        assert!(!dead_dir.exists(), "a dead stage is removed");
        assert!(fake.join("notes.txt").is_file(), "no token: kept");
        assert!(
            borrowed.join(TOKEN).is_file(),
            "another stage's token: kept"
        );
        assert!(fs::symlink_metadata(&link).is_ok(), "a link: kept");
        assert!(other.is_file(), "another shape: kept");
        drop(live);
        fs::remove_dir_all(&d).unwrap();
    }

    /// A planted link at a stage's token name is not written through: the create fails.
    #[cfg(unix)]
    #[test]
    fn names_are_random_and_never_reused() {
        let d = scratch("names");
        let a = Stage::create(&d, "x").unwrap();
        let b = Stage::create(&d, "x").unwrap();
        assert_ne!(a.dir(), b.dir());
        let victim = d.join("victim.txt");
        fs::write(&victim, b"keep").unwrap();
        let planted = d.join("planted");
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        assert!(sys::create_new(&planted).is_err());
        assert_eq!(fs::read(&victim).unwrap(), b"keep");
        drop((a, b));
        assert_eq!(
            fs::read_dir(&d).unwrap().count(),
            2,
            "stages removed on drop"
        );
        fs::remove_dir_all(&d).unwrap();
    }
}
