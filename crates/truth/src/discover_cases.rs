//! Planted truths for `capstan discover` (docs/README-discover.md): data sets made end to end
//! by the firmware-in-the-loop simulator with the thesis rig's noise, on the thesis's design
//! (two capstans × five wraps, ten cords, six runs each), holding the thesis's catalogue pair
//! (contact heating and a T2 offset, at the thesis's sizes) plus, in most, physics outside the
//! catalogue that only the plant knows (`host_sim::plant::Unmodelled`):
//!
//! * **clean**: nothing at all; **catalogue**: the catalogue pair only;
//! * **expressible** kinds, which a library term can express: `t2_lowforce`,
//!   `t1_tare_diameter`, `t2_offset_wrap`, `settling`, `hysteresis` (on up-down runs);
//! * **inexpressible** kinds, which no single library term can: `regime_change` (a kink of mu
//!   in tension), `t2_nonlinearity` (an S-shaped T2 calibration), `t2_range_step` (a step of
//!   the T2 reading at 15 N).
//!
//! Each kind lists the variable sets a proposed term must depend on to have "the right
//! dependence" ([`Kind::right`]).

use crate::cases::{short_protocol, Case, Class};
use capstan_friction::{Effect, EffectKind, Model};
use firmware::StepOrder;
use host_sim::campaign::CampaignConfig;
use host_sim::noise::{thesis, NoiseProfile};
use host_sim::plant::rng::{derive_seed, Rng};
use host_sim::plant::Disturbances;

/// What a set hides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// Nothing, or the catalogue only: a term proposed is a false discovery.
    Null,
    /// Physics a library term can express.
    Expressible,
    /// Physics no single library term can express.
    Inexpressible,
}

/// One kind of planted truth.
#[derive(Clone, Copy, Debug)]
pub struct Kind {
    /// Name (an `Unmodelled` name, or `clean` / `catalogue`).
    pub name: &'static str,
    /// Its group.
    pub group: Group,
    /// Its size range (absolute value) and whether its sign is drawn.
    pub size: (f64, f64, bool),
    /// The variable sets (a term's `depends_on`, as names) that count as the right dependence.
    pub right: &'static [&'static [&'static str]],
    /// Up-down runs (the step direction must vary).
    pub updown: bool,
    /// An expressible kind that is a near-twin, at this design and noise, of what the model
    /// already has (a catalogue effect, or every run's own mu and zero error): what it is a twin
    /// of. The validation reports these apart ("indistinguishable at this design"): the
    /// oracle (the best term of the right dependence, given the catalogue as the engine
    /// selected it) does not pass the search's bar in ~90 % of the calibration sets at any
    /// physically plausible size (docs/README-discover.md).
    pub twin: Option<&'static str>,
}

/// Every kind, in the order of the tables.
pub const KINDS: [Kind; 10] = [
    Kind {
        name: "clean",
        group: Group::Null,
        size: (0.0, 0.0, false),
        right: &[],
        updown: false,
        twin: None,
    },
    Kind {
        name: "catalogue",
        group: Group::Null,
        size: (0.0, 0.0, false),
        right: &[],
        updown: false,
        twin: None,
    },
    Kind {
        name: "t2_lowforce",
        group: Group::Expressible,
        size: (0.5, 1.0, true),
        right: &[&["t2"]],
        updown: false,
        twin: Some(
            "the catalogue's T2 offset (above a few newtons the error is a constant; within runs their columns share up to 99 %)",
        ),
    },
    Kind {
        name: "t1_tare_diameter",
        group: Group::Expressible,
        // q 1.2-2.4 N: a T1 tare ±q/3 = ±0.4-0.8 N at each capstan, 0.8-1.6 N apart (the
        // oracle's power on seed 26: 6/12 at 0.4-0.8 N, 9/12 at ×2, 12/12 at ×3).
        size: (1.2, 2.4, true),
        right: &[&["t1", "diameter"], &["diameter"]],
        updown: false,
        twin: None,
    },
    Kind {
        name: "t2_offset_wrap",
        group: Group::Expressible,
        size: (0.4, 0.8, true),
        right: &[&["wrap"]],
        updown: false,
        twin: Some(
            "every run's own mu and its slow wander (a run sees one wrap; what its mu leaves is a tilt along a monotone run, which the wander makes too)",
        ),
    },
    Kind {
        name: "settling",
        group: Group::Expressible,
        size: (0.08, 0.15, true),
        right: &[&["time", "step"]],
        updown: false,
        twin: Some(
            "the catalogue's thermal drift (a fall of mu with time in the run; within runs their columns share 86-96 %)",
        ),
    },
    Kind {
        name: "hysteresis",
        group: Group::Expressible,
        size: (0.08, 0.2, false),
        right: &[&["step_direction"]],
        updown: true,
        twin: None,
    },
    Kind {
        name: "regime_change",
        group: Group::Inexpressible,
        size: (0.15, 0.25, true),
        right: &[],
        updown: false,
        twin: None,
    },
    Kind {
        name: "t2_nonlinearity",
        group: Group::Inexpressible,
        size: (0.6, 1.2, true),
        right: &[],
        updown: false,
        twin: None,
    },
    Kind {
        name: "t2_range_step",
        group: Group::Inexpressible,
        size: (0.4, 0.8, true),
        right: &[],
        updown: false,
        twin: None,
    },
];

/// The thesis's catalogue pair: contact heating (ln mu per newton of load) and the T2 offset.
pub const THESIS_HEATING: f64 = 0.0067;
/// The thesis's T2 offset, N.
pub const THESIS_T2_OFFSET_N: f64 = -0.9;

/// A planted set.
#[derive(Clone, Debug)]
pub struct DiscoverCase {
    /// The simulator's case.
    pub case: Case,
    /// Its kind.
    pub kind: Kind,
    /// The planted size (0 for clean and catalogue).
    pub size: f64,
}

/// The thesis-like campaign (catalogue pair in unless `clean`).
fn design(rng: &mut Rng, clean: bool, updown: bool) -> CampaignConfig {
    let mut cfg = CampaignConfig {
        diameters_mm: vec![12.7, 25.4],
        wraps_deg: vec![270.0, 360.0, 450.0, 630.0, 720.0],
        drive_vs: vec![10.0],
        runs: 6,
        order: if updown {
            StepOrder::UpDown
        } else {
            StepOrder::Monotone
        },
        model: Model::euler_eytelwein(0.143 * (1.0 + 0.05 * (rng.uniform() - 0.5))),
        protocol: short_protocol(),
        threads: 1,
        keep_raw: false,
        ..CampaignConfig::default()
    };
    crate::cases::rail_rig(&mut cfg);
    NoiseProfile::Thesis.apply(&mut cfg);
    cfg.scatter_pct = thesis::CORD_SCATTER_PCT;
    cfg.run_scatter_pct = Some(thesis::RUN_SCATTER_PCT);
    cfg.plant.disturbances = Disturbances {
        mu_wander_sd: thesis::MU_WANDER_SD,
        mu_wander_tau_s: thesis::MU_WANDER_TAU_S * cfg.protocol.dwell_ms as f64 / 10_000.0,
        zero_error_sd_n: thesis::ZERO_ERROR_SD_N,
    };
    if !clean {
        cfg.effects = vec![
            Effect {
                kind: EffectKind::T2Offset,
                value: THESIS_T2_OFFSET_N,
            },
            Effect {
                kind: EffectKind::ContactHeating,
                value: THESIS_HEATING,
            },
        ];
    }
    cfg
}

/// Set `index` of `kind` from `master_seed`.
pub fn draw(master_seed: u64, kind: &Kind, index: u64) -> DiscoverCase {
    let k = KINDS.iter().position(|x| x.name == kind.name).unwrap_or(0) as u64;
    let seed = derive_seed(master_seed, &[0x26, k, index]);
    let mut rng = Rng::new(seed);
    let mut cfg = design(&mut rng, kind.name == "clean", kind.updown);
    let (lo, hi, signed) = kind.size;
    let mut size = lo + (hi - lo) * rng.uniform();
    if signed && rng.uniform() < 0.5 {
        size = -size;
    }
    let outside = match kind.group {
        Group::Null => {
            size = 0.0;
            None
        }
        _ => {
            cfg.unmodelled.set(kind.name, size);
            Some((kind.name, size))
        }
    };
    cfg.seed = seed;
    let effects = cfg.effects.clone();
    DiscoverCase {
        case: Case {
            seed,
            class: if outside.is_some() {
                Class::Outside
            } else {
                Class::Clean
            },
            effects,
            outside,
            config: cfg,
            drop_columns: Vec::new(),
        },
        kind: *kind,
        size,
    }
}

/// `per_kind` sets of every kind from `master_seed`, kind by kind.
pub fn draw_all(master_seed: u64, per_kind: usize) -> Vec<DiscoverCase> {
    KINDS
        .iter()
        .flat_map(|k| (0..per_kind as u64).map(move |i| draw(master_seed, k, i)))
        .collect()
}

/// The same sets as [`draw_all`] (the same seeds, sizes and cords) with every run's levels in
/// up-down order: level is nearly uncorrelated with time in the run.
pub fn draw_all_updown(master_seed: u64, per_kind: usize) -> Vec<DiscoverCase> {
    let mut cases = draw_all(master_seed, per_kind);
    for c in &mut cases {
        c.case.config.order = StepOrder::UpDown;
    }
    cases
}
