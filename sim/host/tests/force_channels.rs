//! N force-controlled channels on one drive (issue 43): each holds its own T2 target through
//! its own firmware and servo; the drive carries their sum.

use capstan_sim::force::channels;
use capstan_sim::two_control::{run_two_control, TRACKING_WINDOW};
use capstan_tracking::steps;

#[test]
fn two_and_four_channels_each_hold_their_targets_on_one_drive() {
    for n in [2, 4] {
        let r = run_two_control(&channels(n)).unwrap();
        for (k, ch) in r.channels.iter().enumerate() {
            let end = ch.end.unwrap();
            assert_eq!(
                (end.pairs, end.fault),
                (4, None),
                "{n} channels, ch{}",
                k + 1
            );
            let st = steps(&capstan_sim::force::trace_of(&ch.log), TRACKING_WINDOW);
            let worst = st.iter().map(|s| s.ss_error_pct.abs()).fold(0.0, f64::max);
            let over = st.iter().map(|s| s.overshoot_pct).fold(0.0, f64::max);
            eprintln!(
                "{n} channels, ch{}: {} steps, worst |ss| {worst:.2} %, overshoot {over:.1} %",
                k + 1,
                st.len()
            );
            assert!(
                worst <= 3.0 && over <= 15.0,
                "{n} ch{}: {worst} {over}",
                k + 1
            );
        }
        let d = r.drive;
        eprintln!(
            "{n} channels: inrush {:.2} A / {:.1} W, running {:.2} A / {:.2} W, mean {:.2} W",
            d.peak_current_a,
            d.peak_power_w,
            d.running_current_a,
            d.running_power_w,
            d.mean_power_w
        );
        // The inrush is the spin-up's (all channels at their preload): the same for 2 and 4.
        assert!(d.peak_current_a > d.running_current_a);
        // Cross-talk: the holding channels' T2 ends where it was (feedback), each step a
        // transient through the drive's speed.
        assert!(!r.force_crosstalk.is_empty());
        for c in &r.force_crosstalk {
            let after = (c.observer_t2_after_n / c.observer_t2_before_n - 1.0).abs();
            assert!(after < 0.02, "{c:?}");
        }
    }
}
