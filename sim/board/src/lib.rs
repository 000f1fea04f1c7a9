//! The simulated board behind `capstan rig --sim DIR` and `capstan log --sim DIR`: the
//! firmware's own code on host-sim (`capstan_sim::session`), against a simulated rig whose force
//! sensors have hidden zero and sensitivity errors, kept in `DIR` between commands.
//!
//! A real board keeps running between two host commands: its RAM (setup mode, a latched fault,
//! settings `set` but not stored), its flash and the rig's physical state (the servo's angle, a
//! weight on a hook) all carry over. Here that state is kept honestly by replay: `DIR` holds
//! the rig's description (`sim.json`), everything that happened at the bench so far
//! (`journal.txt`, one step a line) and how many records the board has made (`state.json`);
//! each command replays the journal in virtual time (deterministic: the same seed, the same
//! records, bit for bit) and then does its own steps, and the records they produce are the
//! answer. `flash.bin` is the settings flash afterwards (for inspection; the replay rebuilds
//! it). `sim-truth.json` is what the firmware cannot see: the sensors' true zeros and
//! sensitivities, so a rehearsal's calibration can be checked.
//!
//! The cost of a command grows with the journal (about 1 s of CPU per 100 s of bench time);
//! a new `DIR` is a new, unconfigured board.
//!
//! Nothing here prints: what a command has to say comes back to the caller (a new board's
//! sentence through `say`, the records as values, the errors as [`SimError`]).

#![deny(missing_docs)]

mod config;
mod error;
pub mod steps;

pub use capstan_sim::session::Event;
pub use config::{
    SensorTruth, SimConfig, SimOptions, Truth, MAX_SENSITIVITY_ERROR, SENSITIVITY_ERROR_SD,
    ZERO_SPREAD_COUNTS,
};
pub use error::{BenchError, Result, SimError};

use capstan_sim::flash::RamFlash;
use capstan_sim::session::{run_session_observed, SessionOutput, Step, FLASH_PAGES};
use std::fs::File;
use std::path::{Path, PathBuf};

/// The rig's description.
pub const SIM_JSON: &str = "sim.json";
/// The truth the firmware cannot see.
pub const TRUTH_JSON: &str = "sim-truth.json";
/// The bench so far.
pub const JOURNAL_TXT: &str = "journal.txt";
/// Records made so far.
pub const STATE_JSON: &str = "state.json";
/// The settings flash after the last command.
pub const FLASH_BIN: &str = "flash.bin";
const LOCK: &str = ".lock";

/// After each command, the person at the bench takes this long before the next one, ms (the
/// board keeps running: live values, a servo moving to where it was sent).
pub const IDLE_MS: u32 = 2_000;

/// What the replay of the journal must reproduce.
#[derive(serde::Serialize, serde::Deserialize, Default)]
struct State {
    /// Records made by the journal's steps.
    events: usize,
    /// The last record's sequence number and boot, to check the replay.
    last: Option<(u32, u32)>,
    /// Command lines of the journal that got no answer.
    unanswered: usize,
}

/// A simulated board in its directory, locked while a command uses it.
pub struct SimBoard {
    dir: PathBuf,
    config: SimConfig,
    journal: Vec<Step>,
    state: State,
    _lock: File,
}

/// What a command's steps produced.
pub struct Advance {
    /// The records the board made, in order (with their sequence numbers, boots and virtual
    /// times).
    pub events: Vec<Event>,
    /// Command lines the board did not answer.
    pub unanswered: Vec<String>,
}

impl SimBoard {
    /// Open the board in `args.dir`, creating a new one (and saying so through `say`) if the
    /// directory does not exist or is empty.
    pub fn open(args: &SimOptions, say: &mut dyn FnMut(String)) -> Result<SimBoard> {
        let dir = args.dir.clone().ok_or(SimError::NoDir)?;
        let fresh = !dir.join(SIM_JSON).exists();
        // A new board's description is checked before anything is written: a refused option
        // leaves no directory behind that later commands would take for someone else's.
        let new_config = if fresh {
            let c = SimConfig::from_options(args)?;
            let truth = c.truth()?;
            Some((c, truth))
        } else {
            None
        };
        if fresh {
            if dir.exists() && !dir.is_dir() {
                return Err(SimError::NotADirectory(dir));
            }
            // Empty, or holding only a lock left by an earlier command that stopped early.
            let empty = match std::fs::read_dir(&dir) {
                Ok(d) => d.flatten().all(|e| e.file_name() == LOCK),
                Err(_) => !dir.exists(),
            };
            if !empty {
                return Err(SimError::NotABoard(dir));
            }
            std::fs::create_dir_all(&dir).map_err(|e| SimError::file("create", &dir, e))?;
        }
        let lock = lock(&dir)?;
        let config = if let Some((c, truth)) = new_config {
            write_json(&dir.join(SIM_JSON), &c)?;
            write_json(&dir.join(TRUTH_JSON), &truth)?;
            std::fs::write(dir.join(JOURNAL_TXT), "")?;
            write_json(&dir.join(STATE_JSON), &State::default())?;
            say(format!(
                "capstan: a new simulated board in {} (seed {}), unconfigured; its sensors' true \
                 zeros and sensitivities are in {}",
                dir.display(),
                c.seed,
                dir.join(TRUTH_JSON).display()
            ));
            c
        } else {
            let c: SimConfig = read_json(&dir.join(SIM_JSON))?;
            c.check_same(args)?;
            c
        };
        let journal_path = dir.join(JOURNAL_TXT);
        let text = std::fs::read_to_string(&journal_path)
            .map_err(|e| SimError::file("read", &journal_path, e))?;
        let journal = steps::parse_journal(&text, &journal_path)?;
        let state: State = read_json(&dir.join(STATE_JSON))?;
        Ok(SimBoard {
            dir,
            config,
            journal,
            state,
            _lock: lock,
        })
    }

    /// The board's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The rig's description.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Send one command line to the board (as the host's command channel does), then leave it
    /// [`IDLE_MS`] at the bench; the records it made. A line the board does not answer in
    /// [`capstan_sim::session::REPLY_TIMEOUT_MS`] of its time is an error.
    pub fn send(&mut self, line: &str) -> Result<Vec<Event>> {
        let steps = [Step::Send(line.to_string()), Step::Wait(IDLE_MS)];
        let done = self.advance(&steps)?;
        if let Some(l) = done.unanswered.first() {
            return Err(SimError::NoAnswer {
                line: l.clone(),
                seconds: capstan_sim::session::REPLY_TIMEOUT_MS / 1000,
            });
        }
        Ok(done.events)
    }

    /// Replay the bench so far, then do `steps`; the records they produced. The steps join the
    /// journal (the board's state now includes them).
    pub fn advance(&mut self, steps: &[Step]) -> Result<Advance> {
        let mut events = Vec::new();
        let mut a = self.advance_streamed(steps, &mut |_, mut new| {
            events.append(&mut new);
            true
        })?;
        a.events = events;
        Ok(a)
    }

    /// As [`SimBoard::advance`], handing the records each of `steps` produced to `take` as
    /// soon as the step is done, with how many of `steps` are done (the replay's records are
    /// not handed), and stopping after the step at which `take` returns false: only the steps
    /// done join the journal. The returned `events` are empty (they went to `take`).
    pub fn advance_streamed(
        &mut self,
        steps: &[Step],
        take: &mut dyn FnMut(usize, Vec<Event>) -> bool,
    ) -> Result<Advance> {
        let mut all = self.config.sensor_steps();
        all.extend(self.journal.iter().cloned());
        let mine_from = all.len();
        all.extend(steps.iter().cloned());
        let (mut seen, last) = (self.state.events, self.state.last);
        let mut diverged = false;
        let mut observe = |done: usize, events: &[Event]| {
            if done <= mine_from {
                return true;
            }
            // The replay must reproduce the records the board made before.
            if seen == self.state.events && !replays(events, seen, last) {
                diverged = true;
                return false;
            }
            let new = events[seen..].to_vec();
            seen = events.len();
            take(done - mine_from, new)
        };
        let out = run_session_observed(
            &self.config.session_spec()?,
            RamFlash::new(FLASH_PAGES),
            &all,
            &mut observe,
        )
        .map_err(|e| SimError::Setup(format!("{e:?}")))?;
        if diverged || !replays(&out.events, self.state.events, self.state.last) {
            return Err(SimError::Diverged(self.dir.clone()));
        }
        let earlier = self.state.unanswered.min(out.unanswered.len());
        let unanswered = out.unanswered[earlier..].to_vec();
        let done = out.steps_done.saturating_sub(mine_from).min(steps.len());
        self.journal.extend(steps[..done].iter().cloned());
        self.state = State {
            events: out.events.len(),
            last: out.events.last().map(|e| (e.seq, e.boot)),
            unanswered: out.unanswered.len(),
        };
        self.save(&out)?;
        Ok(Advance {
            events: Vec::new(),
            unanswered,
        })
    }

    fn save(&self, out: &SessionOutput) -> Result<()> {
        let text = steps::journal_text(&self.journal);
        write_atomic(&self.dir.join(JOURNAL_TXT), text.as_bytes())?;
        write_json(&self.dir.join(STATE_JSON), &self.state)?;
        write_atomic(&self.dir.join(FLASH_BIN), out.flash.bytes())
    }
}

/// The records of a replay reproduce the first `n` the board made before: the `n`-th is the
/// one it made last (sequence number and boot).
fn replays(events: &[Event], n: usize, last: Option<(u32, u32)>) -> bool {
    n <= events.len()
        && match (last, n.checked_sub(1)) {
            (Some(last), Some(i)) => (events[i].seq, events[i].boot) == last,
            (None, None) => true,
            _ => false,
        }
}

fn lock(dir: &Path) -> Result<File> {
    let path = dir.join(LOCK);
    let f = File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| SimError::file("open", &path, e))?;
    if f.try_lock().is_err() {
        return Err(SimError::InUse(dir.to_path_buf()));
    }
    Ok(f)
}

fn write_json<T: serde::Serialize>(path: &Path, v: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(v).expect("serialises") + "\n";
    write_atomic(path, text.as_bytes())
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| SimError::file("read", path, e))?;
    serde_json::from_str(&text).map_err(|source| SimError::Damaged {
        path: path.to_path_buf(),
        source,
    })
}

/// Write through a temporary file and a rename: a command stopped half-way leaves the old file.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(|e| SimError::file("write", &tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| SimError::file("write", path, e))
}
