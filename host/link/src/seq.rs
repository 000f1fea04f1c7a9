//! Sequence numbers: every record the rig emits is numbered consecutively from 0 at boot
//! (wrapping at 2³²), so a jump tells exactly how many records were lost, and where.

use serde::Serialize;

/// Records lost between two records that did arrive.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Gap {
    /// The last sequence number before the gap.
    pub after_seq: u32,
    /// How many records are missing.
    pub missing: u32,
    /// The sequence number that arrived after it.
    pub resumed_at_seq: u32,
    /// Frame number (in the stream, from 0) of the record after the gap.
    pub frame: u64,
    /// Byte offset of that frame in the stream.
    pub byte_offset: u64,
}

/// The numbering went back to 0: the board restarted (reset, power cycle, watchdog).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Restart {
    /// The last sequence number before the restart.
    pub after_seq: u32,
    /// Frame number of the first record after it.
    pub frame: u64,
    /// Byte offset of that frame.
    pub byte_offset: u64,
}

/// A record numbered below the one expected (and not a restart): a duplicate or a stream that
/// was spliced.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Backwards {
    /// The sequence number expected.
    pub expected_seq: u32,
    /// The one that arrived.
    pub seq: u32,
    /// Frame number.
    pub frame: u64,
    /// Byte offset.
    pub byte_offset: u64,
}

/// What one sequence number meant.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SeqEvent {
    /// The expected one (or the first).
    InOrder,
    /// Records were lost before this one.
    Gap(Gap),
    /// The board restarted.
    Restart(Restart),
    /// Numbered below the expected one.
    Backwards(Backwards),
}

/// Follows the sequence numbers of a stream.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SeqTracker {
    /// The first sequence number seen (a stream joined mid-way does not start at 0).
    pub first_seq: Option<u32>,
    /// The last one seen.
    pub last_seq: Option<u32>,
    /// Every gap, in stream order.
    pub gaps: Vec<Gap>,
    /// Every restart.
    pub restarts: Vec<Restart>,
    /// Every backwards step.
    pub backwards: Vec<Backwards>,
    /// Records missing in all gaps.
    pub missing_records: u64,
}

impl SeqTracker {
    /// A tracker that has seen nothing.
    pub fn new() -> Self {
        SeqTracker::default()
    }

    /// Account for a record numbered `seq`, found in frame `frame` at `byte_offset`.
    pub fn observe(&mut self, seq: u32, frame: u64, byte_offset: u64) -> SeqEvent {
        let Some(last) = self.last_seq.replace(seq) else {
            self.first_seq = Some(seq);
            return SeqEvent::InOrder;
        };
        let expected = last.wrapping_add(1);
        let ahead = seq.wrapping_sub(expected);
        if ahead == 0 {
            return SeqEvent::InOrder;
        }
        if seq == 0 {
            let r = Restart {
                after_seq: last,
                frame,
                byte_offset,
            };
            self.restarts.push(r.clone());
            return SeqEvent::Restart(r);
        }
        if ahead < 1 << 31 {
            let g = Gap {
                after_seq: last,
                missing: ahead,
                resumed_at_seq: seq,
                frame,
                byte_offset,
            };
            self.missing_records += ahead as u64;
            self.gaps.push(g.clone());
            return SeqEvent::Gap(g);
        }
        let b = Backwards {
            expected_seq: expected,
            seq,
            frame,
            byte_offset,
        };
        self.backwards.push(b.clone());
        SeqEvent::Backwards(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_restarts_and_wrapping() {
        let mut t = SeqTracker::new();
        assert_eq!(t.observe(5, 0, 0), SeqEvent::InOrder);
        assert_eq!(t.observe(6, 1, 10), SeqEvent::InOrder);
        match t.observe(9, 2, 20) {
            SeqEvent::Gap(g) => assert_eq!((g.after_seq, g.missing, g.resumed_at_seq), (6, 2, 9)),
            e => panic!("{e:?}"),
        }
        assert!(matches!(t.observe(0, 3, 30), SeqEvent::Restart(_)));
        assert!(matches!(t.observe(1, 4, 40), SeqEvent::InOrder));
        assert!(matches!(t.observe(1, 5, 50), SeqEvent::Backwards(_)));
        assert_eq!(t.missing_records, 2);
        let mut w = SeqTracker::new();
        w.observe(u32::MAX - 1, 0, 0);
        assert_eq!(w.observe(u32::MAX, 1, 1), SeqEvent::InOrder);
        assert!(matches!(
            w.observe(1, 2, 2),
            SeqEvent::Gap(Gap { missing: 1, .. })
        ));
        assert_eq!(t.first_seq, Some(5));
    }
}
