//! Calibrations: servo angle -> pulse, amplifier volts -> duty, ADC counts -> newtons, and
//! where each force channel's sensitivity came from ([`CalSource`]: a run needs both measured
//! or typed by a person).

pub use capstan_wire::CalSource;

/// Period of the servo's 50 Hz PWM frame, µs.
pub const SERVO_FRAME_US: f32 = 20_000.0;

/// Servo angle to pulse width, linear between two calibration points.
///
/// The protocol's angles are *command* angles, as the thesis's Arduino sketch wrote them
/// (`myservo.write(pos)`): the default is that convention ([`ServoMap::ARDUINO_SERVO`]), so
/// 125° is the thesis's 1833 µs pulse and 65° its 1214 µs. Where the horn really goes for a
/// pulse is the servo's own business (the HS-322HD turns 0.1°/µs about 1500 µs; the simulated
/// plant models that separately), so the same command means the same tension as on the thesis's
/// rig only with this map.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ServoMap {
    /// Pulse at 0 deg, µs (default 544).
    pub pulse_at_min_us: f32,
    /// Pulse at `max_deg`, µs (default 2400).
    pub pulse_at_max_us: f32,
    /// Angle reached with `pulse_at_max_us`, deg (default 180).
    pub max_deg: f32,
}

impl Default for ServoMap {
    /// The Arduino Servo library's convention, as on the thesis's rig.
    fn default() -> Self {
        ServoMap::ARDUINO_SERVO
    }
}

impl ServoMap {
    /// The Arduino Servo library's default map, which the thesis's sketch used
    /// (`myservo.attach(9)`, then `myservo.write(pos)` for pos = 125 … 65): `MIN_PULSE_WIDTH`
    /// 544 µs at 0°, `MAX_PULSE_WIDTH` 2400 µs at 180°, linear between. pulse = 544 + angle ·
    /// (2400 − 544) / 180 µs: 125° → 1832.9 µs, 65° → 1214.2 µs. (The library's integer
    /// `map()` truncates to whole µs, 1832 and 1214: within 1 µs of this map, and inside the
    /// HS-322HD's 5 µs dead band.)
    pub const ARDUINO_SERVO: ServoMap = ServoMap {
        pulse_at_min_us: 544.0,
        pulse_at_max_us: 2_400.0,
        max_deg: 180.0,
    };

    /// Pulse width for an angle, µs (angle clamped to 0..=max).
    pub fn pulse_us(&self, angle_deg: f32) -> f32 {
        // Not `f32::clamp`: its `min <= max` assertion formats floats on panic, which links
        // ~20 KiB of float formatting into the board image. Same result (NaN stays NaN).
        let a = if angle_deg < 0.0 {
            0.0
        } else if angle_deg > self.max_deg {
            self.max_deg
        } else {
            angle_deg
        };
        self.pulse_at_min_us + (self.pulse_at_max_us - self.pulse_at_min_us) * a / self.max_deg
    }

    /// Angle commanded by a pulse width, deg (inverse of [`ServoMap::pulse_us`]).
    pub fn angle_deg(&self, pulse_us: f32) -> f32 {
        (pulse_us - self.pulse_at_min_us) / (self.pulse_at_max_us - self.pulse_at_min_us)
            * self.max_deg
    }

    /// Duty (of `max_duty`) for an angle on a 50 Hz PWM.
    pub fn duty(&self, angle_deg: f32, max_duty: u16) -> u16 {
        fraction_to_duty(self.pulse_us(angle_deg) / SERVO_FRAME_US, max_duty)
    }

    /// Angle a duty (of `max_duty`, 50 Hz PWM) commands, deg, within 0..=`max_deg` (inverse of
    /// [`ServoMap::duty`] to within one count).
    pub fn angle_for_duty(&self, duty: u16, max_duty: u16) -> f32 {
        let pulse_us = duty as f32 / max_duty.max(1) as f32 * SERVO_FRAME_US;
        let a = self.angle_deg(pulse_us);
        if a.is_nan() || a < 0.0 {
            0.0
        } else if a > self.max_deg {
            self.max_deg
        } else {
            a
        }
    }
}

/// Amplifier control voltage to PWM duty: an RC-filtered PWM pin swinging 0..`full_scale_v`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct AmpMap {
    /// Filtered output at 100 % duty, V (the pin's supply: 3.3 V).
    pub full_scale_v: f32,
    /// Power amplifier gain, drive volts per control volt (for the log: drive V = gain × control V).
    pub amp_gain: f32,
}

impl Default for AmpMap {
    fn default() -> Self {
        AmpMap {
            full_scale_v: 3.3,
            amp_gain: 4.0,
        }
    }
}

impl AmpMap {
    /// Duty for a control voltage (clamped to 0..=full scale).
    pub fn duty(&self, control_v: f32, max_duty: u16) -> u16 {
        fraction_to_duty(control_v / self.full_scale_v, max_duty)
    }

    /// Drive-motor voltage the amplifier makes from a control voltage, V.
    pub fn drive_v(&self, control_v: f32) -> f32 {
        control_v * self.amp_gain
    }
}

fn fraction_to_duty(fraction: f32, max_duty: u16) -> u16 {
    let f = if fraction.is_nan() {
        0.0
    } else {
        fraction.clamp(0.0, 1.0)
    };
    libm::roundf(f * max_duty as f32) as u16
}

/// One force channel: newtons = (counts − zero) × newtons per count.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ChannelCal {
    /// Counts at zero force.
    pub zero_counts: f32,
    /// Sensitivity, N per count.
    pub n_per_count: f32,
    /// How the sensitivity came to be: a run needs it weighed or typed, never the placeholder.
    pub source: CalSource,
    /// The zero (counts) the sensitivity was weighed or typed at. The zero in force may move
    /// at most [`ZERO_WALK_MAX_N`] from it (zeros, `set tN_zero`) before the sensitivity counts
    /// as unmeasured again: a zero walked further could be hiding a standing load.
    pub cal_zero: f32,
}

/// Largest load a tare may take as zero, N: the mean reading during the tare may differ from
/// the stored zero by at most this (beyond the cord's `tare_reference_n`). More is a weight or a
/// preload on the cord, or a wrong zero, and taken as zero it would hide that much of every
/// force from the over-force check: the run is refused (`tare_load`). 1 N is ~70 counts at
/// 0.015 N/count, far beyond a sensor's drift between calibrations.
pub const TARE_MAX_N: f32 = 1.0;

/// How far the zero in force may move from the zero a channel's sensitivity was measured at,
/// N, before that sensitivity is unmeasured (the tare's bound, [`TARE_MAX_N`]):
/// repeated zeros of up to 1 N each, or a typed zero, cannot walk it further without a weigh.
pub const ZERO_WALK_MAX_N: f32 = TARE_MAX_N;

impl ChannelCal {
    /// A channel nobody has measured: the built-in placeholder.
    pub const fn placeholder(zero_counts: f32, n_per_count: f32) -> Self {
        ChannelCal {
            zero_counts,
            n_per_count,
            source: CalSource::Placeholder,
            cal_zero: zero_counts,
        }
    }

    /// This sensitivity, measured (or typed) now at the zero in force.
    pub fn measured(self, source: CalSource) -> Self {
        ChannelCal {
            source,
            cal_zero: self.zero_counts,
            ..self
        }
    }

    /// The zero in force set to `zero_counts` (a zero measured or typed): the sensitivity is
    /// unmeasured from then on if the zero is more than [`ZERO_WALK_MAX_N`] from the one it was
    /// measured at.
    pub fn rezeroed(self, zero_counts: f32) -> Self {
        let walked = (zero_counts - self.cal_zero).abs() * self.n_per_count;
        let source = if walked > ZERO_WALK_MAX_N || walked.is_nan() {
            CalSource::Placeholder
        } else {
            self.source
        };
        ChannelCal {
            zero_counts,
            source,
            ..self
        }
    }

    /// Force for a (possibly averaged) count value, N.
    pub fn newtons(&self, counts: f32) -> f32 {
        (counts - self.zero_counts) * self.n_per_count
    }

    /// Counts that read `force_n` (inverse of [`ChannelCal::newtons`]).
    pub fn counts(&self, force_n: f32) -> f32 {
        force_n / self.n_per_count + self.zero_counts
    }

    /// Re-zero from the mean counts seen while the true force was `reference_n`.
    pub fn tare(&mut self, mean_counts: f32, reference_n: f32) {
        self.zero_counts = mean_counts - reference_n / self.n_per_count;
    }
}

/// Everything calibrated on the rig.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Calibration {
    /// T1 (servo-side) force channel.
    pub t1: ChannelCal,
    /// T2 (fixed-side) force channel.
    pub t2: ChannelCal,
    /// Force both channels carry during the tare: the cord's preload with the capstan stopped
    /// (the tension bolt's ~0.1 N), N.
    pub tare_reference_n: f32,
    /// Servo angle map.
    pub servo: ServoMap,
    /// Amplifier map.
    pub amp: AmpMap,
}

impl Default for Calibration {
    /// A 50 N sensor on a 12-bit ADC: zero at 400 counts, 0.015 N per count (−6 N .. +55 N).
    /// A placeholder: nobody measured these sensitivities, and no run uses them
    /// ([`Calibration::unmeasured`]) until they are weighed or typed.
    fn default() -> Self {
        let ch = ChannelCal::placeholder(400.0, 0.015);
        Calibration {
            t1: ch,
            t2: ch,
            tare_reference_n: 0.1,
            servo: ServoMap::default(),
            amp: AmpMap::default(),
        }
    }
}

/// Why a calibration is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum CalibrationError {
    /// A channel's sensitivity must be within [`N_PER_COUNT_RANGE`] (positive: a tension
    /// raises the reading).
    Sensitivity,
    /// A channel's zero must be within the ADC's 0..=4095 counts.
    Zero,
    /// The tare reference must be 0..10 N.
    TareReference,
    /// The servo map needs a longer pulse at `max_deg` than at 0° (not reversed), both within
    /// 400..=2600 µs, and 0 < max ≤ 360°.
    ServoMap,
    /// The amplifier needs a full scale within [`AMP_FULL_SCALE_V_RANGE`] and a gain of
    /// 0..=100.
    AmpMap,
    /// A sensitivity's source code is not one of [`CalSource`]'s, or the zero it was measured
    /// at is outside the ADC's range.
    Source,
}

impl CalibrationError {
    /// What is wrong, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            CalibrationError::Sensitivity => {
                "n_per_count must be 0.002 to 0.1 N/count (positive: a tension raises the reading)"
            }
            CalibrationError::Zero => "a zero must be within 0..=4095 counts",
            CalibrationError::TareReference => "the tare reference must be 0 to 10 N",
            CalibrationError::ServoMap => {
                "the servo pulse at servo_max_deg must be longer than at 0° (no reversed map), both in 400..=2600 µs, max_deg in (0, 360]"
            }
            CalibrationError::AmpMap => {
                "the amplifier full scale (the filtered 3V3 at 100 % duty, measured) must be 3.0 to 3.5 V and its gain in (0, 100]: a full scale typed low pins the duty at 100 %, the rail, while the log says less"
            }
            CalibrationError::Source => {
                "a sensitivity's source must be unmeasured, weighed or typed, and its zero within 0..=4095 counts"
            }
        }
    }
}

/// Plausible sensitivities of a force channel, N per count: a 12-bit reading spans 8 N to
/// 400 N. Outside, a value is a typo (a factor of ten, a sign) that would misread every force.
pub const N_PER_COUNT_RANGE: (f32, f32) = (0.002, 0.1);

/// Plausible amplifier full scales, V: the filtered output at 100 % duty is the Pico's 3V3 rail
/// (3.3 V ± 5 %) less the pin's drop into the pull-down. A value typed below the real one pins
/// the run's duty at or near 100 %, and the drive is then the rail × gain (13.2 V) while
/// the log says the control voltage × gain.
pub const AMP_FULL_SCALE_V_RANGE: (f32, f32) = (3.0, 3.5);

fn within(v: f32, lo: f32, hi: f32) -> bool {
    v.is_finite() && v >= lo && v <= hi
}

impl Calibration {
    /// Both channels' zeros, counts (T1, T2).
    pub fn zeros(&self) -> [f32; 2] {
        [self.t1.zero_counts, self.t2.zero_counts]
    }

    /// Both channels' sensitivities weighed or typed by a person: `None`; else the first
    /// channel whose sensitivity nobody measured (the placeholder).
    pub fn unmeasured(&self) -> Option<crate::hal::Channel> {
        use crate::hal::Channel;
        [(Channel::T1, &self.t1), (Channel::T2, &self.t2)]
            .into_iter()
            .find(|(_, c)| !c.source.is_measured())
            .map(|(ch, _)| ch)
    }

    /// These values, typed by a person: both sensitivities count as measured at the zeros in
    /// force (a simulated bench whose person knows its sensors, a board set up by `set`).
    pub fn typed(self) -> Calibration {
        Calibration {
            t1: self.t1.measured(CalSource::Typed),
            t2: self.t2.measured(CalSource::Typed),
            ..self
        }
    }

    /// Refuse a calibration the rig cannot work with, with the reason.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        for ch in [&self.t1, &self.t2] {
            let (lo, hi) = N_PER_COUNT_RANGE;
            if !within(ch.n_per_count, lo, hi) {
                return Err(CalibrationError::Sensitivity);
            }
            if !within(ch.zero_counts, 0.0, 4095.0) {
                return Err(CalibrationError::Zero);
            }
            if !within(ch.cal_zero, 0.0, 4095.0) {
                return Err(CalibrationError::Source);
            }
        }
        if !within(self.tare_reference_n, 0.0, 10.0) {
            return Err(CalibrationError::TareReference);
        }
        let s = &self.servo;
        let pulses_ok = within(s.pulse_at_min_us, 400.0, 2600.0)
            && within(s.pulse_at_max_us, 400.0, 2600.0)
            && s.pulse_at_max_us - s.pulse_at_min_us >= 1.0;
        if !(pulses_ok && within(s.max_deg, 0.0, 360.0) && s.max_deg > 0.0) {
            return Err(CalibrationError::ServoMap);
        }
        let a = &self.amp;
        let positive_within = |v: f32, hi: f32| within(v, 0.0, hi) && v > 0.0;
        let (lo, hi) = AMP_FULL_SCALE_V_RANGE;
        if !(within(a.full_scale_v, lo, hi) && positive_within(a.amp_gain, 100.0)) {
            return Err(CalibrationError::AmpMap);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_servo_map_is_the_arduino_servo_librarys() {
        let m = ServoMap::default();
        assert_eq!(m, ServoMap::ARDUINO_SERVO);
        assert_eq!(m.pulse_us(0.0), 544.0);
        assert_eq!(m.pulse_us(180.0), 2400.0);
        assert_eq!(m.pulse_us(200.0), 2400.0);
        // The thesis's rest and last angle: write(125) and write(65).
        let (rest, last) = (m.pulse_us(125.0), m.pulse_us(65.0));
        assert!((rest - 1833.0).abs() <= 1.0, "{rest}");
        assert!((last - 1214.0).abs() <= 1.0, "{last}");
        // What the RP2040 puts on the wire: 125 MHz / 40, top 62 499, a 62 500-count frame
        // (the board's full scale), so 0.32 µs per count.
        for (angle, want_us) in [(125.0, 1833.0), (65.0, 1214.0)] {
            let on_wire_us = m.duty(angle, 62_500) as f32 * 0.32;
            assert!((on_wire_us - want_us).abs() <= 1.0, "{angle}: {on_wire_us}");
        }
        // The thesis's 60° span is 619 µs of pulse, not the 333 µs of a 1-2 ms map.
        assert!(((rest - last) - 618.7).abs() < 0.1);
        assert!((m.angle_deg(m.pulse_us(125.0)) - 125.0).abs() < 1e-4);
        assert!((m.angle_for_duty(m.duty(125.0, 62_499), 62_499) - 125.0).abs() < 0.04);
        assert_eq!(m.angle_for_duty(0, 62_499), 0.0);
        assert_eq!(m.angle_for_duty(62_499, 62_499), 180.0);
        let custom = ServoMap {
            pulse_at_min_us: 500.0,
            pulse_at_max_us: 2500.0,
            max_deg: 180.0,
        };
        assert_eq!(custom.pulse_us(90.0), 1500.0);
    }

    #[test]
    fn amp_map_and_clamps() {
        let m = AmpMap::default();
        assert_eq!(m.duty(3.3, 1000), 1000);
        assert_eq!(m.duty(1.65, 1000), 500);
        assert_eq!(m.duty(-1.0, 1000), 0);
        assert_eq!(m.duty(f32::NAN, 1000), 0);
        assert_eq!(m.drive_v(2.5), 10.0);
    }

    #[test]
    fn channel_calibration_and_tare() {
        let mut ch = ChannelCal::placeholder(400.0, 0.015);
        assert!((ch.newtons(1066.667) - 10.0).abs() < 1e-3);
        assert!((ch.newtons(ch.counts(7.3)) - 7.3).abs() < 1e-4);
        // The sensor drifted by +20 counts; a tare with the 0.1 N preload on the cord restores it.
        let preload_counts = 420.0 + 0.1 / 0.015;
        ch.tare(preload_counts, 0.1);
        assert!((ch.zero_counts - 420.0).abs() < 1e-3);
        assert!((ch.newtons(420.0 + 10.0 / 0.015) - 10.0).abs() < 1e-4);
    }

    #[test]
    fn implausible_sensitivities_and_reversed_servo_maps_are_refused() {
        let ok = Calibration::default();
        assert_eq!(ok.validate(), Ok(()));
        for npc in [0.0015, -0.015, 0.0, 0.2, f32::NAN] {
            let mut c = ok;
            c.t2.n_per_count = npc;
            assert_eq!(c.validate(), Err(CalibrationError::Sensitivity), "{npc}");
        }
        let mut c = ok;
        c.servo = ServoMap {
            pulse_at_min_us: 2400.0,
            pulse_at_max_us: 544.0,
            max_deg: 180.0,
        };
        assert_eq!(c.validate(), Err(CalibrationError::ServoMap));
        // A full scale typed at the control voltage (2.5 V) would pin the duty at 100 %.
        for v in [2.5, 2.99, 3.51, 5.0] {
            let mut c = ok;
            c.amp.full_scale_v = v;
            assert_eq!(c.validate(), Err(CalibrationError::AmpMap), "{v}");
        }
    }

    #[test]
    fn a_zero_walked_more_than_1_n_from_the_weighed_one_leaves_the_sensitivity_unmeasured() {
        let placeholder = Calibration::default();
        assert_eq!(placeholder.unmeasured(), Some(crate::hal::Channel::T1));
        let typed = placeholder.typed();
        assert_eq!(typed.unmeasured(), None);
        assert_eq!(typed.t2.cal_zero, 400.0);
        // 0.015 N/count: 66 counts is 0.99 N, 67 counts 1.005 N from the weighed zero.
        let ch = typed.t1;
        let once = ch.rezeroed(466.0);
        assert_eq!(once.source, CalSource::Typed);
        // A second zero 60 counts further (each within 1 N of the last): 126 counts walked.
        let twice = once.rezeroed(526.0);
        assert_eq!(twice.source, CalSource::Placeholder);
        assert_eq!(ch.rezeroed(333.0).source, CalSource::Placeholder);
        // A weigh at the new zero measures it again from there.
        let weighed = twice.measured(CalSource::Weighed);
        assert_eq!(
            (weighed.source, weighed.cal_zero),
            (CalSource::Weighed, 526.0)
        );
    }
}
