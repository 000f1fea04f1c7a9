//! The log records a run produces, and the sink they go to.
//!
//! Every record is emitted with a sequence number (consecutive from 0 since boot, wrapping), so
//! a host can tell exactly which records it lost. On the board the sink is defmt over RTT
//! (`defmt_sink`); in the simulator it is a `Vec`.
//!
//! Times: `t_us` are µs since the trigger's rising edge (negative before it), the timebase of
//! the thesis's logger.

use crate::calib::Calibration;
use crate::condition::ChannelStats;
use crate::protocol::Protocol;
use crate::settings::Settings;
use capstan_wire::{Channel, CommandError, CommandKind, RecordKind, Scalar, Setting, Value};

mod held;

pub use held::{Held, LONG_RECORD_UNTIL_US};

/// The codes the records carry (fault kinds, where the settings came from, "none"): the wire
/// schema's.
pub use capstan_wire::{FaultKind, SettingsSource, NONE_CODE};

/// The run begins (emitted once the tare is done, with the calibration the run will use).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct RunStart {
    /// Runs started since boot, from 1.
    pub run: u32,
    /// The protocol being run.
    pub protocol: Protocol,
    /// The calibration in force (after the tare).
    pub calibration: Calibration,
}

/// A decimated raw sample.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct RawSample {
    /// µs since the trigger.
    pub t_us: i64,
    /// ADC counts, T1 then T2.
    pub counts: [u16; 2],
    /// Calibrated forces, N, T1 then T2.
    pub force_n: [f32; 2],
    /// The T2 target of force control, N (0: none).
    pub t2_target_n: f32,
}

/// The conditioned pair of one step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct StepPair {
    /// Step in time order, 1..=N.
    pub step: u32,
    /// Tension level held (1..=N; equals `step` for the monotone order).
    pub level: u32,
    /// Servo angle commanded, deg.
    pub angle_deg: f32,
    /// Middle of the conditioning window, ms since the trigger.
    pub t_mid_ms: u32,
    /// T1 statistics over the window.
    pub t1: ChannelStats,
    /// T2 statistics over the window.
    pub t2: ChannelStats,
    /// The T2 target of force control at the window's middle (a sine's mean), N (0: none).
    pub t2_target_n: f32,
}

/// A safety fault: the rig went to its safe state.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Fault {
    /// What happened.
    pub kind: FaultKind,
    /// The channel concerned, if any.
    pub channel: Option<Channel>,
    /// The offending value: N for force faults (the load the tare saw for `tare_load`, the
    /// force readable at the rail check for `blind_calibration`), counts for rail faults, ms
    /// for the watchdog (NaN for one latched at boot: the gap is unknown), 0 for the others.
    pub value: f32,
    /// µs since the trigger when it was detected (and the safe state commanded).
    pub t_us: i64,
}

/// The run is over.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct RunEnd {
    /// µs since the trigger.
    pub t_us: i64,
    /// Pairs emitted in this run.
    pub pairs: u32,
    /// The fault that ended it, if one did.
    pub fault: Option<FaultKind>,
}

/// Live values in setup mode, ~10 a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Live {
    /// ms since boot.
    pub t_ms: u32,
    /// ADC counts, T1 then T2 (0 where a conversion failed).
    pub counts: [u16; 2],
    /// Calibrated forces, N, T1 then T2.
    pub force_n: [f32; 2],
    /// Servo angle commanded, deg.
    pub servo_deg: f32,
}

/// The answer to one host command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reply {
    /// The command answered.
    pub command: CommandKind,
    /// Why it was refused; `None` = done.
    pub error: Option<CommandError>,
    /// What it produced: `jog`/`servo` the angle; `zero` the zeros of T1 and T2, counts;
    /// `weigh` n_per_count and the mean counts; `set` the key's code and its value; else 0.
    pub values: [f32; 2],
}

/// The settings in force, and where they came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettingsReport {
    /// Where they came from.
    pub source: SettingsSource,
    /// The settings.
    pub settings: Settings,
}

/// One log record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Record {
    /// Run start (protocol, calibration).
    RunStart(RunStart),
    /// Decimated raw sample.
    Raw(RawSample),
    /// Conditioned step pair.
    Pair(StepPair),
    /// Safety fault.
    Fault(Fault),
    /// Run end.
    RunEnd(RunEnd),
    /// Live values (setup mode).
    Live(Live),
    /// The answer to a host command.
    Reply(Reply),
    /// The settings in force.
    Settings(SettingsReport),
}

/// Where records go.
pub trait LogSink {
    /// Send one record with its sequence number.
    fn emit(&mut self, seq: u32, record: &Record);

    /// The runner has applied this sample's outputs: send what was held back. A sink may hold
    /// records until then, so that encoding them never delays a safe state at the pins, and
    /// (the board's) hold a long record further, to a sample with time to spare for it.
    fn flush(&mut self) {}

    /// A sample begins, at `now_us` (embassy-time's clock): the runner calls this before the
    /// sample's work, so a sink can tell how much of the sample is left when it flushes.
    fn sample_started(&mut self, now_us: u64) {
        let _ = now_us;
    }
}

impl<T: LogSink + ?Sized> LogSink for &mut T {
    fn emit(&mut self, seq: u32, record: &Record) {
        (**self).emit(seq, record)
    }
    fn flush(&mut self) {
        (**self).flush()
    }
    fn sample_started(&mut self, now_us: u64) {
        (**self).sample_started(now_us)
    }
}

/// Numbers records consecutively (wrapping).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sequencer {
    next: u32,
}

impl Sequencer {
    /// The next sequence number.
    pub fn next_seq(&mut self) -> u32 {
        let seq = self.next;
        self.next = self.next.wrapping_add(1);
        seq
    }
}

/// The CRC of every log record: CRC-32/ISO-HDLC (the Ethernet and zip CRC).
const RECORD_CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The bytes a record's checksum covers, fed one field at a time in wire order
/// ([`Record::for_each_field`]), each little-endian at its wire width; a NaN always as the
/// canonical NaN (the host reads NaN back from its text, without its payload).
///
/// The fields' bytes are gathered in a small buffer and checksummed a buffer at a time: the
/// CRC's per-call overhead paid per field cost the board ~100 cycles a field (a settings record
/// has 50).
pub struct CrcFields {
    digest: crc::Digest<'static, u32>,
    buf: [u8; CRC_CHUNK],
    len: usize,
}

/// Bytes checksummed at once.
const CRC_CHUNK: usize = 64;

impl CrcFields {
    /// An empty checksum.
    pub fn new() -> Self {
        CrcFields {
            digest: RECORD_CRC.digest(),
            buf: [0; CRC_CHUNK],
            len: 0,
        }
    }
    /// One field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn push(&mut self, v: Scalar) {
        let n = v.prim().bytes();
        if self.len + n > CRC_CHUNK {
            self.digest.update(&self.buf[..self.len]);
            self.len = 0;
        }
        self.buf[self.len..self.len + n].copy_from_slice(&v.le_bytes()[..n]);
        self.len += n;
    }
    /// A `u8` field.
    pub fn u8(mut self, v: u8) -> Self {
        self.push(Scalar::U8(v));
        self
    }
    /// A `u16` field.
    pub fn u16(mut self, v: u16) -> Self {
        self.push(Scalar::U16(v));
        self
    }
    /// A `u32` field.
    pub fn u32(mut self, v: u32) -> Self {
        self.push(Scalar::U32(v));
        self
    }
    /// An `i64` field.
    pub fn i64(mut self, v: i64) -> Self {
        self.push(Scalar::I64(v));
        self
    }
    /// An `f32` field.
    pub fn f32(mut self, v: f32) -> Self {
        self.push(Scalar::F32(v));
        self
    }
    /// The checksum.
    pub fn finish(mut self) -> u32 {
        self.digest.update(&self.buf[..self.len]);
        self.digest.finalize()
    }
}

impl Default for CrcFields {
    fn default() -> Self {
        Self::new()
    }
}

impl Record {
    /// Its kind in the wire schema.
    pub const fn kind(&self) -> RecordKind {
        match self {
            Record::RunStart(_) => RecordKind::RunStart,
            Record::Raw(_) => RecordKind::Raw,
            Record::Pair(_) => RecordKind::Pair,
            Record::Fault(_) => RecordKind::Fault,
            Record::RunEnd(_) => RecordKind::RunEnd,
            Record::Live(_) => RecordKind::Live,
            Record::Reply(_) => RecordKind::Reply,
            Record::Settings(_) => RecordKind::Settings,
        }
    }

    /// Every field of the record but its `crc`, with `seq`, in wire order and at its wire type
    /// (the schema's [`RecordKind::fields`]): what the checksum covers and the board sends.
    pub fn for_each_field(&self, seq: u32, mut f: impl FnMut(Scalar)) {
        use Scalar::{F32, I64, U16, U32, U8};
        f(U32(seq));
        match self {
            Record::RunStart(s) => {
                f(U32(s.run));
                settings_fields(&s.settings().fields(), f);
            }
            Record::Settings(s) => {
                f(U8(s.source.code()));
                settings_fields(&s.settings.fields(), f);
            }
            Record::Live(l) => {
                f(U32(l.t_ms));
                f(U16(l.counts[0]));
                f(U16(l.counts[1]));
                f(F32(l.force_n[0]));
                f(F32(l.force_n[1]));
                f(F32(l.servo_deg));
            }
            Record::Reply(r) => {
                f(U8(r.command.code()));
                f(U8(r.error.map_or(0, |e| e.code())));
                f(F32(r.values[0]));
                f(F32(r.values[1]));
            }
            Record::Raw(r) => {
                f(I64(r.t_us));
                f(U16(r.counts[0]));
                f(U16(r.counts[1]));
                f(F32(r.force_n[0]));
                f(F32(r.force_n[1]));
                f(F32(r.t2_target_n));
            }
            Record::Pair(p) => {
                f(U32(p.step));
                f(U32(p.level));
                f(F32(p.angle_deg));
                f(U32(p.t_mid_ms));
                for t in [&p.t1, &p.t2] {
                    f(F32(t.mean_n));
                    f(F32(t.std_n));
                    f(U32(t.count));
                }
                f(F32(p.t2_target_n));
            }
            Record::Fault(x) => {
                f(U8(x.kind.code()));
                f(U8(x.channel.map_or(NONE_CODE, Channel::code)));
                f(F32(x.value));
                f(I64(x.t_us));
            }
            Record::RunEnd(e) => {
                f(I64(e.t_us));
                f(U32(e.pairs));
                f(U8(e.fault.map_or(NONE_CODE, FaultKind::code)));
            }
        }
    }
}

impl RunStart {
    /// The protocol and calibration of the run, as settings.
    pub fn settings(&self) -> Settings {
        Settings {
            protocol: self.protocol,
            calibration: self.calibration,
        }
    }
}

/// The settings block of `run_start` and `settings`, from the settings' bits
/// ([`Settings::fields`]): every setting in wire order, at its wire type.
fn settings_fields(bits: &[u32; crate::settings::FIELDS], mut f: impl FnMut(Scalar)) {
    for (&setting, &bits) in Setting::ALL.iter().zip(bits) {
        f(crate::settings::scalar(setting, bits));
    }
}

/// Why fields do not make a record ([`Record::from_fields`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldsError {
    /// Fewer fields than the record has; the first missing.
    Missing(&'static str),
    /// A field of another wire type.
    Type(&'static str),
    /// More fields than the record has.
    Extra,
    /// A code that means nothing in this field.
    Code {
        /// The field.
        field: &'static str,
        /// The code.
        code: u8,
    },
}

impl Record {
    /// The record of a kind from its fields in wire order, `seq` first and `crc` left out (as
    /// [`Record::for_each_field`] gives them): the sequence number and the record.
    pub fn from_fields(kind: RecordKind, fields: &[Scalar]) -> Result<(u32, Record), FieldsError> {
        let mut r = FieldReader {
            kind,
            fields,
            at: 0,
        };
        let seq = r.u32()?;
        let record = match kind {
            RecordKind::RunStart => {
                let run = r.u32()?;
                let s = r.settings()?;
                Record::RunStart(RunStart {
                    run,
                    protocol: s.protocol,
                    calibration: s.calibration,
                })
            }
            RecordKind::Settings => Record::Settings(SettingsReport {
                source: r.code(SettingsSource::from_code)?,
                settings: r.settings()?,
            }),
            RecordKind::Live => Record::Live(Live {
                t_ms: r.u32()?,
                counts: [r.u16()?, r.u16()?],
                force_n: [r.f32()?, r.f32()?],
                servo_deg: r.f32()?,
            }),
            RecordKind::Reply => Record::Reply(Reply {
                command: r.code(CommandKind::from_code)?,
                error: r.code(|c| match c {
                    0 => Some(None),
                    c => CommandError::from_code(c).map(Some),
                })?,
                values: [r.f32()?, r.f32()?],
            }),
            RecordKind::Raw => Record::Raw(RawSample {
                t_us: r.i64()?,
                counts: [r.u16()?, r.u16()?],
                force_n: [r.f32()?, r.f32()?],
                t2_target_n: r.f32()?,
            }),
            RecordKind::Pair => Record::Pair(StepPair {
                step: r.u32()?,
                level: r.u32()?,
                angle_deg: r.f32()?,
                t_mid_ms: r.u32()?,
                t1: r.stats()?,
                t2: r.stats()?,
                t2_target_n: r.f32()?,
            }),
            RecordKind::Fault => Record::Fault(Fault {
                kind: r.code(FaultKind::from_code)?,
                channel: r.code(none_or(Channel::from_code))?,
                value: r.f32()?,
                t_us: r.i64()?,
            }),
            RecordKind::RunEnd => Record::RunEnd(RunEnd {
                t_us: r.i64()?,
                pairs: r.u32()?,
                fault: r.code(none_or(FaultKind::from_code))?,
            }),
        };
        match r.at == fields.len() {
            true => Ok((seq, record)),
            false => Err(FieldsError::Extra),
        }
    }
}

/// A code that may be [`NONE_CODE`].
fn none_or<T>(of: impl Fn(u8) -> Option<T>) -> impl Fn(u8) -> Option<Option<T>> {
    move |c| match c {
        NONE_CODE => Some(None),
        c => of(c).map(Some),
    }
}

/// Reads a record's fields in wire order.
struct FieldReader<'a> {
    kind: RecordKind,
    fields: &'a [Scalar],
    at: usize,
}

impl FieldReader<'_> {
    /// The next field and its name.
    fn next(&mut self) -> Result<(Scalar, &'static str), FieldsError> {
        let name = self.kind.fields().nth(self.at).map_or("crc", |f| f.name);
        let v = *self.fields.get(self.at).ok_or(FieldsError::Missing(name))?;
        self.at += 1;
        Ok((v, name))
    }
    fn u8(&mut self) -> Result<(u8, &'static str), FieldsError> {
        match self.next()? {
            (Scalar::U8(v), name) => Ok((v, name)),
            (_, name) => Err(FieldsError::Type(name)),
        }
    }
    fn u16(&mut self) -> Result<u16, FieldsError> {
        match self.next()? {
            (Scalar::U16(v), _) => Ok(v),
            (_, name) => Err(FieldsError::Type(name)),
        }
    }
    fn u32(&mut self) -> Result<u32, FieldsError> {
        match self.next()? {
            (Scalar::U32(v), _) => Ok(v),
            (_, name) => Err(FieldsError::Type(name)),
        }
    }
    fn i64(&mut self) -> Result<i64, FieldsError> {
        match self.next()? {
            (Scalar::I64(v), _) => Ok(v),
            (_, name) => Err(FieldsError::Type(name)),
        }
    }
    fn f32(&mut self) -> Result<f32, FieldsError> {
        match self.next()? {
            (Scalar::F32(v), _) => Ok(v),
            (_, name) => Err(FieldsError::Type(name)),
        }
    }
    /// A one-byte code, as `of` reads it.
    fn code<T>(&mut self, of: impl Fn(u8) -> Option<T>) -> Result<T, FieldsError> {
        let (code, field) = self.u8()?;
        of(code).ok_or(FieldsError::Code { field, code })
    }
    fn stats(&mut self) -> Result<ChannelStats, FieldsError> {
        Ok(ChannelStats {
            mean_n: self.f32()?,
            std_n: self.f32()?,
            count: self.u32()?,
        })
    }
    /// The settings block (not validated: a record says what the rig ran with).
    fn settings(&mut self) -> Result<Settings, FieldsError> {
        let mut bits = [0u32; crate::settings::FIELDS];
        for (b, setting) in bits.iter_mut().zip(Setting::ALL) {
            *b = match setting.value() {
                Value::Code => self.u8()?.0 as u32,
                Value::Whole => self.u32()?,
                Value::Real => self.f32()?.to_bits(),
            };
        }
        Settings::from_fields_or_bad(&bits).map_err(|bad| FieldsError::Code {
            field: bad.name(),
            code: bits[bad.index()] as u8,
        })
    }
}

/// The checksum a record is logged with (`crc=` in its format string): over its sequence
/// number and every field, in wire order ([`Record::for_each_field`]).
pub fn record_crc(seq: u32, record: &Record) -> u32 {
    let mut c = CrcFields::new();
    record.for_each_field(seq, |v| c.push(v));
    c.finish()
}

/// [`record_crc`] of a record that carries the settings (`run_start`, `settings`), from its
/// leading field (`run`, `source`) and the settings' bits as [`Settings::fields`] gives them (a
/// NaN canonical), which the board works out once for both the checksum and the frame. The
/// bytes are laid out in one buffer and checksummed at once: no per-field call (on the
/// board ~2 000 cycles for the 50 fields, against ~11 000 field by field).
pub fn settings_record_crc(seq: u32, lead: Scalar, bits: &[u32; crate::settings::FIELDS]) -> u32 {
    let mut bytes = [0u8; 4 + 4 + 4 * crate::settings::FIELDS];
    bytes[..4].copy_from_slice(&seq.to_le_bytes());
    let lead_bytes = lead.prim().bytes().min(4);
    bytes[4..4 + lead_bytes].copy_from_slice(&lead.le_bytes()[..lead_bytes]);
    let mut n = 4 + lead_bytes;
    for (setting, &b) in Setting::ALL.iter().zip(bits) {
        let b = b.to_le_bytes();
        if setting.value() == Value::Code {
            bytes[n] = b[0];
            n += 1;
        } else {
            bytes[n..n + 4].copy_from_slice(&b);
            n += 4;
        }
    }
    RECORD_CRC.checksum(&bytes[..n])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::Calibration;
    use crate::protocol::Protocol;
    use capstan_wire::Prim;

    fn one_of_each() -> [Record; 8] {
        let stats = ChannelStats {
            mean_n: 1.5,
            std_n: 0.02,
            count: 7000,
        };
        let settings = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        [
            Record::RunStart(RunStart {
                run: 2,
                protocol: settings.protocol,
                calibration: settings.calibration,
            }),
            Record::Raw(RawSample {
                t_us: -500,
                counts: [400, 410],
                force_n: [0.1, 0.2],
                t2_target_n: 5.0,
            }),
            Record::Pair(StepPair {
                step: 3,
                level: 3,
                angle_deg: 110.0,
                t_mid_ms: 26_000,
                t1: stats,
                t2: stats,
                t2_target_n: 0.0,
            }),
            Record::Fault(Fault {
                kind: FaultKind::CordBreak,
                channel: Some(Channel::T2),
                value: 0.1,
                t_us: 30_004_000,
            }),
            Record::RunEnd(RunEnd {
                t_us: 30_004_000,
                pairs: 2,
                fault: Some(FaultKind::CordBreak),
            }),
            Record::Settings(SettingsReport {
                source: SettingsSource::Loaded,
                settings,
            }),
            Record::Live(Live {
                t_ms: 100,
                counts: [400, 401],
                force_n: [0.0, 0.01],
                servo_deg: 125.0,
            }),
            Record::Reply(Reply {
                command: CommandKind::Jog,
                error: None,
                values: [95.0, 0.0],
            }),
        ]
    }

    #[test]
    fn every_record_gives_the_schemas_fields_in_its_order() {
        let records = one_of_each();
        for kind in RecordKind::ALL {
            let record = records.iter().find(|r| r.kind() == kind).unwrap();
            let mut prims = std::vec::Vec::new();
            record.for_each_field(9, |v| prims.push(v.prim()));
            let schema: std::vec::Vec<Prim> = kind
                .fields()
                .filter(|f| f.name != "crc")
                .map(|f| f.prim)
                .collect();
            assert_eq!(prims, schema, "{}", kind.word());
        }
    }

    #[test]
    fn fields_make_the_record_back() {
        for record in one_of_each() {
            let mut fields = std::vec::Vec::new();
            record.for_each_field(9, |v| fields.push(v));
            assert_eq!(Record::from_fields(record.kind(), &fields), Ok((9, record)));
            let short = &fields[..fields.len() - 1];
            let last = record.kind().fields().nth(short.len()).unwrap().name;
            assert_eq!(
                Record::from_fields(record.kind(), short),
                Err(FieldsError::Missing(last))
            );
        }
        let bad_kind = [Scalar::U32(1), Scalar::U8(77), Scalar::U8(NONE_CODE)];
        let bad_kind = [&bad_kind[..], &[Scalar::F32(0.0), Scalar::I64(0)]].concat();
        assert_eq!(
            Record::from_fields(RecordKind::Fault, &bad_kind),
            Err(FieldsError::Code {
                field: "kind",
                code: 77
            })
        );
    }

    #[test]
    fn settings_records_checksum_the_same_from_their_bits() {
        for record in one_of_each() {
            let (lead, settings) = match record {
                Record::RunStart(s) => (Scalar::U32(s.run), s.settings()),
                Record::Settings(s) => (Scalar::U8(s.source.code()), s.settings),
                _ => continue,
            };
            let crc = settings_record_crc(9, lead, &settings.fields());
            assert_eq!(crc, record_crc(9, &record), "{}", record.kind().word());
        }
        // A NaN (with a payload) in a setting, a code past 0: the same bytes both ways.
        let mut settings = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        settings.calibration.t2.zero_counts = f32::from_bits(0x7fc0_0001);
        settings.protocol.order = capstan_wire::StepOrder::Pulse;
        let record = Record::Settings(SettingsReport {
            source: SettingsSource::Stored,
            settings,
        });
        let lead = Scalar::U8(SettingsSource::Stored.code());
        assert_eq!(
            settings_record_crc(7, lead, &settings.fields()),
            record_crc(7, &record)
        );
    }

    #[test]
    fn the_checksum_covers_every_field_at_its_width() {
        let raw = Record::Raw(RawSample {
            t_us: -500,
            counts: [400, 410],
            force_n: [f32::from_bits(0x7fc0_0001), 0.2],
            t2_target_n: 0.0,
        });
        // seq, t_us, c1, c2, t1_n (a NaN with a payload: checksummed as the canonical NaN), t2_n,
        // t2_target_n.
        let mut bytes = std::vec::Vec::new();
        bytes.extend(9u32.to_le_bytes());
        bytes.extend((-500i64).to_le_bytes());
        bytes.extend(400u16.to_le_bytes());
        bytes.extend(410u16.to_le_bytes());
        bytes.extend(f32::NAN.to_bits().to_le_bytes());
        bytes.extend(0.2f32.to_bits().to_le_bytes());
        bytes.extend(0.0f32.to_bits().to_le_bytes());
        assert_eq!(record_crc(9, &raw), RECORD_CRC.checksum(&bytes));
    }
}
