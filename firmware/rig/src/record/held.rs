//! The records a sink holds back, in order: until the sample's outputs are applied (every
//! record), and a long record further, to a sample with time to spare for it.
//!
//! Encoding a record that carries the 47 settings (`run_start`, `settings`) costs the board
//! ~30 000 cycles (~240 µs), a quarter of a 1 ms sample (the emulated board's `setup` case: a
//! sample that answers `show` against one that does not); in force mode every tenth sample
//! already takes ~57 000 (46 %) for the controller. A `show` taken in such a sample would end
//! it past 70 %. So a sink writes a long record only while the sample has used at most
//! [`LONG_RECORD_UNTIL_US`], and one a sample at most; otherwise the record, and every record
//! behind it, wait for the next sample. The host sees them a millisecond later, in the same
//! order.

use super::Record;

/// A long record is written in a sample only while at most this much of it has gone, µs (of
/// 1000): with the record's ~240 µs and the small records' few µs the sample ends by ~560 µs,
/// under the 60 % of its period the loop budget allows (`tests/emu_rp2040`, `budget.rs`).
pub const LONG_RECORD_UNTIL_US: u64 = 300;

impl Record {
    /// It carries the settings: encoding it takes long (~240 µs on the board, against a few
    /// µs for any other record).
    pub const fn is_long(&self) -> bool {
        matches!(self, Record::RunStart(_) | Record::Settings(_))
    }
}

/// Up to `N` records with their sequence numbers, oldest first.
#[derive(Clone, Copy, Debug)]
pub struct Held<const N: usize> {
    slots: [Option<(u32, Record)>; N],
    /// The oldest's slot.
    first: usize,
    len: usize,
}

impl<const N: usize> Default for Held<N> {
    fn default() -> Self {
        Held {
            slots: [None; N],
            first: 0,
            len: 0,
        }
    }
}

impl<const N: usize> Held<N> {
    /// Records held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Nothing held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Hold one more, behind the others; `false` (and nothing held) if `N` are held already.
    pub fn push(&mut self, seq: u32, record: &Record) -> bool {
        if self.len == N {
            return false;
        }
        self.slots[(self.first + self.len) % N] = Some((seq, *record));
        self.len += 1;
        true
    }

    /// Hand the held records to `send`, oldest first, while `may` lets each go: the first it
    /// refuses, and every record behind it, stay held (in order).
    pub fn send_while(
        &mut self,
        mut may: impl FnMut(&Record) -> bool,
        mut send: impl FnMut(u32, &Record),
    ) {
        while self.len > 0 {
            let slot = &mut self.slots[self.first];
            match slot {
                Some((seq, record)) if may(record) => send(*seq, record),
                Some(_) => return,
                None => {}
            }
            *slot = None;
            self.first = (self.first + 1) % N;
            self.len -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{Reply, RunEnd, SettingsReport, SettingsSource};
    use crate::settings::Settings;
    use crate::{Calibration, Protocol};
    use capstan_wire::CommandKind;

    fn reply() -> Record {
        Record::Reply(Reply {
            command: CommandKind::Show,
            error: None,
            values: [0.0; 2],
        })
    }

    fn settings() -> Record {
        Record::Settings(SettingsReport {
            source: SettingsSource::Loaded,
            settings: Settings {
                protocol: Protocol::default(),
                calibration: Calibration::default(),
            },
        })
    }

    fn end() -> Record {
        Record::RunEnd(RunEnd {
            t_us: 5,
            pairs: 1,
            fault: None,
        })
    }

    fn sent(held: &mut Held<4>, may: impl FnMut(&Record) -> bool) -> std::vec::Vec<u32> {
        let mut out = std::vec::Vec::new();
        held.send_while(may, |seq, _| out.push(seq));
        out
    }

    #[test]
    fn a_long_record_and_those_behind_it_wait_in_order() {
        let mut held = Held::<4>::default();
        assert!(held.push(1, &reply()) && held.push(2, &settings()) && held.push(3, &end()));
        // A busy sample: the reply goes, the settings and the run's end behind it wait.
        assert_eq!(sent(&mut held, |r| !r.is_long()), [1]);
        assert_eq!(held.len(), 2);
        assert!(held.push(4, &reply()));
        // The next sample has time: everything, in order.
        assert_eq!(sent(&mut held, |_| true), [2, 3, 4]);
        assert!(held.is_empty());
    }

    #[test]
    fn a_full_hold_makes_room_by_its_oldest_alone() {
        // What the board's sink does when a record comes and N are held: the oldest goes.
        let mut held = Held::<4>::default();
        for seq in 1..=4 {
            assert!(held.push(seq, &settings()));
        }
        let mut first = true;
        assert_eq!(sent(&mut held, |_| core::mem::take(&mut first)), [1]);
        assert!(held.push(5, &reply()));
        assert_eq!(sent(&mut held, |_| true), [2, 3, 4, 5]);
    }

    #[test]
    fn it_holds_n_and_wraps_around() {
        let mut held = Held::<4>::default();
        for round in 0..3u32 {
            for i in 0..4 {
                assert!(held.push(10 * round + i, &end()));
            }
            assert!(!held.push(99, &end()), "full");
            assert_eq!(
                sent(&mut held, |_| true),
                [0, 1, 2, 3].map(|i| 10 * round + i)
            );
            assert!(held.push(10 * round + 9, &end()));
            assert_eq!(sent(&mut held, |_| true), [10 * round + 9]);
        }
        assert!(settings().is_long() && !reply().is_long() && !end().is_long());
    }
}
