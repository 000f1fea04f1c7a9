//! Force control on the release image (issue 43, case `force`): the host loads the thesis fit's
//! law by `set` lines over RTT (as `capstan rig load-model` sends them), sets force mode and
//! arms a run that a press at the rig starts; the board holds T2 at 5 then 10 N on a 720° cord, the servo's dead band in the
//! plant. Against host-sim's session with the same lines at the same samples: the same replies,
//! and pairs that agree (not to the bit: the emulated servo takes a pulse a frame later than
//! host-sim's, and in force mode the pulse moves every 10 ms).

use super::{case, common, f, ready, selected};
use crate::setup::emulate;
use crate::setup_mode::board::{host_sim, Board};
use capstan_rig::record::{Record, RunEnd, StepPair};

fn pairs(records: impl Iterator<Item = Record>) -> Vec<StepPair> {
    records
        .filter_map(|r| match r {
            Record::Pair(p) => Some(p),
            _ => None,
        })
        .collect()
}

#[test]
fn force_control_on_the_emulated_board_holds_its_targets_as_host_sim() {
    let Some(setup) = ready() else { return };
    let c = case("force");
    if !selected(&c) {
        return;
    }
    // The case's cord is host-sim's thesis fit.
    assert_eq!(
        capstan_emu_bench::case::thesis_fit(),
        capstan_sim::force::thesis_fit()
    );
    let e = emulate(setup, c.clone());
    common(&e);
    let board = Board::new(setup, &e);
    let end_ms = board.sample_of(f(&e.bench()["end_ns"]));
    let sim = host_sim(&c, &board, end_ms);
    // Every line answered without a refusal, on the board as in host-sim.
    let refusals: Vec<_> = board
        .records
        .iter()
        .filter_map(|g| match g.record {
            Record::Reply(r) if r.error.is_some() => Some(r),
            _ => None,
        })
        .collect();
    assert!(refusals.is_empty(), "{refusals:?}");
    // The burst of `show` during the run: every settings report there, in order, equal to
    // host-sim's (some waited a sample on the board: a long record is not encoded in a busy
    // sample), and no record lost (the sequence numbers consecutive). To the bit but the tare's
    // zeros: means of the ADC's codes, which differ by a fraction of a count in this case (the
    // emulated servo takes its pulse a frame later than host-sim's).
    let reports = |records: &mut dyn Iterator<Item = Record>| -> Vec<_> {
        records
            .filter_map(|r| match r {
                Record::Settings(s) => Some(s),
                _ => None,
            })
            .collect()
    };
    let board_reports = reports(&mut board.records.iter().map(|g| g.record));
    let sim_reports = reports(&mut sim.events.iter().map(|e| e.record));
    assert!(board_reports.len() > capstan_emu_bench::case::FORCE_SHOW_BURST);
    assert_eq!(board_reports.len(), sim_reports.len());
    for (i, (a, b)) in board_reports.iter().zip(&sim_reports).enumerate() {
        assert_eq!(a.source, b.source, "report {i}");
        for (s, (x, y)) in capstan_wire::Setting::ALL
            .iter()
            .zip(a.settings.fields().iter().zip(b.settings.fields()))
        {
            let zero = matches!(s.name(), "t1_zero" | "t2_zero");
            let (fx, fy) = (f32::from_bits(*x), f32::from_bits(y));
            assert!(
                *x == y || (zero && (fx - fy).abs() < 0.05),
                "report {i}: {} {x:#x} on the board, {y:#x} in host-sim",
                s.name()
            );
        }
    }
    let gaps = board
        .records
        .windows(2)
        .filter(|w| w[1].seq != w[0].seq.wrapping_add(1));
    assert_eq!(gaps.count(), 0, "records lost");
    let ours = pairs(board.records.iter().map(|g| g.record));
    let theirs = pairs(sim.events.iter().map(|e| e.record));
    let end: Vec<RunEnd> = board
        .records
        .iter()
        .filter_map(|g| match g.record {
            Record::RunEnd(x) => Some(x),
            _ => None,
        })
        .collect();
    assert_eq!(end.len(), 1, "one run");
    assert_eq!((end[0].pairs, end[0].fault), (2, None));
    assert_eq!(ours.len(), 2);
    for (p, q) in ours.iter().zip(&theirs) {
        assert_eq!(p.t2_target_n, q.t2_target_n);
        assert!((p.t2.mean_n / p.t2_target_n - 1.0).abs() < 0.03, "{p:?}");
        assert!(
            (p.t2.mean_n / q.t2.mean_n - 1.0).abs() < 0.015,
            "{p:?} vs {q:?}"
        );
        assert!((p.angle_deg - q.angle_deg).abs() < 1.0, "{p:?} vs {q:?}");
        assert!((65.0..125.0).contains(&p.angle_deg), "{p:?}");
    }
    assert_eq!(
        ours.iter().map(|p| p.t2_target_n).collect::<Vec<_>>(),
        [5.0, 10.0]
    );
    // Every raw record carries its target: 0 before the first segment, then 5 and 10 N.
    let targets: Vec<f32> = board
        .records
        .iter()
        .filter_map(|g| match g.record {
            Record::Raw(r) => Some(r.t2_target_n),
            _ => None,
        })
        .collect();
    assert!(targets.contains(&0.0) && targets.contains(&5.0) && targets.contains(&10.0));
    let busy = &e.bench()["budget"]["run"];
    eprintln!(
        "emulated board, force: T2 {:.3} N for 5 N, {:.3} N for 10 N (host-sim {:.3}, {:.3}); \
         servo at {:.1}° and {:.1}°; cycles per sample during the run: mean {:.0}, p99.9 {}, \
         max {}",
        ours[0].t2.mean_n,
        ours[1].t2.mean_n,
        theirs[0].t2.mean_n,
        theirs[1].t2.mean_n,
        ours[0].angle_deg,
        ours[1].angle_deg,
        f(&busy["mean"]),
        busy["p999"],
        busy["max"]
    );
}
