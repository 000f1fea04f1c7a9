//! The settings, defined once: every value of the protocol and the calibration with its name,
//! how it is held, its unit and what it means, in their wire order: the order of the
//! `run_start` and `settings` records' fields and of the firmware's flash layout. The firmware's
//! command keys (`set KEY VALUE`), its flash layout and its records' fields, and the host's
//! decoder and its listings of the settings, are all derived from the one table below.

/// How a setting is held (and sent: its wire type, [`Value::prim`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Value {
    /// A code, one byte: the step order ([`crate::StepOrder::code`]), the control mode, the
    /// force profile, a sensitivity's source ([`crate::CalSource::code`]); each named by
    /// [`Setting::code_name`].
    Code,
    /// A whole number (ms, Hz), `u32`.
    Whole,
    /// A real number, `f32`.
    Real,
}

impl Value {
    /// Its type on the wire.
    pub const fn prim(self) -> crate::Prim {
        match self {
            Value::Code => crate::Prim::U8,
            Value::Whole => crate::Prim::U32,
            Value::Real => crate::Prim::F32,
        }
    }
}

/// What a setting belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// The test protocol (what a run does).
    Protocol,
    /// The calibration (how counts and angles map to forces and pulses).
    Calibration,
    /// Force control (issue 43): the mode, the T2 target profile, the controller's gains and
    /// the fitted capstan law its feedforward goes through.
    Force,
}

/// Since when the `run_start` record carries a setting (the `settings` record carries all).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Since {
    /// From the first firmware on.
    First,
    /// Since setup mode (the tare reference, the servo map and the amplifier's full scale): a
    /// `run_start` of a firmware built before it lacks them, and the host reads it anyway.
    SetupMode,
    /// Since force control (issue 43): a `run_start` of an older firmware lacks them (the host
    /// takes the defaults: protocol mode).
    ForceControl,
    /// Since the calibration says where its sensitivities came from (issue 38): neither
    /// record of a firmware built before it has them, and the host reads both anyway.
    Provenance,
}

/// The table: `Variant "name" group value "unit" since key "meaning";` one row per setting, in
/// wire order. `key` is the setting's code in the `reply` to a `set` (the order `capstan rig` lists
/// the keys in), or `fixed` for a setting the host cannot set (the rates, fixed at build time).
macro_rules! settings {
    ($($v:ident $name:literal $group:ident $value:ident $unit:literal $since:ident $key:tt $meaning:literal;)*) => {
        /// One value of the settings, in wire order (its discriminant is its index).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum Setting {
            $(#[doc = $meaning] $v,)*
        }

        impl Setting {
            /// Every setting, in wire order.
            pub const ALL: [Setting; SETTINGS] = [$(Setting::$v),*];

            /// Its name: the field of the records, the key of `set`.
            pub const fn name(self) -> &'static str {
                match self { $(Setting::$v => $name,)* }
            }

            /// What it belongs to.
            pub const fn group(self) -> Group {
                match self { $(Setting::$v => Group::$group,)* }
            }

            /// How it is held.
            pub const fn value(self) -> Value {
                match self { $(Setting::$v => Value::$value,)* }
            }

            /// Its unit (empty for the order).
            pub const fn unit(self) -> &'static str {
                match self { $(Setting::$v => $unit,)* }
            }

            /// Since when `run_start` carries it.
            pub const fn since(self) -> Since {
                match self { $(Setting::$v => Since::$since,)* }
            }

            /// What it sets, in a few words.
            pub const fn meaning(self) -> &'static str {
                match self { $(Setting::$v => $meaning,)* }
            }

            /// Its key, if the host may set it by name.
            pub const fn key(self) -> Option<Key> {
                match self { $(Setting::$v => key_of!($v $key),)* }
            }
        }

        keys! { [] [] $($v $key $meaning;)* }
    };
}

/// The key of a row: `fixed` has none.
macro_rules! key_of {
    ($v:ident fixed) => {
        None
    };
    ($v:ident $code:literal) => {
        Some(Key::$v)
    };
}

/// The [`Key`] enum of the rows that have a key code, and their list in row order.
macro_rules! keys {
    ([$($done:tt)*] [$($rows:tt)*]) => {
        /// A setting the host may set by name (`set KEY VALUE`); its discriminant is its code
        /// in the `reply` to a `set`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum Key {
            $($done)*
        }

        /// The keys in wire order.
        const KEYS_BY_ROW: [Key; KEYS] = [$($rows)*];
    };
    ([$($done:tt)*] [$($rows:tt)*] $v:ident fixed $meaning:literal; $($rest:tt)*) => {
        keys! { [$($done)*] [$($rows)*] $($rest)* }
    };
    ([$($done:tt)*] [$($rows:tt)*] $v:ident $code:literal $meaning:literal; $($rest:tt)*) => {
        keys! { [$($done)* #[doc = $meaning] $v = $code,] [$($rows)* Key::$v,] $($rest)* }
    };
}

/// Values in the settings: 15 of the protocol, 10 of the calibration, 18 of force control, then
/// 4 of the calibration's provenance (appended after force control: the wire order only grows).
pub const SETTINGS: usize = 47;

/// Settings the host may set by name (all but the two rates).
pub const KEYS: usize = 41;

settings! {
    // variant     name               group       value unit      run_start key meaning
    Order          "order"            Protocol    Code  ""        First     3  "order of the levels: monotone, updown or pulse";
    RestDeg        "rest_deg"         Protocol    Real  "°"       First     0  "servo angle at rest and for step 0";
    StepDeg        "step_deg"         Protocol    Real  "°"       First     1  "servo angle change per tension level";
    FinalDeg       "final_deg"        Protocol    Real  "°"       First     2  "servo angle of the highest level";
    DwellMs        "dwell_ms"         Protocol    Whole "ms"      First     4  "time each level is held";
    PreTriggerMs   "pre_trigger_ms"   Protocol    Whole "ms"      First     5  "from the button (or run) to the logger trigger";
    TriggerMs      "trigger_ms"       Protocol    Whole "ms"      First     6  "logger trigger pulse length";
    TareMs         "tare_ms"          Protocol    Whole "ms"      First     7  "tare window before the trigger (0: keep the zeros)";
    AmpControlV    "amp_control_v"    Protocol    Real  "V"       First     8  "amplifier control voltage during a run";
    SampleHz       "sample_hz"        Protocol    Whole "Hz"      First     fixed "sampling rate of both force channels (fixed by the firmware)";
    RawLogHz       "raw_log_hz"       Protocol    Whole "Hz"      First     fixed "rate of the raw samples in the log (fixed by the firmware)";
    WindowAfterMs  "window_after_ms"  Protocol    Whole "ms"      First     9  "conditioning window starts this long after a change";
    WindowBeforeMs "window_before_ms" Protocol    Whole "ms"      First     10 "conditioning window ends this long before the next";
    DiameterMm     "diameter_mm"      Protocol    Real  "mm"      First     11 "capstan diameter (for the log; 0 = not given)";
    WrapDeg        "wrap_deg"         Protocol    Real  "°"       First     12 "wrap angle (for the log; 0 = not given)";
    AmpGain        "amp_gain"         Calibration Real  "V/V"     First     22 "drive volts per control volt";
    T1Zero         "t1_zero"          Calibration Real  "counts"  First     13 "T1 reading at no load (zero sets it)";
    T1NPerCount    "t1_n_per_count"   Calibration Real  "N/count" First     14 "T1 sensitivity (weigh t1 sets it)";
    T2Zero         "t2_zero"          Calibration Real  "counts"  First     15 "T2 reading at no load (zero sets it)";
    T2NPerCount    "t2_n_per_count"   Calibration Real  "N/count" First     16 "T2 sensitivity (weigh t2 sets it)";
    TareReferenceN "tare_reference_n" Calibration Real  "N"       SetupMode 17 "force both channels carry during the tare";
    ServoMinUs     "servo_min_us"     Calibration Real  "µs"      SetupMode 18 "servo pulse at 0°";
    ServoMaxUs     "servo_max_us"     Calibration Real  "µs"      SetupMode 19 "servo pulse at servo_max_deg";
    ServoMaxDeg    "servo_max_deg"    Calibration Real  "°"       SetupMode 20 "servo angle reached at servo_max_us";
    AmpFullScaleV  "amp_full_scale_v" Calibration Real  "V"       SetupMode 21 "amplifier control voltage at full PWM duty";
    Mode           "mode"             Force       Code  ""        ForceControl 23 "what a run does: protocol (servo steps) or force (T2 held to a target)";
    ForceProfile   "force_profile"    Force       Code  ""        ForceControl 24 "force mode's T2 target: steps, ramp or sine";
    ForceLevel1N   "force_level1_n"   Force       Real  "N"       ForceControl 25 "T2 target of segment 1 (ramp: start; sine: mean)";
    ForceLevel2N   "force_level2_n"   Force       Real  "N"       ForceControl 26 "T2 target of segment 2 (ramp: end; sine: amplitude; 0 ends the steps)";
    ForceLevel3N   "force_level3_n"   Force       Real  "N"       ForceControl 27 "T2 target of segment 3 (steps; 0 ends them)";
    ForceLevel4N   "force_level4_n"   Force       Real  "N"       ForceControl 28 "T2 target of segment 4 (steps; 0 ends them)";
    ForceSineHz    "force_sine_hz"    Force       Real  "Hz"      ForceControl 29 "sine: first frequency";
    ForceSineToHz  "force_sine_to_hz" Force       Real  "Hz"      ForceControl 30 "sine: last frequency (log-spaced between)";
    ForceSineSteps "force_sine_steps" Force       Whole ""        ForceControl 31 "sine: frequencies, one per segment (1 to 16)";
    ForceKp        "force_kp"         Force       Real  "N/N"     ForceControl 32 "T2 feedback: proportional gain (0 with force_ki 0: open loop)";
    ForceKi        "force_ki"         Force       Real  "1/s"     ForceControl 33 "T2 feedback: integral gain";
    ForceT1Gain    "force_t1_gain"    Force       Real  "°/s/N"   ForceControl 34 "servo speed per N of T1 error (the T1 loop)";
    ForceRateDegS  "force_rate_deg_s" Force       Real  "°/s"     ForceControl 35 "fastest servo command in force mode";
    ForceShapeMs   "force_shape_ms"   Force       Whole "ms"      ForceControl 36 "a jump of the target is shaped over this time constant (0: none)";
    ModelMu        "model_mu"         Force       Real  ""        ForceControl 37 "fitted law: mu at the rig's diameter and drive (0: no model)";
    ModelHeatPerN  "model_heat_per_n" Force       Real  "1/N"     ForceControl 38 "fitted law: mu falls by exp(-this x (T2 - T1)) (contact heating, settled)";
    ModelT2OffsetN "model_t2_offset_n" Force      Real  "N"       ForceControl 39 "fitted law: what the T2 sensor adds while the capstan turns";
    ModelExponent  "model_exponent"   Force       Real  ""        ForceControl 40 "fitted law: tension exponent n (1: Euler-Eytelwein)";
    T1Cal          "t1_cal"           Calibration Code  ""        Provenance fixed "how T1's sensitivity came to be: unmeasured (the placeholder), weighed or typed";
    T1CalZero      "t1_cal_zero"      Calibration Real  "counts"  Provenance fixed "the T1 zero its sensitivity was weighed or typed at (a zero more than 1 N from it leaves it unmeasured)";
    T2Cal          "t2_cal"           Calibration Code  ""        Provenance fixed "how T2's sensitivity came to be: unmeasured (the placeholder), weighed or typed";
    T2CalZero      "t2_cal_zero"      Calibration Real  "counts"  Provenance fixed "the T2 zero its sensitivity was weighed or typed at (a zero more than 1 N from it leaves it unmeasured)";
}

impl Setting {
    /// Its index in wire order.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The setting of a name.
    pub fn from_name(name: &str) -> Option<Setting> {
        Setting::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The name of a code of a [`Value::Code`] setting (the step order, the control mode, the
    /// force profile), as `set KEY NAME` takes it; `None` for another setting or an unknown code.
    pub const fn code_name(self, code: u8) -> Option<&'static str> {
        match self {
            Setting::Order => match crate::StepOrder::from_code(code) {
                Some(o) => Some(o.name()),
                None => None,
            },
            Setting::Mode => match crate::ControlMode::from_code(code) {
                Some(m) => Some(m.name()),
                None => None,
            },
            Setting::ForceProfile => match crate::ForceProfile::from_code(code) {
                Some(p) => Some(p.name()),
                None => None,
            },
            Setting::T1Cal | Setting::T2Cal => match crate::CalSource::from_code(code) {
                Some(c) => Some(c.name()),
                None => None,
            },
            _ => None,
        }
    }

    /// The code of a name of a [`Value::Code`] setting (as bytes: the board's parser has no
    /// `str`).
    pub fn code_of_name(self, name: &[u8]) -> Option<u8> {
        (0..=u8::MAX)
            .take_while(|&c| self.code_name(c).is_some())
            .find(|&c| self.code_name(c).is_some_and(|n| n.as_bytes() == name))
    }
}

impl Key {
    /// Every key, by code: the order `capstan rig` lists them in.
    pub const ALL: [Key; KEYS] = {
        let mut all = [KEYS_BY_ROW[0]; KEYS];
        let mut i = 0;
        while i < KEYS {
            all[KEYS_BY_ROW[i] as usize] = KEYS_BY_ROW[i];
            i += 1;
        }
        all
    };

    /// The setting it sets.
    pub const fn setting(self) -> Setting {
        KEY_SETTINGS[self as usize]
    }

    /// Its name on the command line (the setting's).
    pub const fn name(self) -> &'static str {
        self.setting().name()
    }

    /// Its index among the settings, in wire order.
    pub const fn field(self) -> usize {
        self.setting().index()
    }

    /// Its code in the `reply` to a `set`.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The key of a code.
    pub fn from_code(code: u8) -> Option<Key> {
        Key::ALL.get(code as usize).copied()
    }

    /// The key of a name (`None` for a name that is not a setting, or one the host cannot set).
    pub fn from_name(name: &str) -> Option<Key> {
        Key::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// The setting of each key, by code.
const KEY_SETTINGS: [Setting; KEYS] = {
    let mut by_code = [Setting::Order; KEYS];
    let mut i = 0;
    while i < SETTINGS {
        if let Some(k) = Setting::ALL[i].key() {
            by_code[k as usize] = Setting::ALL[i];
        }
        i += 1;
    }
    by_code
};

// The table is whole: one row per setting, each key code used once.
const _: () = {
    let mut i = 0;
    while i < SETTINGS {
        assert!(Setting::ALL[i] as usize == i);
        i += 1;
    }
    let mut c = 0;
    while c < KEYS {
        assert!(
            Key::ALL[c] as usize == c,
            "key codes must be 0..KEYS, each once"
        );
        c += 1;
    }
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_keys_name_their_settings() {
        for (i, a) in Setting::ALL.iter().enumerate() {
            assert_eq!(Setting::from_name(a.name()), Some(*a));
            assert!(Setting::ALL[..i].iter().all(|b| b.name() != a.name()));
        }
        for k in Key::ALL {
            assert_eq!(k.setting().key(), Some(k));
            assert_eq!(Key::from_name(k.name()), Some(k));
            assert_eq!(Key::from_code(k.code()), Some(k));
        }
        assert_eq!(Key::from_name("sample_hz"), None);
        assert_eq!(Key::ALL[0], Key::RestDeg);
        assert_eq!(Key::Order.field(), 0);
        assert_eq!(Key::AmpGain.field(), 15);
    }

    #[test]
    fn protocol_calibration_force_control_then_the_calibrations_provenance() {
        for s in Setting::ALL {
            let group = match s.index() {
                0..15 => Group::Protocol,
                15..25 | 43.. => Group::Calibration,
                _ => Group::Force,
            };
            assert_eq!(s.group(), group, "{}", s.name());
            // Force control and the provenance came later: an older run_start lacks them.
            assert_eq!(s.since() == Since::ForceControl, group == Group::Force);
            assert_eq!(
                s.since() == Since::Provenance,
                s.index() >= 43,
                "{}",
                s.name()
            );
        }
    }

    #[test]
    fn every_setting_has_a_unit_but_codes_counts_and_pure_numbers() {
        let unitless = [
            Setting::Order,
            Setting::Mode,
            Setting::ForceProfile,
            Setting::ForceSineSteps,
            Setting::ModelMu,
            Setting::ModelExponent,
            Setting::T1Cal,
            Setting::T2Cal,
        ];
        for s in Setting::ALL {
            assert_eq!(s.unit().is_empty(), unitless.contains(&s), "{}", s.name());
        }
    }

    #[test]
    fn codes_have_names_both_ways() {
        for s in Setting::ALL {
            let named = (0..=u8::MAX).filter(|&c| s.code_name(c).is_some()).count();
            assert_eq!(named > 0, s.value() == Value::Code, "{}", s.name());
            for c in 0..named as u8 {
                let name = s.code_name(c).unwrap();
                assert_eq!(s.code_of_name(name.as_bytes()), Some(c));
            }
        }
        assert_eq!(Setting::Mode.code_of_name(b"force"), Some(1));
        assert_eq!(Setting::ForceProfile.code_of_name(b"sine"), Some(2));
        assert_eq!(Setting::Mode.code_of_name(b"sine"), None);
    }
}
