//! The plant's constants. `Default` is the thesis's rig (appendix m-files and text); where the
//! thesis contradicts itself, the choice and its reason are written next to the number.

use crate::disturb::{Disturbances, Unmodelled};
use capstan_physics::Model;

pub use crate::servo::ServoCharacteristic;

/// The rest pulse of the thesis's rig, µs: its sketch's `myservo.write(125)` under the Arduino
/// Servo library's default 544-2400 µs over 0-180°.
pub const THESIS_REST_PULSE_US: f64 = 544.0 + 125.0 * (2_400.0 - 544.0) / 180.0;

/// The HiTec HS-322HD servo and its lever.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoConfig {
    /// Pulse width to horn angle: the servo's own (HS-322HD data sheet).
    pub characteristic: ServoCharacteristic,
    /// PWM frame, µs: a new pulse width is taken at the next frame (50 Hz). A frame without a
    /// pulse (duty 0) leaves the servo unpowered: its motor drives nothing, and the cord
    /// back-drives the horn toward release (`unpowered_hold_nm`, `backdrive_deg_per_s_per_nm`).
    pub frame_us: u32,
    /// The pulse the rig holds at rest, µs: where the operator tightened the tension bolt to
    /// the cord's preload, and what "servo at rest" means for [`crate::Plant::is_safe`]
    /// (within the dead band). Default [`THESIS_REST_PULSE_US`], 1832.9 µs (horn at 123.3°).
    pub rest_pulse_us: f64,
    /// No-load slew rate, deg/s (0.19 s per 60° at 4.8 V).
    pub no_load_deg_per_s: f64,
    /// Stall torque, N m (3.0 kg cm at 4.8 V); the slew rate falls linearly to zero at it.
    pub stall_torque_nm: f64,
    /// Lever radius from the servo axis to the cord, m (the thesis's 6.35 mm).
    pub lever_m: f64,
    /// Unpowered (no pulses), the gear train holds the horn against the cord up to this
    /// torque, N m; above it the cord turns the horn toward release. Assumed, not measured:
    /// 0.003 N m (1 % of the stall torque; T1 ≈ 0.47 N on the 6.35 mm lever), so that even
    /// the first level's 0.75 N back-drives it, as the issue reports of the rig. 0 with
    /// `backdrive_deg_per_s_per_nm` 0: an unpowered horn holds still (the plant before).
    pub unpowered_hold_nm: f64,
    /// How fast the cord back-drives an unpowered horn per N m above the hold, deg/s
    /// (assumed: 2000, so 21 N on the lever swings it at ~260 deg/s; capped at the no-load
    /// slew rate).
    pub backdrive_deg_per_s_per_nm: f64,
    /// The position control's dead band in the motion (`crate::servo`; off by default).
    pub dynamics: crate::servo::ServoDynamics,
}

impl Default for ServoConfig {
    fn default() -> Self {
        ServoConfig {
            characteristic: ServoCharacteristic::HS_322HD,
            frame_us: 20_000,
            rest_pulse_us: THESIS_REST_PULSE_US,
            no_load_deg_per_s: 60.0 / 0.19,
            stall_torque_nm: 3.0 * 9.81e-2,
            lever_m: 6.35e-3,
            unpowered_hold_nm: 0.003,
            backdrive_deg_per_s_per_nm: 2_000.0,
            dynamics: crate::servo::ServoDynamics::EXACT,
        }
    }
}

/// The cord as a hardening spring between the lever and the fixed sensor.
///
/// A cord element at tension T is stretched by ε(T) = (T/k)^(1/p) (mm, p > 1: soft at first,
/// stiffer as it straightens). The lever side carries T1 over one unit of free length, the
/// fixed side T2 over `far_side_ratio` units, so the stretch the lever imposes is
/// ε(T1) + λ·ε(T2). With the capstan stopped T2 = T1; turning, T2 follows the friction law, and
/// the harder the capstan amplifies, the less T1 a given lever travel makes — which is why the
/// thesis's T1 at step 12 falls from ~21 N at 270° to ~12 N at 720°.
///
/// Default: fitted (least squares in log T1) to the mean T1 per step and wrap of the thesis's
/// appendix data, constrained so that Euler-Eytelwein with mu = 0.115 keeps T2 at or below 42 N
/// at 720° — under the firmware's 45 N over-force limit (the thesis's own cords reached 47-55 N
/// at 630-720°, which that limit would stop). Result: T1 0.75 → 21 N over steps 1-12 at 270°,
/// 0.35 → 8.7 N at 720°.
///
/// The fit (k = 12.68) counted 5° of lever travel per protocol step. With the protocol's
/// angles as the thesis's Arduino meant them and the HS-322HD's own 0.1°/µs, a step is
/// 5 · (2400 − 544)/180 µs · 0.1°/µs = 5.156° of horn (s = 1.0311 times more). The stretch the
/// lever imposes scales by s, and so does the preload's (ε_pre ∝ k^(−1/p)): k' = k · s^(−p) =
/// 12.68 · 1.0311^(−1.45) = 12.13 gives the same tensions at every step, to 0.1-0.2 % (the
/// rounding of k and the PWM's 0.32 µs steps): e.g. Euler-Eytelwein at mu 0.115, 270°, steps
/// 1/6/12: 0.753/7.915/21.048 N before, 0.754/7.924/21.066 N now (the plant test
/// `euler_eytelwein_is_exact_and_the_protocol_spans_the_thesis_tensions` holds the ranges).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordConfig {
    /// Tension with the servo at rest and the capstan stopped, N (the tension bolt's 0.1 N).
    pub preload_n: f64,
    /// k in T = k·ε^p, N/mm^p.
    pub stiffness: f64,
    /// p in T = k·ε^p (1 = linear spring).
    pub hardening: f64,
    /// λ: free length on the fixed (T2) side relative to the lever (T1) side.
    pub far_side_ratio: f64,
}

impl Default for CordConfig {
    fn default() -> Self {
        CordConfig {
            preload_n: 0.1,
            stiffness: 12.13,
            hardening: 1.45,
            far_side_ratio: 2.6,
        }
    }
}

/// The power amplifier and the Pittman GM14904S016 gearmotor that turns the capstan.
///
/// The thesis's m-file gives R = 46.5 Ω, but its own data sheet lines (24 V, no-load 179 rpm
/// at the output, no-load current 0.26 A) only agree with 4.65 Ω: with 46.5 Ω the no-load
/// current alone would be half the stall current and the 10 V stall torque (0.26 N m at the
/// output) would be below the 0.39 N m the thesis's 1.0 in capstan data needs — the motor would
/// stall in the very runs the thesis reports. So the default is 4.65 Ω, with the no-load figures
/// split into Coulomb (4 mN m) and viscous (3.2e-5 N m s/rad) motor friction; set
/// `resistance_ohm: 46.5` to see the thesis-as-written motor stall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorConfig {
    /// Torque (and back-emf) constant, N m/A.
    pub kt_nm_per_a: f64,
    /// Winding resistance, Ω.
    pub resistance_ohm: f64,
    /// Gearbox reduction (motor turns per capstan turn).
    pub gear_ratio: f64,
    /// Rotor inertia, kg m² (the capstan's, reflected through 19.7², is negligible).
    pub rotor_inertia_kg_m2: f64,
    /// Viscous friction at the motor shaft, N m s/rad.
    pub viscous_nms: f64,
    /// Coulomb friction at the motor shaft, N m.
    pub coulomb_nm: f64,
    /// Power amplifier gain, drive volts per control volt (the firmware's `AmpMap::amp_gain`).
    pub amp_gain: f64,
    /// Amplifier control input at 100 % PWM duty, V (RC-filtered 3.3 V pin).
    pub amp_full_scale_v: f64,
    /// Amplifier supply: the drive voltage saturates here, V.
    pub amp_supply_v: f64,
    /// Time constant of the RC filter between the PWM pin and the amplifier's control input
    /// while the pin is driven, s (the hardware chapter's 4.7 kΩ and 1 µF: 4.7 ms; a step settles to 1 %
    /// in 22 ms, so after a fault the drive needs that long to fall below 1 %). 0 = no filter.
    pub amp_filter_tau_s: f64,
    /// ... and while the pin is not driven (a reset, the chip unpowered, booting): the
    /// capacitor discharges through the series resistor and the pull-down on the pin's side,
    /// s (the hardware chapter's 4.7 kΩ + 2.2 kΩ, 1 µF: 6.9 ms. With the 100 kΩ pull-down the hardware chapter
    /// gave before issue 38 it was 104.7 ms: ~0.5 s to 1 %, 22 × slower than documented).
    pub amp_filter_released_tau_s: f64,
}

impl Default for MotorConfig {
    fn default() -> Self {
        MotorConfig {
            kt_nm_per_a: 0.0612,
            resistance_ohm: 4.65,
            gear_ratio: 19.7,
            rotor_inertia_kg_m2: 2.6e-5,
            viscous_nms: 3.2e-5,
            coulomb_nm: 0.004,
            amp_gain: 4.0,
            amp_full_scale_v: 3.3,
            amp_supply_v: 24.0,
            amp_filter_tau_s: 0.0047,
            amp_filter_released_tau_s: 0.0069,
        }
    }
}

/// One force sensor on the 12-bit ADC.
///
/// counts = zero + gain·reading/`n_per_count` + noise, rounded and clamped to 0..=4095. The
/// nominal transfer is the firmware's `Calibration::default()` (400 counts, 0.015 N/count), so
/// the firmware's calibration is right for these sensors; each plant draws its own zero around
/// the nominal one (the tare removes it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorConfig {
    /// Nominal counts at zero force.
    pub zero_counts: f64,
    /// Nominal sensitivity, N per count.
    pub n_per_count: f64,
    /// Sensitivity of the actual sensor relative to nominal (1 = exactly nominal).
    pub gain: f64,
    /// Standard deviation of each plant's zero around the nominal one, counts.
    pub zero_spread_counts: f64,
    /// Gaussian noise per conversion, N (standard deviation; 0 = none).
    pub noise_sd_n: f64,
    /// The highest reading the sensor can produce at the ADC, counts: its output saturates
    /// at its supply, and a 0-5 V sensor behind the board's 10k/18k divider reads 3989.6
    /// counts there (5 V × 18/28 of a 3.3 V, 4096-count ADC). A force beyond that reads as
    /// this, pinned. `f64::INFINITY`: no saturation below the ADC's own 4095.
    pub saturation_counts: f64,
}

/// Where a 0-5 V sensor saturates behind the hardware chapter's 10 kΩ / 18 kΩ divider, ADC counts.
pub const DIVIDER_SATURATION_COUNTS: f64 = 5.0 * 18.0 / 28.0 / 3.3 * 4096.0;

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            zero_counts: 400.0,
            n_per_count: 0.015,
            gain: 1.0,
            zero_spread_counts: 10.0,
            noise_sd_n: 0.02,
            saturation_counts: DIVIDER_SATURATION_COUNTS,
        }
    }
}

/// The ADC the sensors are read through (the RP2040's): what it adds to every conversion,
/// in counts. The sensors' own noise ([`SensorConfig::noise_sd_n`]) comes before it; an
/// unplugged sensor's input, pulled to AGND by the divider, reads only this.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdcConfig {
    /// Offset of every conversion, counts: what the ADC reads with its input at 0 V.
    pub offset_counts: f64,
    /// Gaussian noise of every conversion, counts (standard deviation; 0 = none).
    pub noise_sd_counts: f64,
}

impl AdcConfig {
    /// An ideal ADC: no offset, no noise of its own (the default: the campaigns' sensors'
    /// 0.02 N is all the noise their data have, as it always was).
    pub const IDEAL: AdcConfig = AdcConfig {
        offset_counts: 0.0,
        noise_sd_counts: 0.0,
    };

    /// A Raspberry Pi Pico's: 10-20 counts with the input grounded (15: its offset) and about a
    /// count of noise of its own (assumed from the RP2040 data sheet's ENOB of ~9 bits at the
    /// pin and measurements posted of Picos, not measured here).
    pub const RP2040: AdcConfig = AdcConfig {
        offset_counts: 15.0,
        noise_sd_counts: 1.0,
    };
}

impl Default for AdcConfig {
    fn default() -> Self {
        AdcConfig::IDEAL
    }
}

/// What a fault injection does to the plant (beyond its kind).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultConfig {
    /// The tension a snag puts on the T2 sensor (over-force injection), N. Must stay under the
    /// ADC's top rail (55.4 N with the nominal transfer), or the firmware sees a rail instead.
    pub snag_n: f64,
    /// How long the operator holds the button for an abort, ms.
    pub abort_press_ms: u32,
}

impl Default for FaultConfig {
    fn default() -> Self {
        FaultConfig {
            snag_n: 50.0,
            abort_press_ms: 200,
        }
    }
}

/// The whole rig's constants (shared by every cord on the capstan).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantConfig {
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: f64,
    /// The servo and its lever (one per cord).
    pub servo: ServoConfig,
    /// The cord (one per servo).
    pub cord: CordConfig,
    /// The drive.
    pub motor: MotorConfig,
    /// Both force sensors of every cord.
    pub sensor: SensorConfig,
    /// The ADC they are read through.
    pub adc: AdcConfig,
    /// Fault injection details.
    pub faults: FaultConfig,
    /// Longest integration step, µs (the plant advances lazily to each read in such steps).
    pub max_step_us: u32,
    /// With a time-dependent friction law (drift with time, contact heating), how often the
    /// tensions are re-solved, µs.
    pub refresh_us: u32,
    /// Scatter inside a run that no model fits (none by default).
    pub disturbances: Disturbances,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            capstan_diameter_mm: 12.7,
            servo: ServoConfig::default(),
            cord: CordConfig::default(),
            motor: MotorConfig::default(),
            sensor: SensorConfig::default(),
            adc: AdcConfig::IDEAL,
            faults: FaultConfig::default(),
            max_step_us: 1_000,
            refresh_us: 10_000,
            disturbances: Disturbances::QUIET,
        }
    }
}

/// One cord on the capstan: its wrap, its friction model and which repeat run it is in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordSetup {
    /// Wrap (contact) angle, deg.
    pub wrap_deg: f64,
    /// The shared friction model: its law transmits the tension, its sensor artefacts are
    /// applied by the force sensors.
    pub model: Model,
    /// Repeat run on this cord, from 1 (the law's wear term).
    pub run: u32,
    /// When the operator presses this cord's start button, µs after the plant was made
    /// (`None`: never, e.g. the button is pressed by a test through [`crate::Plant::press`]).
    pub press_at_us: Option<u64>,
    /// How long the start press lasts, µs.
    pub press_us: u64,
    /// Physics outside the effect catalogue on this cord (none by default).
    pub unmodelled: Unmodelled,
}

impl CordSetup {
    /// A cord at `wrap_deg` with `model`, run 1, pressed 10 ms after the start for 200 ms.
    pub fn new(wrap_deg: f64, model: Model) -> Self {
        CordSetup {
            wrap_deg,
            model,
            run: 1,
            press_at_us: Some(10_000),
            press_us: 200_000,
            unmodelled: Unmodelled::default(),
        }
    }
}

impl Default for CordSetup {
    /// The thesis's 360° with Euler-Eytelwein at mu = 0.115.
    fn default() -> Self {
        CordSetup::new(360.0, Model::euler_eytelwein(crate::THESIS_MU))
    }
}
