//! The simulated board as a [`RigLink`]: each command line is sent to the board in DIR (the
//! journal replayed, then the line, then [`IDLE_MS`] at the bench), and the records it made
//! are what the link gives back.

use super::{SimBoard, IDLE_MS};
use capstan_link::frame::Event;
use capstan_link::rig::RigLink;
use capstan_sim::session::Step;
use std::collections::VecDeque;
use std::time::Duration;

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
    fn send_line(&mut self, line: &str) -> anyhow::Result<()> {
        let steps = [Step::Send(line.to_string()), Step::Wait(IDLE_MS)];
        let done = self.board.advance(&steps)?;
        self.queue.extend(done.events);
        if let Some(l) = done.unanswered.first() {
            anyhow::bail!(
                "the simulated board did not answer `{l}` within {} s of its time (its firmware \
                 loop is stuck?)",
                capstan_sim::session::REPLY_TIMEOUT_MS / 1000
            );
        }
        Ok(())
    }

    fn poll(&mut self, _timeout: Duration) -> anyhow::Result<Vec<Event>> {
        // Everything the line produced is here already: the board ran in virtual time.
        Ok(self.queue.drain(..).collect())
    }
}
