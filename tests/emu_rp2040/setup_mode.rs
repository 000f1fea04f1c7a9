//! Setup mode on the emulated board, by the host's command lines over RTT (case `setup`,
//! `capstan_emu_bench::case::SETUP_COMMANDS`): the harness writes each line into RTT down channel 0
//! as a debug probe does (`capstan rig`), the board answers in the log, moves the servo, keeps
//! the amplifier at 0 V, reports live values; host-sim's session (`run_session`, the reference
//! behaviour, `sim/host/tests/setup_flow.rs`) gets the same lines at the same samples.
//!
//! No `store`: rp2040js has no flash chip behind the SSI (the boot ROM's flash routines, which
//! embassy-rp's erase and write call, are absent), so writing the settings to flash is tested
//! in host-sim only (`setup_flow.rs`, on its RAM flash). Reading works (XIP): the board boots
//! on an erased flash and says so, as host-sim's empty flash does.

pub(crate) mod board;

use super::{case, common, f, is_rest, pulse_us, ready, selected, AMP_SLICE, MS};
use crate::pins::{segments, widths_after};
use crate::setup::{emulate, Emulated};
use board::{host_sim, Board, Line, ZERO_MS};
use capstan_emu_bench::case::{board_protocol, SHOW_BURST};
use capstan_rig::command::{CommandKind, Key};
use capstan_rig::record::{Live, Record, Reply, SettingsSource};
use capstan_rig::rig::HOMING_DEG_PER_S;
use capstan_rig::setup::SETUP_DEG_PER_S;
use capstan_sim::session::SessionOutput;

fn replies(records: impl Iterator<Item = Record>) -> Vec<Reply> {
    records
        .filter_map(|r| match r {
            Record::Reply(x) => Some(x),
            _ => None,
        })
        .collect()
}

#[test]
fn setup_mode_on_the_emulated_board_answers_as_host_sim() {
    let Some(setup) = ready() else { return };
    let c = case("setup");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c.clone());
    common(&e);
    let board = Board::new(setup, &e);
    let end_ms = board.sample_of(f(&e.bench()["end_ns"]));
    let sim = host_sim(&c, &board, end_ms);
    let zero = the_replies(&board, &sim);
    let latency_ms = reply_times(&board, &sim);
    let (burst_first, burst_ms) = burst_flow(&board);
    let (lives, late, equal) = live_values(&board, &sim);
    let servo = servo_pulses(&e, &board);
    amplifier_off(&e);
    // No button press: every busy stretch counts as idle, the boot's (the first) included.
    let idle = &e.bench()["budget"]["idle"];
    eprintln!(
        "emulated board, setup: lines taken at samples {:?} ms; replies identical to \
         host-sim's (each by the next RTT poll, {latency_ms:.3} ms at most from a line's \
         writing), the zero's means to the bit ({zero:?} counts); a burst of {SHOW_BURST} \
         `show` lines: {burst_first} written at once, the last {burst_ms:.3} ms later; {lives} \
         live records, every 100 ms ({late} gaps otherwise), their counts the ADC's; \
         host-sim's live counts are the bench's codes at the same samples for {equal} of \
         {lives} (the rest: the cord moving); servo {servo}; amplifier static low \
         throughout; cycles per sample outside runs: mean {:.0}, p99.9 {} (the boot: {})",
        board.lines.iter().map(|l| l.sample).collect::<Vec<_>>(),
        f(&idle["mean"]),
        idle["p999"],
        idle["max"],
    );
}

/// Every command answered as in host-sim, at the same sample, to the bit: the same records in
/// the same order (seq), each reply and settings report equal. Returns the zero's means.
fn the_replies(board: &Board, sim: &SessionOutput) -> [f32; 2] {
    let kinds = |r: &Record| std::mem::discriminant(r);
    let ours: Vec<_> = board
        .records
        .iter()
        .map(|g| (g.seq, kinds(&g.record)))
        .collect();
    let theirs: Vec<_> = sim
        .events
        .iter()
        .map(|h| (h.seq, kinds(&h.record)))
        .collect();
    assert_eq!(ours, theirs, "the records' order");
    for (g, h) in board.records.iter().zip(&sim.events) {
        if !matches!(g.record, Record::Live(_)) {
            assert_eq!(g.record, h.record, "seq {}", g.seq);
        }
    }
    let got = replies(board.records.iter().map(|g| g.record));
    let zero = got[1].values;
    let dwell = Key::DwellMs.code() as f32;
    let want = [
        (CommandKind::Setup, [board_protocol().rest_deg, 0.0]),
        (CommandKind::Zero, zero),
        (CommandKind::Servo, [95.0, 0.0]),
        (CommandKind::Jog, [85.0, 0.0]), // 95° - 10°
        (CommandKind::Set, [dwell, 8000.0]),
        (CommandKind::Show, [0.0, 0.0]),
        (CommandKind::Leave, [0.0, 0.0]),
    ];
    let burst = [(CommandKind::Show, [0.0, 0.0]); SHOW_BURST];
    let got_kv: Vec<_> = got.iter().map(|r| (r.command, r.error, r.values)).collect();
    let want_kv: Vec<_> = want
        .iter()
        .chain(&burst)
        .map(|&(k, v)| (k, None, v))
        .collect();
    assert_eq!(got_kv, want_kv);
    // The zero, with the servo at rest since boot: bit-identical to host-sim's because the
    // board averaged the same 501 samples, each with the same noise draw (one per conversion,
    // in order) of the same plant; a window one sample longer (the chip's clock read is a µs
    // late or early, see `live_values`) would differ by about a count's noise / 501. And it is
    // each sensor's own zero (the plant's, drawn around 400 counts) plus the cord's preload.
    let p = sim.plant.config();
    let preload = p.cord.preload_n / p.sensor.n_per_count;
    let truth = sim.plant.sensor_zero_counts(0);
    // Within 5 standard deviations of a 501-sample mean (1.33 counts of noise each: 0.06).
    for k in 0..2 {
        let off = zero[k] as f64 - (truth[k] + preload);
        assert!(off.abs() < 0.3, "zero {k}: {off} counts off the plant's");
    }
    let shown: Vec<_> = board
        .records
        .iter()
        .filter_map(|g| match g.record {
            Record::Settings(s) if s.source == SettingsSource::Current => Some(s.settings),
            _ => None,
        })
        .collect();
    assert_eq!(shown.len(), 1 + SHOW_BURST);
    for s in shown {
        assert_eq!(s.protocol.dwell_ms, 8000);
        let cal = s.calibration;
        assert_eq!([cal.t1.zero_counts, cal.t2.zero_counts], zero);
    }
    zero
}

/// host-sim replied at the sample the board took each line (the zero 500 ms later); on the
/// board each reply reached the host by the first or second 1 ms RTT poll after that sample
/// (the polls have a fixed phase against the samples; a `show`'s sample, which encodes a
/// 110-byte settings record, can end after the first since the idle samples run the safety
/// checks too). Returns the
/// longest time from a line's writing to its reply, ms, but the zero's and the queued burst's.
fn reply_times(board: &Board, sim: &SessionOutput) -> f64 {
    let sim_at: Vec<u64> = sim
        .events
        .iter()
        .filter(|h| matches!(h.record, Record::Reply(_)))
        .map(|h| h.t_us)
        .collect();
    let ours: Vec<f64> = board
        .records
        .iter()
        .filter(|g| matches!(g.record, Record::Reply(_)))
        .map(|g| g.at_ns)
        .collect();
    let mut worst: f64 = 0.0;
    for ((l, sim_us), at_ns) in board.lines.iter().zip(sim_at).zip(ours) {
        let measure = if l.text == "zero" { ZERO_MS } else { 0 };
        let k = l.sample + measure;
        assert_eq!(sim_us, k * 1_000, "host-sim: {}", l.text);
        let after_ms = (at_ns - (board.origin_ns + k as f64 * MS)) / MS;
        assert!(
            (0.0..=2.0).contains(&after_ms),
            "{}: read {after_ms} ms after its sample",
            l.text
        );
        if measure == 0 && l.written_ns < board.burst_ns() {
            worst = worst.max((at_ns - l.written_ns) / MS);
        }
    }
    worst
}

/// The burst of `show` lines, more than the down channel holds: the harness wrote what fit
/// at the first poll and each later line at a later poll, once the board had read enough
/// (a line per sample). Returns (lines written at the first poll, ms until the last).
fn burst_flow(board: &Board) -> (usize, f64) {
    let burst: Vec<&Line> = board
        .lines
        .iter()
        .filter(|l| l.written_ns >= board.burst_ns())
        .collect();
    assert_eq!(burst.len(), SHOW_BURST);
    let t0 = burst[0].written_ns;
    // (At the host's first poll once due: it polls every 1 ms.)
    assert!(
        t0 >= board.burst_ns() && t0 < board.burst_ns() + MS,
        "the first burst line is written when due: {t0} ns"
    );
    let first = burst.iter().filter(|l| l.written_ns == t0).count();
    // 127 of the 128 bytes may be filled: 25 lines of 5 bytes, then the rest as the board
    // takes a line (5 bytes) per sample.
    assert_eq!(first, 127 / 5);
    let samples: Vec<u64> = burst.iter().map(|l| l.sample).collect();
    assert!(
        samples.windows(2).all(|w| w[1] == w[0] + 1),
        "one line per sample: {samples:?}"
    );
    let last_ms = (burst.last().unwrap().written_ns - t0) / MS;
    assert!(
        last_ms > 0.0 && last_ms <= (SHOW_BURST - first) as f64 + 1.0,
        "{last_ms} ms"
    );
    (first, last_ms)
}

/// Live records: one at the setup sample, then every 100 ms on the sample grid until
/// `leave`; each with the codes the bench's ADC returned at its sample, the servo angle of
/// host-sim's. host-sim's live counts are the bench's codes at host-sim's samples (the same
/// plant and noise), but while the cord moves after a servo command. Returns (records, gaps
/// other than 100 ms, host-sim's records equal to the bench's codes).
fn live_values(board: &Board, sim: &SessionOutput) -> (usize, usize, usize) {
    let live = |r: &Record| match r {
        Record::Live(l) => Some(*l),
        _ => None,
    };
    let ours: Vec<Live> = board
        .records
        .iter()
        .filter_map(|g| live(&g.record))
        .collect();
    let theirs: Vec<Live> = sim.events.iter().filter_map(|h| live(&h.record)).collect();
    let at: Vec<u64> = ours.iter().map(|l| board.live_sample(l)).collect();
    let (from, to) = (board.line("setup").sample, board.line("leave").sample);
    assert_eq!(at[0], from, "the first live record comes with setup");
    assert!(
        *at.last().unwrap() < to && at.last().unwrap() + 102 > to,
        "{at:?}"
    );
    // Every 100 ms to the sample: setup mode times its records on the sample grid (the clock
    // read wanders by about a µs from sample to sample; unrounded, a record would now and then
    // wait for the next sample, as it did before the grid).
    let gaps: Vec<u64> = at.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(gaps.iter().all(|&g| g == 100), "live gaps {gaps:?}");
    assert_eq!(ours.len(), theirs.len());
    let angles = |v: &[Live]| v.iter().map(|l| l.servo_deg).collect::<Vec<_>>();
    assert_eq!(angles(&ours), angles(&theirs));
    // The board's servo takes each new pulse 20-40 ms later than host-sim's (its frame, then
    // the plant's), and the cord follows the horn in ~0.1 s: while the servo moves (30°/s: 1 s
    // for `servo 95`, 0.33 s for `jog -10`) and 200 ms after, the two plants' tensions differ.
    let ramp_ms = |deg: f32| (deg / SETUP_DEG_PER_S * 1000.0) as u64;
    let moves = [
        (board.line("servo 95").sample, ramp_ms(30.0)),
        (board.line("jog -10").sample, ramp_ms(10.0)),
    ];
    let mut equal = 0;
    for h in &theirs {
        let k = h.t_ms as u64;
        let moving = moves.iter().any(|&(m, d)| k >= m && k < m + d + 200);
        let codes = board.codes_at(k);
        equal += (codes == (h.counts[0], h.counts[1])) as usize;
        assert!(
            moving || codes == (h.counts[0], h.counts[1]),
            "sample {k}: the bench's codes {codes:?}, host-sim's live {:?}",
            h.counts
        );
    }
    let late = gaps.iter().filter(|&&g| g != 100).count();
    (ours.len(), late, equal)
}

/// The servo's pulse through the calibration map: rest, 95° then 85° from the first 20 ms
/// frame after the line was taken (≤ 1 ms + one frame after it was written), then back to
/// rest after `leave`, monotonically, at the homing rate.
fn servo_pulses(e: &Emulated, board: &Board) -> String {
    let servo = segments(&e.bench()["servo"]);
    let pulses: Vec<_> = servo.iter().filter(|s| s.switching()).collect();
    assert!(is_rest(pulses[0].high_ns), "{servo:?}");
    let mut said = Vec::new();
    // Each move: from the first new pulse after the line, the widths go one way only, by at
    // most setup mode's 30°/s per 20 ms frame (0.6°), and end at the map's pulse for the
    // target, |Δ| / 30°/s after the line (+ a frame and a sample).
    // (+ one 0.32 µs count of the PWM, by which a frame's duty may round up.)
    let max_step_us = pulse_us(0.6) - pulse_us(0.0) + 0.33;
    for (text, from, deg) in [("servo 95", 125.0f64, 95.0f32), ("jog -10", 95.0, 85.0)] {
        let l = board.line(text);
        let moving: Vec<(f64, f64)> = widths_after(&servo, l.written_ns)
            .into_iter()
            .take_while(|&(_, w)| (w / 1e3 - pulse_us(deg)).abs() > 1.0)
            .collect();
        let reached = widths_after(&servo, l.written_ns)
            .into_iter()
            .find(|&(_, w)| (w / 1e3 - pulse_us(deg)).abs() <= 1.0);
        let (t, us) = reached.map(|(t, w)| (t, w / 1e3)).unwrap();
        let steps: Vec<f64> = moving.windows(2).map(|w| (w[1].1 - w[0].1) / 1e3).collect();
        assert!(
            steps.iter().all(|&d| d <= 0.0 && -d <= max_step_us),
            "{text}: pulse steps {steps:?} µs"
        );
        let want_s = (from - deg as f64) / SETUP_DEG_PER_S as f64;
        let after_s = (t - l.written_ns) / 1e9;
        assert!(
            after_s >= want_s - 0.021 && after_s <= want_s + 0.021,
            "{text}: the map's {} µs {after_s} s after the line; {want_s} s at 30°/s",
            pulse_us(deg)
        );
        said.push(format!(
            "{us:.2} µs ({deg}°) {after_s:.3} s after `{text}` ({} frames on the way)",
            moving.len()
        ));
    }
    let leave = board.line("leave");
    let home = widths_after(&servo, leave.written_ns);
    assert!(
        home.windows(2).all(|w| w[1].1 >= w[0].1),
        "homing: {home:?}"
    );
    let (rest_at, last) = *home.last().unwrap();
    assert!(is_rest(last), "the servo ends at rest: {home:?}");
    // 40° at 10°/s from the sample that took `leave`; the rest pulse then goes out at the
    // next frame.
    let want_s = (board_protocol().rest_deg - 85.0) as f64 / HOMING_DEG_PER_S as f64;
    let homing_s = (rest_at - leave.written_ns) / 1e9;
    // (The rest duty is reached up to half a duty count, 0.016°, before the rest angle.)
    assert!(
        homing_s >= want_s - 0.005 && homing_s <= want_s + 0.022,
        "at rest {homing_s} s after leave; homing takes {want_s} s"
    );
    said.push(format!(
        "rest {homing_s:.3} s after `leave` ({} steps)",
        home.len()
    ));
    said.join(", ")
}

/// Setup mode holds the amplifier at 0 V: its PWM pin never switches, its compare never
/// changes from 0.
fn amplifier_off(e: &Emulated) {
    let b = e.bench();
    assert_eq!(b["amp_periods"], 0, "{}", b["amp"]);
    assert!(segments(&b["amp"]).iter().all(|s| s.static_low()));
    let amp_writes = e.emulation["pwm_writes"].as_array().unwrap();
    assert!(
        amp_writes.iter().all(|w| w["slice"] != AMP_SLICE),
        "{amp_writes:?}"
    );
}
