//! The simulated board on the command line (`capstan_simboard`): its options (`--sim DIR`
//! and `--sim-*`, shared by `capstan rig` and `capstan log`), its records as the link's
//! events, and the board as a [`RigLink`]: each command line is sent to the board in DIR (the
//! journal replayed, then the line, then [`capstan_simboard::IDLE_MS`] at the bench), and the
//! records it made are what the link gives back.

use capstan_link::frame::Event;
use capstan_link::rig::{LinkError, RigLink};
use capstan_simboard::{SimBoard, SimOptions};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::Duration;

/// The options that choose a simulated board (given with `capstan rig` and `capstan log`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SimArgs {
    /// A simulated board kept in DIR instead of a real one (created on first use: a new,
    /// unconfigured board). Bench actions are commands: `capstan rig --sim DIR bench ...`.
    #[arg(long, value_name = "DIR")]
    pub sim: Option<PathBuf>,

    /// Simulated board, when created: seed of its sensors' hidden errors and its noise.
    #[arg(long, value_name = "N", requires = "sim")]
    pub sim_seed: Option<u64>,

    /// Simulated board, when created: friction coefficient of its cord [default: 0.115].
    #[arg(long, value_name = "MU", requires = "sim")]
    pub sim_mu: Option<f64>,

    /// Simulated board, when created: the cord's true wrap, deg [default: 360].
    #[arg(long, value_name = "DEG", requires = "sim")]
    pub sim_wrap_deg: Option<f64>,

    /// Simulated board, when created: a catalogue effect, NAME=VALUE (repeatable), as in
    /// `capstan simulate --effect`.
    #[arg(long = "sim-effect", value_name = "NAME=VALUE", requires = "sim")]
    pub sim_effects: Vec<String>,

    /// Simulated board, when created: noise profile, `quiet` or `thesis` (as `simulate`).
    #[arg(long, value_name = "PROFILE", requires = "sim")]
    pub sim_noise: Option<String>,
}

impl SimArgs {
    /// The board these options choose.
    pub fn options(&self) -> SimOptions {
        SimOptions {
            dir: self.sim.clone(),
            seed: self.sim_seed,
            mu: self.sim_mu,
            wrap_deg: self.sim_wrap_deg,
            effects: self.sim_effects.clone(),
            noise: self.sim_noise.clone(),
        }
    }

    /// Open the board these options choose; a new board's sentence is said on stderr.
    pub fn open(&self) -> anyhow::Result<SimBoard> {
        Ok(SimBoard::open(&self.options(), &mut |l| {
            crate::errln!("{l}")
        })?)
    }
}

/// The simulated board's records as the link's events (what a board's decoded stream gives).
pub fn link_events(events: Vec<capstan_simboard::Event>) -> Vec<Event> {
    (events.into_iter())
        .map(|e| Event::Record {
            seq: e.seq,
            record: e.record,
        })
        .collect()
}

/// A [`RigLink`] to a simulated board.
pub struct SimLink {
    board: SimBoard,
    queue: VecDeque<Event>,
}

impl SimLink {
    /// A link to `board`.
    pub fn new(board: SimBoard) -> Self {
        SimLink {
            board,
            queue: VecDeque::new(),
        }
    }

    /// The board.
    pub fn board(&mut self) -> &mut SimBoard {
        &mut self.board
    }
}

impl RigLink for SimLink {
    fn send_line(&mut self, line: &str) -> Result<(), LinkError> {
        let events = self.board.send(line).map_err(LinkError::broken)?;
        self.queue.extend(link_events(events));
        Ok(())
    }

    fn poll(&mut self, _timeout: Duration) -> Result<Vec<Event>, LinkError> {
        // Everything the line produced is here already: the board ran in virtual time.
        Ok(self.queue.drain(..).collect())
    }
}
