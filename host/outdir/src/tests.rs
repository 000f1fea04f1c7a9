//! The output directory's promises, tested at every point a process can die.

use super::commit::Crash;
use super::*;
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Dies (an I/O error) after `n` changes to the disk.
struct CrashAfter(usize);

impl Crash for CrashAfter {
    fn step(&mut self) -> std::io::Result<()> {
        if self.0 == 0 {
            return Err(std::io::Error::other("simulated crash"));
        }
        self.0 -= 1;
        Ok(())
    }
}

fn scratch() -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let p = std::env::temp_dir().join(format!(
        "capstan-outdir-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&p);
    std::fs::create_dir_all(&p).unwrap();
    p
}

/// The visible files of `dir` (ours and the user's), name -> contents.
fn visible(dir: &Path) -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with(".capstan") || name.starts_with(INCOMPLETE_PREFIX) {
                continue;
            }
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read_to_string(&p).unwrap_or_default());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn set(tag: &str, names: &[String]) -> BTreeMap<String, String> {
    names
        .iter()
        .map(|n| (n.clone(), format!("{tag}:{n}")))
        .collect()
}

fn write_set(dir: &Path, files: &BTreeMap<String, String>, crash: usize) -> crate::Result<()> {
    let mut s = OutputDir::open(dir, "test", &[])?.stage()?;
    for (n, c) in files {
        s.write(n, c.as_bytes())?;
    }
    let r = s.commit_with(&mut CrashAfter(crash));
    if r.is_err() {
        s.abandon(); // the process died: no destructor runs
    }
    r
}

fn with_user_files(mut m: BTreeMap<String, String>) -> BTreeMap<String, String> {
    m.insert("notes.txt".into(), "the user's".into());
    m.insert("raw/d1_run9.csv".into(), "the user's too".into());
    m
}

const NAMES: [&str; 6] = [
    "report.html",
    "metrics.json",
    "pairs.csv",
    "raw/d1_run1.csv",
    "raw/d1_run2.csv",
    "raw/d2_run1.csv",
];

proptest! {
    // Reproducible: a fixed seed, failures persisted beside this file.
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0023_0d1e),
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("proptest-regressions"),
        )),
        ..ProptestConfig::default()
    })]

    /// For any old set, any new set and any point of interruption, the directory holds the
    /// complete old set or the complete new set once it is opened again, and the user's own
    /// files are untouched.
    #[test]
    fn interrupted_commit_leaves_old_or_new(
        old_mask in 1u8..64, new_mask in 1u8..64, crash in 0usize..20,
    ) {
        let pick = |m: u8| -> Vec<String> {
            NAMES.iter().enumerate().filter(|(i, _)| m >> i & 1 == 1).map(|(_, n)| n.to_string()).collect()
        };
        let dir = scratch();
        std::fs::create_dir_all(dir.join("raw")).unwrap();
        std::fs::write(dir.join("notes.txt"), "the user's").unwrap();
        std::fs::write(dir.join("raw/d1_run9.csv"), "the user's too").unwrap();
        let old = set("old", &pick(old_mask));
        let new = set("new", &pick(new_mask));
        write_set(&dir, &old, usize::MAX).unwrap();
        let crashed = write_set(&dir, &new, crash).is_err();
        drop(OutputDir::open(&dir, "test", &[]).unwrap()); // the next run recovers
        let now = visible(&dir);
        let is_old = now == with_user_files(old.clone());
        let is_new = now == with_user_files(new.clone());
        prop_assert!(is_old || is_new, "crash at {crash}: {now:?}");
        if !crashed {
            prop_assert!(is_new);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_second_writer_is_refused_with_the_holder_named() {
    let dir = scratch();
    let first = OutputDir::open(&dir, "test", &[]).unwrap();
    let e = OutputDir::open(&dir, "test", &[]).unwrap_err().to_string();
    assert!(e.contains("in use by another capstan process"), "{e}");
    assert!(e.contains(&format!("pid {}", std::process::id())), "{e}");
    drop(first);
    OutputDir::open(&dir, "test", &[]).unwrap();
}

#[test]
fn a_command_that_fails_before_writing_leaves_no_directory_it_made() {
    let base = scratch();
    let dir = base.join("new");
    // Staged, then failed (dropped without a commit): the directory it made is gone.
    let out = OutputDir::open(&dir, "test", &["a.txt"]).unwrap();
    assert!(dir.is_dir(), "made and locked while the command runs");
    drop(out.stage().unwrap());
    assert!(!dir.exists(), "{:?}", visible(&base));
    // Committed: it stays, with its results.
    let mut s = OutputDir::open(&dir, "test", &["a.txt"])
        .unwrap()
        .stage()
        .unwrap();
    s.write("a.txt", b"a").unwrap();
    s.commit().unwrap();
    assert_eq!(std::fs::read(dir.join("a.txt")).unwrap(), b"a");
    // A directory the user made is never removed, empty or not.
    let theirs = base.join("theirs");
    std::fs::create_dir(&theirs).unwrap();
    drop(OutputDir::open(&theirs, "test", &["a.txt"]).unwrap());
    assert!(theirs.is_dir());
    // The parents it made for a nested directory go with it (`--out a/b/c` with no `a`), up
    // to the first that was there; one something was put in since stays, with those above.
    let nested = theirs.join("a/b/c");
    drop(OutputDir::open(&nested, "test", &["a.txt"]).unwrap());
    assert!(
        !theirs.join("a").exists() && theirs.is_dir(),
        "{:?}",
        visible(&base)
    );
    let out = OutputDir::open(&nested, "test", &["a.txt"]).unwrap();
    std::fs::write(theirs.join("a/note.txt"), "mine").unwrap();
    drop(out);
    assert!(!theirs.join("a/b").exists(), "{:?}", visible(&base));
    assert!(theirs.join("a/note.txt").is_file());
}

#[test]
fn a_finished_command_leaves_its_results_and_no_lock_file() {
    let dir = scratch();
    let out = OutputDir::open(&dir, "test", &["a.txt"]).unwrap();
    assert!(dir.join(LOCK).exists(), "held while the command runs");
    let mut s = out.stage().unwrap();
    s.write("a.txt", b"a").unwrap();
    s.commit().unwrap();
    assert!(!dir.join(LOCK).exists(), "{:?}", visible(&dir));
    // A lock file that is not ours any more (unlinked, another made) is left to its holder.
    let first = OutputDir::open(&dir, "test", &[]).unwrap();
    std::fs::remove_file(dir.join(LOCK)).unwrap();
    let second = OutputDir::open(&dir, "test", &[]).unwrap();
    drop(first);
    assert!(
        dir.join(LOCK).exists(),
        "the second holder's lock file stays"
    );
    drop(second);
    assert!(!dir.join(LOCK).exists());
}

#[cfg(unix)]
#[test]
fn links_and_files_we_did_not_write_are_refused_never_replaced_or_written_through() {
    let dir = scratch();
    let outside = scratch();
    std::fs::write(outside.join("precious.html"), "keep me").unwrap();
    std::os::unix::fs::symlink(outside.join("precious.html"), dir.join("report.html")).unwrap();
    // Refused when the directory is opened, before any work ...
    let e = OutputDir::open(&dir, "test", &["report.html"]).unwrap_err();
    assert!(
        chain(&e).contains("is a symbolic link that `capstan test` did not write"),
        "{}",
        chain(&e)
    );
    // ... and at the commit, for a set that did not name it up front.
    let e = write_set(&dir, &set("new", &["report.html".into()]), usize::MAX).unwrap_err();
    assert!(chain(&e).contains("did not write"), "{}", chain(&e));
    assert_eq!(
        std::fs::read_to_string(outside.join("precious.html")).unwrap(),
        "keep me"
    );
    assert!(std::fs::symlink_metadata(dir.join("report.html"))
        .unwrap()
        .file_type()
        .is_symlink());
    // The user's own file under a name we write: refused the same way, and kept.
    std::fs::write(dir.join("metrics.json"), "the user's").unwrap();
    let e = OutputDir::open(&dir, "test", &["metrics.json"]).unwrap_err();
    assert!(
        chain(&e).contains("is a file that `capstan test` did not write"),
        "{}",
        chain(&e)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("metrics.json")).unwrap(),
        "the user's"
    );
    // A refused directory is left as it was found: no lock file (adversarial pass 2, 10a).
    assert!(!dir.join(LOCK).exists());
    assert!(OutputDir::open(&dir, "test", &["other.json"]).is_ok());
    // A linked or plain-file sub-directory is refused before any work, and nothing lands
    // outside.
    std::os::unix::fs::symlink(&outside, dir.join("raw")).unwrap();
    let never = |_: &str| false;
    let e = OutputDir::open_with(&dir, "test", &[], &[("raw", &never)]).unwrap_err();
    assert!(chain(&e).contains("symbolic link"), "{}", chain(&e));
    let e = write_set(&dir, &set("new", &["raw/x.csv".into()]), usize::MAX).unwrap_err();
    assert!(chain(&e).contains("symbolic link"), "{}", chain(&e));
    assert!(!outside.join("x.csv").exists());
    std::fs::remove_file(dir.join("raw")).unwrap();
    std::fs::write(dir.join("raw"), "a file").unwrap();
    let e = OutputDir::open_with(&dir, "test", &[], &[("raw", &never)]).unwrap_err();
    assert!(
        chain(&e).contains("is a file where capstan test writes a directory"),
        "{}",
        chain(&e)
    );
}

#[test]
fn a_set_that_fails_late_is_kept_and_the_error_says_where() {
    let dir = scratch();
    let mut s = OutputDir::open(&dir, "test", &[]).unwrap().stage().unwrap();
    s.write("pairs.csv", b"run,step\n1,1\n").unwrap();
    s.keep_on_failure(|_| {});
    // Something in the way appears while the work runs: the commit is refused.
    std::fs::create_dir_all(dir.join("pairs.csv")).unwrap();
    let e = chain(&s.commit().unwrap_err());
    let kept = e.rsplit("the results are kept in ").next().unwrap();
    assert_eq!(
        std::fs::read_to_string(Path::new(kept).join("pairs.csv")).unwrap(),
        "run,step\n1,1\n",
        "{e}"
    );
}

#[test]
fn a_set_dropped_after_work_worth_keeping_is_kept_and_said_where() {
    static SAID: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    fn say(kept: &Path) {
        SAID.lock().unwrap().push(kept.to_path_buf());
    }
    let dir = scratch();
    let mut s = OutputDir::open(&dir, "test", &[]).unwrap().stage().unwrap();
    s.write("pairs.csv", b"run,step\n1,1\n").unwrap();
    s.keep_on_failure(say);
    let kept = s.kept_path();
    drop(s); // an error before the commit
    assert_eq!(SAID.lock().unwrap().as_slice(), std::slice::from_ref(&kept));
    assert_eq!(
        std::fs::read_to_string(kept.join("pairs.csv")).unwrap(),
        "run,step\n1,1\n"
    );
}

#[test]
fn an_abandoned_staging_directory_is_kept_not_deleted() {
    let dir = scratch();
    let mut s = OutputDir::open(&dir, "test", &[]).unwrap().stage().unwrap();
    s.write("pairs.csv", b"run,step\n1,1\n").unwrap();
    s.abandon(); // killed: the lock goes with the process
    let out = OutputDir::open(&dir, "test", &[]).unwrap();
    assert_eq!(out.recovered.len(), 1, "{:?}", out.recovered);
    let kept: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(INCOMPLETE_PREFIX)
        })
        .collect();
    assert_eq!(kept.len(), 1);
    assert_eq!(
        std::fs::read_to_string(kept[0].path().join("pairs.csv")).unwrap(),
        "run,step\n1,1\n"
    );
}

#[test]
fn a_failed_set_leaves_the_old_one_and_no_staging() {
    let dir = scratch();
    write_set(&dir, &set("old", &["a.csv".into()]), usize::MAX).unwrap();
    {
        let mut s = OutputDir::open(&dir, "test", &[]).unwrap().stage().unwrap();
        s.write("a.csv", b"half").unwrap();
        // an error: the set is dropped
    }
    assert_eq!(visible(&dir), set("old", &["a.csv".into()]));
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.starts_with(STAGING_PREFIX)),
        "{names:?}"
    );
}

#[cfg(unix)]
#[test]
fn an_unwritable_directory_fails_before_any_work() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    let probe = dir.join("probe");
    if std::fs::write(&probe, "").is_ok() {
        return; // running as root: permissions do not bind
    }
    let e = OutputDir::open(&dir, "test", &[]).unwrap_err();
    assert!(
        chain(&e).contains("cannot write to the output directory"),
        "{}",
        chain(&e)
    );
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn another_commands_results_are_neither_replaced_nor_removed() {
    let dir = scratch();
    let logged = set("log", &["pairs.csv".into(), "raw.csv".into()]);
    let mut s = OutputDir::open(&dir, "log", &[]).unwrap().stage().unwrap();
    for (n, c) in &logged {
        s.write(n, c.as_bytes()).unwrap();
    }
    s.commit().unwrap();
    // A campaign into the session's directory: refused before any work.
    let e = OutputDir::open(&dir, "simulate", &["pairs.csv"]).unwrap_err();
    assert!(
        chain(&e).contains("holds the results of `capstan log`"),
        "{}",
        chain(&e)
    );
    // A report beside it replaces nothing of the session's, and removes nothing of it later.
    write_kind(&dir, "analyze", &["report.html"]);
    write_kind(&dir, "analyze", &["metrics.json"]);
    let mut want = logged.clone();
    want.insert("metrics.json".into(), "analyze:metrics.json".into());
    assert_eq!(visible(&dir), want);
}

fn write_kind(dir: &Path, kind: &'static str, names: &[&str]) {
    let mut s = OutputDir::open(dir, kind, names).unwrap().stage().unwrap();
    for n in names {
        s.write(n, format!("{kind}:{n}").as_bytes()).unwrap();
    }
    s.commit().unwrap();
}

#[test]
fn a_move_that_cannot_happen_is_refused_before_the_journal() {
    let dir = scratch();
    write_set(
        &dir,
        &set("old", &["a.csv".into(), "b.csv".into()]),
        usize::MAX,
    )
    .unwrap();
    // A directory where the new set has a file: found before anything is moved.
    std::fs::create_dir_all(dir.join("c.csv")).unwrap();
    let e = write_set(
        &dir,
        &set("new", &["a.csv".into(), "c.csv".into()]),
        usize::MAX,
    );
    assert!(chain(&e.unwrap_err()).contains("is a directory"));
    assert!(!dir.join(COMMIT).exists());
    std::fs::remove_dir(dir.join("c.csv")).unwrap();
    assert_eq!(visible(&dir), set("old", &["a.csv".into(), "b.csv".into()]));
    // And the directory is usable at once.
    write_set(&dir, &set("new", &["a.csv".into()]), usize::MAX).unwrap();
    assert_eq!(visible(&dir), set("new", &["a.csv".into()]));
}

#[cfg(unix)]
#[test]
fn a_linked_lock_file_is_refused_not_written_through() {
    let dir = scratch();
    let outside = scratch();
    std::fs::write(outside.join("precious.txt"), "keep me").unwrap();
    std::os::unix::fs::symlink(outside.join("precious.txt"), dir.join(LOCK)).unwrap();
    let e = OutputDir::open(&dir, "test", &[]).unwrap_err();
    assert!(chain(&e).contains("not a plain file"), "{}", chain(&e));
    assert_eq!(
        std::fs::read_to_string(outside.join("precious.txt")).unwrap(),
        "keep me"
    );
}

#[test]
fn a_process_exiting_at_once_keeps_its_open_sets_where_it_says() {
    let dir = scratch();
    let mut s = OutputDir::open(&dir, "test", &[]).unwrap().stage().unwrap();
    s.write("pairs.csv", b"run,step\n1,1\n").unwrap();
    // What a second signal does before `exit`: the staging directory, visible, named.
    let kept = staged::keep_sets(|p| p.starts_with(&dir));
    assert_eq!(kept.len(), 1);
    let name = kept[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(kept[0].parent() == Some(dir.as_path()) && name.starts_with(INCOMPLETE_PREFIX));
    assert_eq!(
        std::fs::read_to_string(kept[0].join("pairs.csv")).unwrap(),
        "run,step\n1,1\n"
    );
    s.abandon(); // the process is gone: no destructor runs
                 // The next run into the directory finds nothing to recover and the kept work in place.
    let out = OutputDir::open(&dir, "test", &[]).unwrap();
    assert!(out.recovered.is_empty(), "{:?}", out.recovered);
    assert!(kept[0].join("pairs.csv").exists());
}

/// A lock taken on a lock file that was then unlinked (a refused process removes its lock
/// file; a second process had opened it just before) is not the directory's lock: the check
/// after locking sees it, and `take_lock` locks the file at the path instead (adversarial read
/// s35, D1: two processes wrote one directory at once, and the second moved the first's live
/// work to `incomplete-`).
#[test]
fn a_lock_on_an_unlinked_lock_file_is_not_the_directorys_lock() {
    let dir = scratch();
    let stale = lock_file_at(&dir).unwrap();
    std::fs::remove_file(dir.join(LOCK)).unwrap();
    assert!(!still_at_path(&stale, &dir.join(LOCK)));
    drop(stale);
    let f = take_lock(&dir).unwrap();
    assert!(still_at_path(&f, &dir.join(LOCK)));
    // While it is held, no other open of the directory gets in.
    let e = OutputDir::open(&dir, "test", &["a.json"]).unwrap_err();
    assert!(
        chain(&e).contains("in use by another capstan process"),
        "{}",
        chain(&e)
    );
}

/// A refused open still says what its recovery kept (adversarial read s35, D1's last point: an
/// earlier run's staging directory was moved to `incomplete-` without a word).
#[test]
fn a_refused_open_says_what_it_kept() {
    let dir = scratch();
    let staging = dir.join(format!("{STAGING_PREFIX}999-1"));
    std::fs::create_dir_all(&staging).unwrap();
    std::fs::write(staging.join("pairs.csv"), "x").unwrap();
    std::fs::write(dir.join("metrics.json"), "the user's").unwrap();
    let e = format!(
        "{:#}",
        OutputDir::open(&dir, "test", &["metrics.json"]).unwrap_err()
    );
    assert!(
        e.contains("did not write") && e.contains("note: an earlier run"),
        "{e}"
    );
    assert!(dir
        .join(format!("{INCOMPLETE_PREFIX}999-1"))
        .join("pairs.csv")
        .exists());
}
