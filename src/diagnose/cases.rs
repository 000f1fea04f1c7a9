//! Generated test cases: one catalogue effect (or none) hidden at a random magnitude in a data
//! set made by the firmware-in-the-loop simulator (`host-sim`).
//!
//! The ground truth of a case is the [`Effect`] handed to [`CampaignConfig::effects`]. Each case
//! draws a design (wraps, diameters, drive voltages, runs, step order), the cord-to-cord scatter
//! of mu (1-3 %, run-to-run half of it) and the effect's magnitude in the ranges met in
//! practice. The design always lets the hidden effect show: a diameter effect gets two
//! diameters, a speed effect two or three voltages, a gain error a wide spread of wraps. For
//! drift, wear, diameter and speed the coefficient is chosen so that mu changes by 5-25 % over
//! the data set's span of time, runs, diameters or voltages.
//!
//! Used by the tests (`tests/diagnose_*.rs`) and the benchmark (`benches/diagnose.rs`).

use crate::data::{read_pairs, write_pairs_to, Dataset, Pair};
use capstan_friction::{Effect, EffectKind, Model};
use firmware::{Protocol, StepOrder};
use host_sim::campaign::{run_campaign, CampaignConfig, CampaignResult};
use host_sim::plant::rng::{derive_seed, Rng};

/// The shortened protocol of the tests: 4 s steps, windows from 1 s after a change to 0.5 s
/// before the next, still through the firmware's sampling and conditioning.
pub fn short_protocol() -> Protocol {
    Protocol {
        dwell_ms: 4_000,
        window_after_change_ms: 1_000,
        window_before_next_ms: 500,
        ..Protocol::default()
    }
}

/// One generated case, before it is simulated.
#[derive(Clone, Debug)]
pub struct Case {
    /// Case seed (also the campaign seed).
    pub seed: u64,
    /// The hidden effect (the ground truth).
    pub effect: Effect,
    /// mu change the effect makes across the data set's span (drift, wear, diameter, speed),
    /// as a fraction; 0 for the others.
    pub span_change: f64,
    /// Simulator configuration (effects, scatter, design).
    pub config: CampaignConfig,
    /// Optional columns removed from the CSV (e.g. `time_s`).
    pub drop_columns: Vec<&'static str>,
}

impl Case {
    /// A one-line description.
    pub fn describe(&self) -> String {
        let c = &self.config;
        format!(
            "seed {} {}={:.4} | wraps {:?} d {:?} V {:?} runs {} {:?} scatter {:.1}% mu {:.3}{}",
            self.seed,
            self.effect.kind,
            self.effect.value,
            c.wraps_deg,
            c.diameters_mm,
            c.drive_vs,
            c.runs,
            c.order,
            c.scatter_pct,
            c.model.law.mu,
            if self.drop_columns.is_empty() {
                String::new()
            } else {
                format!(" without {:?}", self.drop_columns)
            }
        )
    }

    /// Run the simulator and read its pairs back through the CSV schema, exactly as `capstan
    /// simulate` writes them to `pairs.csv`.
    pub fn generate(&self) -> Result<(Dataset, CampaignResult), String> {
        let r = run_campaign(&self.config).map_err(|e| e.to_string())?;
        let pairs: Vec<Pair> = crate::cli::simulate::to_pairs(&r.rows)
            .into_iter()
            .map(|mut p| {
                for c in &self.drop_columns {
                    match *c {
                        "capstan_diameter_mm" => p.capstan_diameter_mm = None,
                        "drive_v" => p.drive_v = None,
                        "run" => p.run = None,
                        "step" => p.step = None,
                        "time_s" => p.time_s = None,
                        _ => {}
                    }
                }
                p
            })
            .collect();
        let mut csv = Vec::new();
        write_pairs_to(&mut csv, &pairs).map_err(|e| e.to_string())?;
        let name = format!("case-{}-{}.csv", self.seed, self.effect.kind);
        let d = read_pairs(csv.as_slice(), &name).map_err(|e| e.to_string())?;
        Ok((d, r))
    }
}

fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.uniform()
}

fn sign(rng: &mut Rng) -> f64 {
    if rng.uniform() < 0.5 {
        -1.0
    } else {
        1.0
    }
}

/// `k` distinct values of `pool`, sorted.
fn subset(rng: &mut Rng, pool: &[f64], k: usize) -> Vec<f64> {
    let mut v = pool.to_vec();
    // Partial Fisher-Yates.
    for i in 0..k.min(v.len()) {
        let j = i + ((rng.uniform() * (v.len() - i) as f64) as usize).min(v.len() - i - 1);
        v.swap(i, j);
    }
    v.truncate(k);
    v.sort_by(f64::total_cmp);
    v
}

const WRAPS: [f64; 6] = [270.0, 360.0, 450.0, 540.0, 630.0, 720.0];
const DIAMETERS: [f64; 3] = [12.7, 19.05, 25.4];
const VOLTS: [f64; 4] = [6.0, 8.0, 10.0, 12.0];

/// Draw case `index` of effect `kind` from `master_seed`: design, scatter and magnitude.
pub fn draw_case(master_seed: u64, kind: EffectKind, index: u64) -> Case {
    let seed = derive_seed(master_seed, &[kind as u64, index]);
    let mut rng = Rng::new(seed);
    // Design. Small: 3-5 wraps, 1-2 diameters, 1-2 voltages, 3-8 runs. Large (a third of the
    // cases, and every case of an effect that varies between cords): 5-6 wraps × 2 diameters ×
    // 2-3 voltages, 3-5 runs. Either step order.
    let between_cords = matches!(
        kind,
        EffectKind::DiameterDependence | EffectKind::SpeedDependence | EffectKind::SensorGain
    );
    let large = between_cords || rng.uniform() < 0.3;
    let (mut wraps, mut diameters, volts, mut runs);
    if large {
        let k = 5 + usize::from(rng.uniform() < 0.5);
        wraps = subset(&mut rng, &WRAPS, k);
        diameters = subset(&mut rng, &DIAMETERS, 2);
        let k = 2 + usize::from(kind == EffectKind::SpeedDependence && rng.uniform() < 0.4);
        volts = subset(&mut rng, &VOLTS, k);
        runs = 3 + (rng.uniform() * 3.0) as u32 % 3;
    } else {
        let k = 3 + (rng.uniform() * 3.0) as usize % 3;
        wraps = subset(&mut rng, &WRAPS, k);
        let k = 1 + usize::from(rng.uniform() < 0.5);
        diameters = subset(&mut rng, &DIAMETERS, k);
        volts = if rng.uniform() < 0.3 {
            subset(&mut rng, &VOLTS, 2)
        } else if rng.uniform() < 0.6 {
            vec![10.0]
        } else {
            subset(&mut rng, &VOLTS, 1)
        };
        runs = 3 + (rng.uniform() * 6.0) as u32 % 6;
    }
    let order = if rng.uniform() < 0.5 {
        StepOrder::Monotone
    } else {
        StepOrder::UpDown
    };
    let scatter_pct = uniform(&mut rng, 1.0, 3.0);
    let mu = uniform(&mut rng, 0.10, 0.13);
    // What the effect needs to show against the scatter.
    if kind == EffectKind::SensorGain {
        // A gain error shows only across wraps (mu_apparent = mu + ln g / β): span them.
        wraps[0] = 270.0;
        *wraps.last_mut().expect("wraps") = 720.0;
    }
    if kind == EffectKind::Wear {
        // Wear is judged against the run-to-run scatter: at least 4 runs on at least 6 cords.
        runs = runs.max(4);
        if wraps.len() * diameters.len() * volts.len() < 6 {
            diameters = vec![12.7, 25.4];
        }
    }
    let protocol = short_protocol();
    // Time span of a run: window centres from ~step 1 to step N.
    let levels = 12.0;
    let dwell = protocol.dwell_ms as f64 / 1000.0;
    let time_span = levels * dwell;
    let change = uniform(&mut rng, 0.05, 0.25) * sign(&mut rng);
    let (value, span_change) = match kind {
        EffectKind::None => (0.0, 0.0),
        EffectKind::PressureFriction => (uniform(&mut rng, 0.7, 0.95), 0.0),
        EffectKind::BendingStiffness => (uniform(&mut rng, 2e-5, 1.5e-4), 0.0),
        EffectKind::T1Offset => (uniform(&mut rng, 0.2, 1.2), 0.0),
        EffectKind::T2Offset => (uniform(&mut rng, 0.2, 1.2) * sign(&mut rng), 0.0),
        EffectKind::SensorGain => (1.0 + uniform(&mut rng, 0.05, 0.15) * sign(&mut rng), 0.0),
        EffectKind::ThermalDrift => (change * 100.0 / time_span, change),
        EffectKind::Wear => (change / (runs as f64 - 1.0), change),
        EffectKind::DiameterDependence => {
            let span = diameters[diameters.len() - 1] - diameters[0];
            (change / span, change)
        }
        EffectKind::SpeedDependence => {
            let span = volts[volts.len() - 1] - volts[0];
            (change / span, change)
        }
    };
    let effect = if kind == EffectKind::None {
        Effect::NONE
    } else {
        Effect { kind, value }
    };
    let model = Model::euler_eytelwein(mu);
    let config = CampaignConfig {
        diameters_mm: diameters,
        wraps_deg: wraps,
        drive_vs: volts,
        runs,
        order,
        effects: if kind == EffectKind::None {
            Vec::new()
        } else {
            vec![effect]
        },
        model,
        scatter_pct,
        sensor_noise: true,
        seed,
        protocol,
        threads: 1,
        keep_raw: false,
        // The highest T2 reading (mu up to 0.13 and +25 %, or a +15 % gain, at 720°) can pass
        // the default 45 N over-force limit; the ADC's top rail is at 55.4 N.
        limits: firmware::safety::SafetyLimits {
            over_force_n: 54.0,
            ..firmware::safety::SafetyLimits::default()
        },
        ..CampaignConfig::default()
    };
    Case {
        seed,
        effect,
        span_change,
        config,
        drop_columns: Vec::new(),
    }
}
