//! Parts failing as real parts do (issue 38): the ADC's own offset and noise (what an
//! unplugged sensor reads), a channel frozen at its last voltage, a servo that stops following,
//! a preload other than the tare's reference, a cord that parts at rest, and the amplifier's
//! filter discharging slower while its pin is released.

use super::*;

fn plant_with(cfg: PlantConfig, seed: u64) -> Plant {
    let mut cord = CordSetup::new(360.0, Model::euler_eytelwein(0.115));
    cord.press_at_us = None;
    Plant::new_at(cfg, &[cord], seed, 0).unwrap()
}

/// Mean and sd of `n` conversions of `ch`, one per ms.
fn stats(p: &mut Plant, ch: Channel, n: u64) -> (f64, f64) {
    let t0 = p.now_us();
    let xs: std::vec::Vec<f64> = (1..=n)
        .map(|k| {
            p.advance_to(t0 + k * MS);
            p.read_counts(0, ch).unwrap() as f64
        })
        .collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}

#[test]
fn an_unplugged_sensor_reads_the_adcs_floor_its_offset_and_noise() {
    let cfg = PlantConfig {
        adc: AdcConfig::RP2040,
        ..PlantConfig::default()
    };
    let mut p = plant_with(cfg, 21);
    p.inject(Injection {
        kind: InjectionKind::SensorUnplugged(Channel::T1),
        cord: 0,
        after_trigger_us: 0,
    })
    .unwrap();
    p.set_trigger(0, true);
    p.advance_to(10 * MS);
    let (mean, sd) = stats(&mut p, Channel::T1, 4_000);
    // A Pico reads 10-20 counts with its input grounded. (The sd is the ADC's 1 count and
    // the rounding's 1/√12: 1.04.)
    assert!(
        (mean - 15.0).abs() < 0.1 && (sd - 1.041).abs() < 0.05,
        "{mean} {sd}"
    );
    // The other channel: its sensor's 1.33 counts, the ADC's 1 count, the rounding: 1.69.
    let (mean, sd) = stats(&mut p, Channel::T2, 4_000);
    let zero = p.sensor_zero_counts(0)[1];
    assert!((mean - (zero + 15.0 + 0.1 / 0.015)).abs() < 0.2, "{mean}");
    assert!((sd - 1.691).abs() < 0.06, "{sd}");
    // read_both is still the same two conversions.
    let mut a = plant_with(cfg, 22);
    let mut b = plant_with(cfg, 22);
    for k in 1..200 {
        a.advance_to(k * MS);
        b.advance_to(k * MS);
        let two = [b.read_counts(0, Channel::T1), b.read_counts(0, Channel::T2)];
        assert_eq!(a.read_both(0), two);
    }
}

#[test]
fn a_frozen_channel_holds_its_last_value_under_the_adcs_noise_only() {
    for adc in [AdcConfig::IDEAL, AdcConfig::RP2040] {
        let cfg = PlantConfig {
            adc,
            ..PlantConfig::default()
        };
        let mut p = plant_with(cfg, 23);
        hold(&mut p, 100.0, 10.0);
        let t2_before = p.truth(0).t2_n;
        p.inject(Injection {
            kind: InjectionKind::Frozen(Channel::T2),
            cord: 0,
            after_trigger_us: 0,
        })
        .unwrap();
        p.set_trigger(0, true);
        p.advance_to(p.now_us() + MS);
        let held = stats(&mut p, Channel::T2, 2_000);
        // The cord goes on: a step to 80° raises T2 by several N; the reading does not move.
        hold(&mut p, 80.0, 10.0);
        assert!(p.truth(0).t2_n > t2_before + 3.0);
        let after = stats(&mut p, Channel::T2, 2_000);
        assert!(
            (after.0 - held.0).abs() < 0.2,
            "{adc:?}: {held:?} {after:?}"
        );
        // (A count of ADC noise reads 1.04 sd after rounding; none, 0.)
        let want = if adc.noise_sd_counts > 0.0 {
            1.041
        } else {
            0.0
        };
        assert!((after.1 - want).abs() < 0.06, "{adc:?}: {after:?}");
    }
}

#[test]
fn a_stalled_servo_stays_where_it_is() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 24);
    hold(&mut p, 110.0, 10.0);
    let before = p.truth(0);
    p.inject(Injection {
        kind: InjectionKind::ServoStall,
        cord: 0,
        after_trigger_us: 0,
    })
    .unwrap();
    p.set_trigger(0, true);
    hold(&mut p, 90.0, 10.0);
    let after = p.truth(0);
    assert_eq!(after.angle_deg, before.angle_deg);
    assert!(
        (after.t1_n - before.t1_n).abs() < 1e-9,
        "{before:?} {after:?}"
    );
}

#[test]
fn a_preload_below_the_tare_reference_and_a_cord_parting_at_rest() {
    let mut cfg = PlantConfig::default();
    cfg.cord.preload_n = 0.02;
    let mut p = plant_with(cfg, 25);
    p.advance_to(100 * MS);
    assert!((p.truth(0).t1_n - 0.02).abs() < 1e-9);
    // At rest with the drive on: T1 below, T2 above the preload; then the cord parts.
    hold(&mut p, 125.0, 10.0);
    let t = p.truth(0);
    assert!(t.t1_n < 0.02 && t.t2_n > 0.02 && t.t2_n < 0.04, "{t:?}");
    p.inject(Injection {
        kind: InjectionKind::CordBreak,
        cord: 0,
        after_trigger_us: 0,
    })
    .unwrap();
    p.set_trigger(0, true);
    p.advance_to(p.now_us() + 10 * MS);
    let t = p.truth(0);
    assert_eq!((t.t1_n, t.t2_n, t.broken), (0.0, 0.0, true));
}

#[test]
fn a_released_amplifier_pin_discharges_through_the_pull_down() {
    // 4.7 kΩ + 2.2 kΩ, 1 µF: 6.9 ms; the drive below 1 % 32 ms after the release.
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 26);
    hold(&mut p, 125.0, 10.0);
    let t0 = p.now_us();
    p.release_amp(0);
    let mut below = None;
    for k in 1..600 {
        p.advance_to(t0 + k * 100);
        if below.is_none() && p.drive().drive_v < 0.1 {
            below = Some(k as f64 * 0.1);
        }
    }
    let ms = below.unwrap();
    assert!((ms - 4.605 * 6.9).abs() < 0.3, "{ms} ms");
    // Driven low instead: 4.7 ms, 22 ms.
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 26);
    hold(&mut p, 125.0, 10.0);
    let t0 = p.now_us();
    p.set_amp_duty(0, 0, AMP_MAX_DUTY);
    p.advance_to(t0 + 22_000);
    assert!(p.drive().drive_v < 0.1 + 1e-3, "{:?}", p.drive());
}
