//! The settings an operator sets at the bench (protocol and calibration), one value at a time
//! by name, and their byte layout in flash.
//!
//! The layout is ours, little-endian, led by a format version ([`SETTINGS_VERSION`]); the
//! flash store (`store.rs`, on `sequential-storage`) adds the CRC and the wear levelling. A
//! record of another version, of the wrong length, or whose values do not validate, is never
//! used: [`Settings::decode`] refuses it and the rig keeps its defaults.

use crate::calib::{Calibration, CalibrationError};
use crate::command::Key;
use crate::protocol::{Protocol, ProtocolError, StepOrder};

/// Version of the byte layout below. Change it whenever the layout changes.
pub const SETTINGS_VERSION: u8 = 1;

/// Encoded length, bytes: version, generation, 15 protocol values, 10 calibration values.
pub const SETTINGS_BYTES: usize = 1 + 4 + 12 + 1 + 16 + 4 + 16 + 8 + 40;

/// What the rig runs with: the protocol and the calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The test protocol.
    pub protocol: Protocol,
    /// The calibration.
    pub calibration: Calibration,
}

/// Why a settings record or value is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum SettingsError {
    /// The record was written by another layout version.
    Version(u8),
    /// The record has the wrong length.
    Length,
    /// The protocol does not validate.
    Protocol(ProtocolError),
    /// The calibration does not validate.
    Calibration(CalibrationError),
    /// The sample or raw-log rate differs from the firmware's (they are fixed at build time).
    Rates,
    /// A time in ms must be a whole number, 0 to 10⁹.
    NotWhole,
    /// Not a step order's code.
    Order,
    /// The diameter and wrap metadata must be 0..=3600.
    Metadata,
}

impl SettingsError {
    /// What is wrong, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            SettingsError::Version(_) => "the stored settings are of another layout version",
            SettingsError::Length => "the stored settings have the wrong length",
            SettingsError::Protocol(e) => e.message(),
            SettingsError::Calibration(e) => e.message(),
            SettingsError::Rates => "the sample and raw-log rates are fixed by the firmware",
            SettingsError::NotWhole => "a time in ms must be a whole number from 0 to 10⁹",
            SettingsError::Order => "the order must be monotone, updown or pulse",
            SettingsError::Metadata => "the diameter (mm) and wrap (deg) must be 0 to 3600",
        }
    }
}

impl Settings {
    /// Refuse settings the rig cannot run with.
    pub fn validate(&self) -> Result<(), SettingsError> {
        self.protocol.validate().map_err(SettingsError::Protocol)?;
        self.calibration
            .validate()
            .map_err(SettingsError::Calibration)
    }

    /// These settings with one value changed, if they stay valid (`order` takes the step
    /// order's code; a count of ms must be a whole number).
    pub fn with(&self, key: Key, value: f32) -> Result<Settings, SettingsError> {
        let mut s = *self;
        let (p, c) = (&mut s.protocol, &mut s.calibration);
        let ms = || -> Result<u32, SettingsError> {
            let whole = (0.0..=1.0e9).contains(&value) && libm::truncf(value) == value;
            whole.then_some(value as u32).ok_or(SettingsError::NotWhole)
        };
        match key {
            Key::RestDeg => p.rest_deg = value,
            Key::StepDeg => p.step_deg = value,
            Key::FinalDeg => p.final_deg = value,
            Key::Order => {
                p.order = StepOrder::from_code(value as u8)
                    .filter(|o| o.code() as f32 == value)
                    .ok_or(SettingsError::Order)?
            }
            Key::DwellMs => p.dwell_ms = ms()?,
            Key::PreTriggerMs => p.pre_trigger_ms = ms()?,
            Key::TriggerMs => p.trigger_ms = ms()?,
            Key::TareMs => p.tare_ms = ms()?,
            Key::AmpControlV => p.amp_control_v = value,
            Key::WindowAfterMs => p.window_after_change_ms = ms()?,
            Key::WindowBeforeMs => p.window_before_next_ms = ms()?,
            Key::DiameterMm => p.capstan_diameter_mm = value,
            Key::WrapDeg => p.wrap_deg = value,
            Key::T1Zero => c.t1.zero_counts = value,
            Key::T1NPerCount => c.t1.n_per_count = value,
            Key::T2Zero => c.t2.zero_counts = value,
            Key::T2NPerCount => c.t2.n_per_count = value,
            Key::TareReferenceN => c.tare_reference_n = value,
            Key::ServoMinUs => c.servo.pulse_at_min_us = value,
            Key::ServoMaxUs => c.servo.pulse_at_max_us = value,
            Key::ServoMaxDeg => c.servo.max_deg = value,
            Key::AmpFullScaleV => c.amp.full_scale_v = value,
            Key::AmpGain => c.amp.amp_gain = value,
        }
        let metadata_ok = |v: f32| v.is_finite() && (0.0..=3600.0).contains(&v);
        if !metadata_ok(s.protocol.capstan_diameter_mm) || !metadata_ok(s.protocol.wrap_deg) {
            return Err(SettingsError::Metadata);
        }
        s.validate()?;
        Ok(s)
    }

    /// The bytes stored in flash, with the store's `generation` (which save this is).
    pub fn encode(&self, generation: u32) -> [u8; SETTINGS_BYTES] {
        let (p, c) = (&self.protocol, &self.calibration);
        let mut w = Writer::default();
        w.u8(SETTINGS_VERSION).u32(generation);
        w.f32(p.rest_deg).f32(p.step_deg).f32(p.final_deg);
        w.u8(p.order.code());
        w.u32(p.dwell_ms).u32(p.pre_trigger_ms).u32(p.trigger_ms);
        w.u32(p.tare_ms);
        w.f32(p.amp_control_v);
        w.u32(p.sample_hz).u32(p.raw_log_hz);
        w.u32(p.window_after_change_ms).u32(p.window_before_next_ms);
        w.f32(p.capstan_diameter_mm).f32(p.wrap_deg);
        w.f32(c.t1.zero_counts).f32(c.t1.n_per_count);
        w.f32(c.t2.zero_counts).f32(c.t2.n_per_count);
        w.f32(c.tare_reference_n);
        w.f32(c.servo.pulse_at_min_us).f32(c.servo.pulse_at_max_us);
        w.f32(c.servo.max_deg);
        w.f32(c.amp.full_scale_v).f32(c.amp.amp_gain);
        w.buf
    }

    /// Settings and generation from stored bytes; refused unless of this version and valid.
    pub fn decode(bytes: &[u8]) -> Result<(Settings, u32), SettingsError> {
        let version = *bytes.first().ok_or(SettingsError::Length)?;
        if version != SETTINGS_VERSION {
            return Err(SettingsError::Version(version));
        }
        if bytes.len() != SETTINGS_BYTES {
            return Err(SettingsError::Length);
        }
        let mut r = Reader { bytes, at: 1 };
        let generation = r.u32();
        let mut p = Protocol {
            rest_deg: r.f32(),
            step_deg: r.f32(),
            final_deg: r.f32(),
            ..Protocol::default()
        };
        p.order = StepOrder::from_code(r.u8()).ok_or(SettingsError::Order)?;
        p.dwell_ms = r.u32();
        p.pre_trigger_ms = r.u32();
        p.trigger_ms = r.u32();
        p.tare_ms = r.u32();
        p.amp_control_v = r.f32();
        p.sample_hz = r.u32();
        p.raw_log_hz = r.u32();
        p.window_after_change_ms = r.u32();
        p.window_before_next_ms = r.u32();
        p.capstan_diameter_mm = r.f32();
        p.wrap_deg = r.f32();
        let mut c = Calibration::default();
        c.t1.zero_counts = r.f32();
        c.t1.n_per_count = r.f32();
        c.t2.zero_counts = r.f32();
        c.t2.n_per_count = r.f32();
        c.tare_reference_n = r.f32();
        c.servo.pulse_at_min_us = r.f32();
        c.servo.pulse_at_max_us = r.f32();
        c.servo.max_deg = r.f32();
        c.amp.full_scale_v = r.f32();
        c.amp.amp_gain = r.f32();
        let s = Settings {
            protocol: p,
            calibration: c,
        };
        s.validate()?;
        Ok((s, generation))
    }
}

/// Writes fields little-endian into the fixed-size record. The layout is short and ours, so
/// no serialisation crate: a serde format would add flash for nothing this needs.
struct Writer {
    buf: [u8; SETTINGS_BYTES],
    at: usize,
}

impl Default for Writer {
    fn default() -> Self {
        Writer {
            buf: [0; SETTINGS_BYTES],
            at: 0,
        }
    }
}

impl Writer {
    fn put(&mut self, b: &[u8]) -> &mut Self {
        self.buf[self.at..self.at + b.len()].copy_from_slice(b);
        self.at += b.len();
        self
    }
    fn u8(&mut self, v: u8) -> &mut Self {
        self.put(&[v])
    }
    fn u32(&mut self, v: u32) -> &mut Self {
        self.put(&v.to_le_bytes())
    }
    fn f32(&mut self, v: f32) -> &mut Self {
        self.put(&v.to_le_bytes())
    }
}

/// Reads fields back; the length was checked first, so every read is in bounds.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut b = [0; N];
        b.copy_from_slice(&self.bytes[self.at..self.at + N]);
        self.at += N;
        b
    }
    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bench_settings() -> Settings {
        let mut s = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        s.protocol.capstan_diameter_mm = 25.4;
        s.protocol.wrap_deg = 360.0;
        s.protocol.order = StepOrder::UpDown;
        s.calibration.t1.n_per_count = 0.0123;
        s.calibration.servo.pulse_at_min_us = 500.0;
        s
    }

    #[test]
    fn round_trip_keeps_every_value_and_the_generation() {
        let s = bench_settings();
        let bytes = s.encode(7);
        assert_eq!(bytes.len(), SETTINGS_BYTES);
        assert_eq!(Settings::decode(&bytes), Ok((s, 7)));
    }

    #[test]
    fn one_value_is_set_by_name_and_an_invalid_one_refused() {
        let s = bench_settings();
        let t = s.with(Key::DwellMs, 8000.0).unwrap();
        assert_eq!(t.protocol.dwell_ms, 8000);
        assert_eq!(
            t.with(Key::Order, 2.0).unwrap().protocol.order,
            StepOrder::Pulse
        );
        assert!(s.with(Key::DwellMs, 8000.5).is_err());
        assert!(s.with(Key::DwellMs, -1.0).is_err());
        assert!(s.with(Key::Order, 7.0).is_err());
        assert!(
            s.with(Key::StepDeg, 7.0).is_err(),
            "60° is not a whole number of 7° steps"
        );
        assert!(s.with(Key::ServoMaxUs, 500.0).is_err());
        assert!(s.with(Key::WrapDeg, f32::NAN).is_err());
        let t = s.with(Key::ServoMaxUs, 2500.0).unwrap();
        assert_eq!(t.calibration.servo.pulse_at_max_us, 2500.0);
    }

    #[test]
    fn another_version_a_short_record_or_invalid_values_are_refused() {
        let s = bench_settings();
        let mut b = s.encode(1);
        b[0] = 2;
        assert_eq!(Settings::decode(&b), Err(SettingsError::Version(2)));
        assert_eq!(
            Settings::decode(&s.encode(1)[..SETTINGS_BYTES - 1]),
            Err(SettingsError::Length)
        );
        assert_eq!(Settings::decode(&[]), Err(SettingsError::Length));
        let mut bad = s;
        bad.calibration.t2.n_per_count = -0.01;
        assert!(matches!(
            Settings::decode(&bad.encode(1)),
            Err(SettingsError::Calibration(_))
        ));
        let mut bad = s;
        bad.protocol.final_deg = 200.0;
        assert!(matches!(
            Settings::decode(&bad.encode(1)),
            Err(SettingsError::Protocol(_))
        ));
    }
}
