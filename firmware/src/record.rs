//! The log records a run produces, and the sink they go to.
//!
//! Every record is emitted with a sequence number (consecutive from 0 since boot, wrapping), so
//! a host can tell exactly which records it lost. On the board the sink is defmt over RTT
//! (`defmt_sink`); in the simulator it is a `Vec`.
//!
//! Times: `t_us` are µs since the trigger's rising edge (negative before it), the timebase of
//! the thesis's logger.

use crate::calib::Calibration;
use crate::command::{CommandError, CommandKind};
use crate::condition::ChannelStats;
use crate::hal::Channel;
use crate::protocol::Protocol;
use crate::settings::Settings;

/// Wire value of "no channel" / "no fault" in the defmt records (the host decoder reads it too).
pub const NONE_CODE: u8 = 0xff;

/// Why a run was stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum FaultKind {
    /// A channel read above the force limit.
    OverForce,
    /// T2 collapsed while T1 was held: the cord broke.
    CordBreak,
    /// A channel sat at an ADC rail (unplugged or shorted sensor) or failed to convert.
    SensorRail,
    /// The button was pressed during the run.
    Abort,
    /// The sample loop missed its deadline, or (latched at boot) the hardware watchdog reset
    /// the chip.
    Watchdog,
    /// The tare saw a load beyond [`crate::rig::TARE_MAX_N`] on a channel: a weight or a
    /// preload on the cord, or a zero that is wrong. Taken as zero, it would blind the
    /// over-force check.
    TareLoad,
    /// The calibration cannot show the over-force limit below the rail check
    /// ([`crate::safety::SafetyLimits::visible`]).
    Blind,
    /// A channel read far below zero ([`crate::safety::SafetyLimits::negative_force_n`]): a
    /// reversed sensor or a wrong zero.
    NegativeForce,
    /// Latched at boot: the panic or HardFault handler reset the chip.
    Panic,
    /// Latched at boot: the chip was reset (a debugger, the RUN pin) while the rig was not at
    /// rest.
    Reset,
}

impl FaultKind {
    /// Every fault.
    pub const ALL: [FaultKind; 10] = [
        FaultKind::OverForce,
        FaultKind::CordBreak,
        FaultKind::SensorRail,
        FaultKind::Abort,
        FaultKind::Watchdog,
        FaultKind::TareLoad,
        FaultKind::Blind,
        FaultKind::NegativeForce,
        FaultKind::Panic,
        FaultKind::Reset,
    ];

    /// Stable name, as used by the CLI (`--fault NAME@SECONDS`) and in CSV/JSON.
    pub const fn name(self) -> &'static str {
        match self {
            FaultKind::OverForce => "over_force",
            FaultKind::CordBreak => "cord_break",
            FaultKind::SensorRail => "sensor_unplugged",
            FaultKind::Abort => "abort",
            FaultKind::Watchdog => "watchdog",
            FaultKind::TareLoad => "tare_load",
            FaultKind::Blind => "blind_calibration",
            FaultKind::NegativeForce => "negative_force",
            FaultKind::Panic => "panic",
            FaultKind::Reset => "reset",
        }
    }

    /// Wire code used in the defmt record.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`FaultKind::code`].
    pub fn from_code(code: u8) -> Option<FaultKind> {
        FaultKind::ALL.into_iter().find(|k| k.code() == code)
    }
}

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

/// Where the settings in force came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettingsSource {
    /// Changed by `set` since they were loaded, stored or reset to the defaults.
    Current = 0,
    /// Just written to flash (`store`).
    Stored = 1,
    /// Read from flash at boot.
    Loaded = 2,
    /// Built-in defaults: nothing stored yet.
    DefaultsNoRecord = 3,
    /// Built-in defaults: the newest stored record is corrupt, so none is used.
    DefaultsCorrupt = 4,
    /// Built-in defaults: the stored record does not validate (another version, bad values).
    DefaultsInvalid = 5,
    /// Built-in defaults: the flash could not be read.
    DefaultsFlashError = 6,
    /// Built-in defaults restored by `defaults` (not yet stored).
    DefaultsAsked = 7,
}

impl SettingsSource {
    /// Every source.
    pub const ALL: [SettingsSource; 8] = [
        SettingsSource::Current,
        SettingsSource::Stored,
        SettingsSource::Loaded,
        SettingsSource::DefaultsNoRecord,
        SettingsSource::DefaultsCorrupt,
        SettingsSource::DefaultsInvalid,
        SettingsSource::DefaultsFlashError,
        SettingsSource::DefaultsAsked,
    ];

    /// Wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`SettingsSource::code`].
    pub fn from_code(code: u8) -> Option<SettingsSource> {
        SettingsSource::ALL.get(code as usize).copied()
    }

    /// What it means, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            SettingsSource::Current => {
                "changed by `set` since they were loaded or stored (send store to keep them)"
            }
            SettingsSource::Stored => "stored in flash",
            SettingsSource::Loaded => "loaded from flash at boot",
            SettingsSource::DefaultsNoRecord => "no settings stored: using the built-in defaults",
            SettingsSource::DefaultsCorrupt => {
                "the stored settings are corrupt: using the built-in defaults"
            }
            SettingsSource::DefaultsInvalid => {
                "the stored settings are of another version or invalid: using the built-in defaults"
            }
            SettingsSource::DefaultsFlashError => {
                "the flash could not be read: using the built-in defaults"
            }
            SettingsSource::DefaultsAsked => "built-in defaults restored (send store to keep them)",
        }
    }
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
    /// records until then, so that encoding them never delays a safe state at the pins.
    fn flush(&mut self) {}
}

impl<T: LogSink + ?Sized> LogSink for &mut T {
    fn emit(&mut self, seq: u32, record: &Record) {
        (**self).emit(seq, record)
    }
    fn flush(&mut self) {
        (**self).flush()
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

/// The bytes a record's checksum covers, fed one field at a time in the order of the record's
/// format string (`defmt_sink.rs`), each little-endian at its wire width; a NaN always as the
/// canonical NaN (the host reads NaN back from its text, without its payload).
pub struct CrcFields(crc::Digest<'static, u32>);

impl CrcFields {
    /// An empty checksum.
    pub fn new() -> Self {
        CrcFields(RECORD_CRC.digest())
    }
    /// A `u8` field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn u8(mut self, v: u8) -> Self {
        self.0.update(&[v]);
        self
    }
    /// A `u16` field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn u16(mut self, v: u16) -> Self {
        self.0.update(&v.to_le_bytes());
        self
    }
    /// A `u32` field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn u32(mut self, v: u32) -> Self {
        self.0.update(&v.to_le_bytes());
        self
    }
    /// An `i64` field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn i64(mut self, v: i64) -> Self {
        self.0.update(&v.to_le_bytes());
        self
    }
    /// An `f32` field.
    // Not inlined: a record checksums ~25 fields, inlined they cost ~1.5 KiB of flash.
    #[inline(never)]
    pub fn f32(mut self, v: f32) -> Self {
        let bits = if v.is_nan() {
            f32::NAN.to_bits()
        } else {
            v.to_bits()
        };
        self.0.update(&bits.to_le_bytes());
        self
    }
    /// The checksum.
    pub fn finish(self) -> u32 {
        self.0.finalize()
    }
}

impl Default for CrcFields {
    fn default() -> Self {
        Self::new()
    }
}

/// The protocol and calibration fields of `run_start` and `settings`, in their order.
fn settings_crc(c: CrcFields, p: &Protocol, k: &Calibration) -> CrcFields {
    let s = Settings {
        protocol: *p,
        calibration: *k,
    };
    let fields = s.fields();
    let c = c.u8(fields[0] as u8);
    fields[1..].iter().fold(c, |c, &v| c.u32(v))
}

/// The checksum a record is logged with (`crc=` in its format string): over its sequence
/// number and every field, in the format string's order.
pub fn record_crc(seq: u32, record: &Record) -> u32 {
    let c = CrcFields::new().u32(seq);
    match record {
        Record::RunStart(s) => settings_crc(c.u32(s.run), &s.protocol, &s.calibration),
        Record::Settings(s) => settings_crc(
            c.u8(s.source.code()),
            &s.settings.protocol,
            &s.settings.calibration,
        ),
        Record::Live(l) => c
            .u32(l.t_ms)
            .u16(l.counts[0])
            .u16(l.counts[1])
            .f32(l.force_n[0])
            .f32(l.force_n[1])
            .f32(l.servo_deg),
        Record::Reply(r) => c
            .u8(r.command.code())
            .u8(r.error.map_or(0, |e| e.code()))
            .f32(r.values[0])
            .f32(r.values[1]),
        Record::Raw(r) => c
            .i64(r.t_us)
            .u16(r.counts[0])
            .u16(r.counts[1])
            .f32(r.force_n[0])
            .f32(r.force_n[1]),
        Record::Pair(p) => c
            .u32(p.step)
            .u32(p.level)
            .f32(p.angle_deg)
            .u32(p.t_mid_ms)
            .f32(p.t1.mean_n)
            .f32(p.t1.std_n)
            .u32(p.t1.count)
            .f32(p.t2.mean_n)
            .f32(p.t2.std_n)
            .u32(p.t2.count),
        Record::Fault(f) => c
            .u8(f.kind.code())
            .u8(f.channel.map_or(NONE_CODE, |ch| ch as u8))
            .f32(f.value)
            .i64(f.t_us),
        Record::RunEnd(e) => c
            .i64(e.t_us)
            .u32(e.pairs)
            .u8(e.fault.map_or(NONE_CODE, |k| k.code())),
    }
    .finish()
}
