//! The conditioning settings: what the user asked for ([`Request`]) checked and completed with
//! the firmware protocol's defaults ([`Settings`]).

use crate::error::{in_range, option, Error};
use crate::levels::Placement;
use capstan_data::ranges;

/// What a user asked for (the command's options): `None` takes the firmware protocol's.
#[derive(Clone, Debug)]
pub struct Request {
    /// Protocol: the first level change, s of the file's time (or after the trigger's edge).
    pub first_change_s: Option<f64>,
    /// Protocol: time each level is held, s.
    pub dwell_s: Option<f64>,
    /// A trigger column was named: its first rising edge is the run's time zero.
    pub trigger: bool,
    /// Levels per run.
    pub levels: Option<u32>,
    /// Shortest time between two level changes when finding them, s.
    pub min_dwell_s: f64,
    /// The window starts this long after a change, ms.
    pub window_after_ms: Option<u32>,
    /// The window ends this long before the next change, ms.
    pub window_before_ms: Option<u32>,
    /// Wrap angle for the pairs, deg.
    pub wrap_deg: f64,
    /// Capstan diameter for the pairs, mm.
    pub diameter_mm: Option<f64>,
    /// Drive voltage for the pairs, V.
    pub drive_v: Option<f64>,
    /// The first run's number.
    pub first_run: u32,
}

/// The conditioning settings.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Where the levels change.
    pub placement: Placement,
    /// The window starts this long after a change, s.
    pub window_after_s: f64,
    /// The window ends this long before the next change, s.
    pub window_before_s: f64,
    /// Levels expected per run (checked when the levels are found from the tensions).
    pub levels: u32,
    /// Rig facts for the pairs.
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: Option<f64>,
    /// Drive voltage, V.
    pub drive_v: Option<f64>,
    /// The first run's number (runs without a number in the file count up from it).
    pub first_run: u32,
}

impl Settings {
    /// The firmware's windows (the thesis's: 2 s after a change, 1 s before the next).
    pub fn firmware_windows() -> (f64, f64) {
        let p = capstan_rig::Protocol::default();
        (
            p.window_after_change_ms as f64 / 1e3,
            p.window_before_next_ms as f64 / 1e3,
        )
    }

    /// The settings `a` asks for: the rig facts checked against their physical ranges; the
    /// levels from the protocol when its first change and dwell are given (or a trigger
    /// column), found from the tensions otherwise; every default the firmware protocol's.
    pub fn from_request(a: &Request) -> Result<Settings, Error> {
        in_range(&ranges::WRAP_DEG, "--wrap-deg", a.wrap_deg)?;
        if let Some(d) = a.diameter_mm {
            in_range(&ranges::DIAMETER_MM, "--diameter-mm", d)?;
        }
        if let Some(v) = a.drive_v {
            in_range(&ranges::DRIVE_V, "--drive-v", v)?;
        }
        if a.first_run == 0 {
            let why = "--run 0: runs are numbered from 1 (the first run's number)".to_string();
            return Err(option("--run", why));
        }
        let (after, before) = Settings::firmware_windows();
        let after = a.window_after_ms.map_or(after, |m| m as f64 / 1e3);
        let before = a.window_before_ms.map_or(before, |m| m as f64 / 1e3);
        let levels = a
            .levels
            .unwrap_or(capstan_rig::Protocol::default().levels());
        let placement = placement(a, levels)?;
        if let Placement::Protocol { dwell_s, .. } | Placement::Trigger { dwell_s, .. } = &placement
        {
            if !(dwell_s.is_finite() && *dwell_s > 0.0) {
                let why = format!("--dwell-s {dwell_s}: must be a positive number of seconds");
                return Err(option("--dwell-s", why));
            }
        }
        if !(a.min_dwell_s.is_finite() && a.min_dwell_s > 0.0) {
            let why = format!("--min-dwell-s {}: must be positive", a.min_dwell_s);
            return Err(option("--min-dwell-s", why));
        }
        Ok(Settings {
            placement,
            window_after_s: after,
            window_before_s: before,
            levels,
            wrap_deg: a.wrap_deg,
            diameter_mm: a.diameter_mm,
            drive_v: a.drive_v,
            first_run: a.first_run,
        })
    }
}

/// Where the levels change: the protocol given, the trigger's edge and the protocol (the
/// firmware's where not given), or found from the tensions.
fn placement(a: &Request, levels: u32) -> Result<Placement, Error> {
    let p = capstan_rig::Protocol::default();
    // Step 0 (rest) starts `trigger_ms` after the trigger's edge; level 1 a dwell later.
    let proto_first = (p.trigger_ms + p.dwell_ms) as f64 / 1e3;
    Ok(match (a.first_change_s, a.dwell_s, a.trigger) {
        (Some(first), Some(dwell), false) => Placement::Protocol {
            first_s: first,
            dwell_s: dwell,
            levels,
        },
        (first, dwell, true) => Placement::Trigger {
            first_s: first.unwrap_or(proto_first),
            dwell_s: dwell.unwrap_or(p.dwell_ms as f64 / 1e3),
            levels,
        },
        (None, Some(_), false) => {
            let why = "--dwell-s needs --first-change-s (or --trigger-column)";
            return Err(option("--dwell-s", why.into()));
        }
        _ => Placement::Detect {
            min_dwell_s: a.min_dwell_s,
        },
    })
}
