//! A record's field values, read by name from its format (`elf::RecordLayout`), into the
//! firmware's own typed [`Record`]: the same struct the rig emitted, so the host works with
//! what the firmware means, not with a copy of it.

use crate::elf::{RecordKind, RecordLayout};
use firmware::calib::{AmpMap, Calibration, ChannelCal, ServoMap};
use firmware::command::{CommandError, CommandKind};
use firmware::condition::ChannelStats;
use firmware::hal::Channel;
use firmware::record::{
    Fault, FaultKind, Live, RawSample, Record, Reply, RunEnd, RunStart, SettingsReport,
    SettingsSource, StepPair, NONE_CODE,
};
use firmware::{Protocol, Settings, StepOrder};

/// Field values of one record, by name.
pub(super) struct Fields<'a> {
    pub layout: &'a RecordLayout,
    pub values: &'a [String],
}

impl Fields<'_> {
    fn raw(&self, name: &str) -> Result<&str, String> {
        let i = self
            .layout
            .position(name)
            .ok_or_else(|| format!("no field `{name}`"))?;
        self.values
            .get(i)
            .map(String::as_str)
            .ok_or_else(|| format!("field `{name}` missing from the frame"))
    }

    pub fn u(&self, name: &str) -> Result<u32, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not an unsigned integer"))
    }

    fn u8(&self, name: &str) -> Result<u8, String> {
        let v = self.u(name)?;
        u8::try_from(v).map_err(|_| format!("field `{name}`: {v} does not fit a byte"))
    }

    fn u16(&self, name: &str) -> Result<u16, String> {
        let v = self.u(name)?;
        u16::try_from(v).map_err(|_| format!("field `{name}`: {v} does not fit 16 bits"))
    }

    fn i64(&self, name: &str) -> Result<i64, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not an integer"))
    }

    fn f32(&self, name: &str) -> Result<f32, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not a number"))
    }

    /// An optional field (`RecordKind::optional_fields`): `default` when the firmware's
    /// record does not carry it (built before it did).
    fn f32_or(&self, name: &str, default: f32) -> Result<f32, String> {
        match self.layout.position(name) {
            Some(_) => self.f32(name),
            None => Ok(default),
        }
    }
}

/// The typed record of a kind from its fields.
pub(super) fn build(kind: RecordKind, f: &Fields) -> Result<Record, String> {
    Ok(match kind {
        RecordKind::RunStart => Record::RunStart(RunStart {
            run: f.u("run")?,
            protocol: protocol(f)?,
            calibration: calibration(f, Extra::IfPresent)?,
        }),
        RecordKind::Settings => {
            let code = f.u8("source")?;
            let source = SettingsSource::from_code(code)
                .ok_or_else(|| format!("unknown settings source code {code}"))?;
            let settings = Settings {
                protocol: protocol(f)?,
                calibration: calibration(f, Extra::Required)?,
            };
            Record::Settings(SettingsReport { source, settings })
        }
        RecordKind::Live => Record::Live(Live {
            t_ms: f.u("t_ms")?,
            counts: [f.u16("c1")?, f.u16("c2")?],
            force_n: [f.f32("t1_n")?, f.f32("t2_n")?],
            servo_deg: f.f32("servo_deg")?,
        }),
        RecordKind::Reply => Record::Reply(reply(f)?),
        RecordKind::Raw => Record::Raw(RawSample {
            t_us: f.i64("t_us")?,
            counts: [f.u16("c1")?, f.u16("c2")?],
            force_n: [f.f32("t1_n")?, f.f32("t2_n")?],
        }),
        RecordKind::Pair => Record::Pair(StepPair {
            step: f.u("step")?,
            level: f.u("level")?,
            angle_deg: f.f32("angle_deg")?,
            t_mid_ms: f.u("t_mid_ms")?,
            t1: stats(f, "t1")?,
            t2: stats(f, "t2")?,
        }),
        RecordKind::Fault => Record::Fault(Fault {
            kind: fault_kind(f.u8("kind")?)?,
            channel: channel(f.u8("channel")?)?,
            value: f.f32("value")?,
            t_us: f.i64("t_us")?,
        }),
        RecordKind::RunEnd => Record::RunEnd(RunEnd {
            t_us: f.i64("t_us")?,
            pairs: f.u("pairs")?,
            fault: match f.u8("fault")? {
                NONE_CODE => None,
                c => Some(fault_kind(c)?),
            },
        }),
    })
}

fn protocol(f: &Fields) -> Result<Protocol, String> {
    let order = f.u8("order")?;
    Ok(Protocol {
        rest_deg: f.f32("rest_deg")?,
        step_deg: f.f32("step_deg")?,
        final_deg: f.f32("final_deg")?,
        order: StepOrder::from_code(order)
            .ok_or_else(|| format!("unknown step order code {order}"))?,
        dwell_ms: f.u("dwell_ms")?,
        pre_trigger_ms: f.u("pre_trigger_ms")?,
        trigger_ms: f.u("trigger_ms")?,
        tare_ms: f.u("tare_ms")?,
        amp_control_v: f.f32("amp_control_v")?,
        sample_hz: f.u("sample_hz")?,
        raw_log_hz: f.u("raw_log_hz")?,
        window_after_change_ms: f.u("window_after_ms")?,
        window_before_next_ms: f.u("window_before_ms")?,
        capstan_diameter_mm: f.f32("diameter_mm")?,
        wrap_deg: f.f32("wrap_deg")?,
    })
}

/// How the calibration fields `run_start` did not always carry (tare reference, servo map,
/// amplifier full scale) are read.
#[derive(Clone, Copy)]
enum Extra {
    /// Always there (`settings`).
    Required,
    /// The firmware's defaults when absent (`run_start` of a firmware built before them;
    /// `Firmware::record_has_field` tells which were sent). Not NaN: records compare equal.
    IfPresent,
}

fn calibration(f: &Fields, how: Extra) -> Result<Calibration, String> {
    let d = Calibration::default();
    let extra = |name: &str, default: f32| match how {
        Extra::Required => f.f32(name),
        Extra::IfPresent => f.f32_or(name, default),
    };
    let channel = |ch: &str| -> Result<ChannelCal, String> {
        Ok(ChannelCal {
            zero_counts: f.f32(&format!("{ch}_zero"))?,
            n_per_count: f.f32(&format!("{ch}_n_per_count"))?,
        })
    };
    Ok(Calibration {
        t1: channel("t1")?,
        t2: channel("t2")?,
        tare_reference_n: extra("tare_reference_n", d.tare_reference_n)?,
        servo: ServoMap {
            pulse_at_min_us: extra("servo_min_us", d.servo.pulse_at_min_us)?,
            pulse_at_max_us: extra("servo_max_us", d.servo.pulse_at_max_us)?,
            max_deg: extra("servo_max_deg", d.servo.max_deg)?,
        },
        amp: AmpMap {
            amp_gain: f.f32("amp_gain")?,
            full_scale_v: extra("amp_full_scale_v", d.amp.full_scale_v)?,
        },
    })
}

fn reply(f: &Fields) -> Result<Reply, String> {
    let code = f.u8("command")?;
    let command =
        CommandKind::from_code(code).ok_or_else(|| format!("unknown command code {code}"))?;
    let error = match f.u8("error")? {
        0 => None,
        e => Some(CommandError::from_code(e).ok_or_else(|| format!("unknown error code {e}"))?),
    };
    Ok(Reply {
        command,
        error,
        values: [f.f32("v1")?, f.f32("v2")?],
    })
}

fn stats(f: &Fields, ch: &str) -> Result<ChannelStats, String> {
    Ok(ChannelStats {
        mean_n: f.f32(&format!("{ch}_mean_n"))?,
        std_n: f.f32(&format!("{ch}_std_n"))?,
        count: f.u(&format!("{ch}_count"))?,
    })
}

fn fault_kind(code: u8) -> Result<FaultKind, String> {
    FaultKind::from_code(code).ok_or_else(|| format!("unknown fault kind code {code}"))
}

fn channel(code: u8) -> Result<Option<Channel>, String> {
    match code {
        0 => Ok(Some(Channel::T1)),
        1 => Ok(Some(Channel::T2)),
        NONE_CODE => Ok(None),
        c => Err(format!("unknown channel code {c}")),
    }
}
