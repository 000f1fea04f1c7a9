//! Planted truths for `capstan discover` (docs/README-discover.md): data sets made end to end
//! by the firmware-in-the-loop simulator with the thesis rig's noise, holding the thesis's
//! catalogue pair (contact heating and a T2 offset, at the thesis's sizes) plus, in most,
//! physics outside the catalogue that only the plant knows (`capstan_sim::plant::Unmodelled`):
//!
//! * **clean**: nothing at all; **catalogue**: the catalogue pair only;
//! * **expressible** kinds, which a library term can express: the ones the design can tell
//!   apart (`hysteresis` on up-down runs, `t2_quadratic`, `mu_bump`, `t1_tare_diameter`) and
//!   the near-twins of what the model already has (`t2_lowforce`, `t2_offset_wrap`,
//!   `settling`: [`Kind::twin`]);
//! * **inexpressible** kinds, which no single library term can: `regime_change` (a kink of mu
//!   in tension), `t2_nonlinearity` (an S-shaped T2 calibration), `t2_range_step` (a step of
//!   the T2 reading at 15 N);
//! * **mixed**: one more catalogue effect ([`MIXED_EFFECTS`]) beside one of the
//!   distinguishable kinds ([`MIXED_OUTSIDE`]): the effect must be named and the term found.
//!
//! Two designs ([`Variety`]): the thesis's own (two capstans × five wraps, six runs, monotone
//! steps, a time column) and the **varied** one the issue asks for (monotone or up-down steps,
//! with or without a time column, one or two capstans, three to six runs; five wraps always).
//!
//! Each kind lists the variable sets a proposed term must depend on to have "the right
//! dependence" ([`Kind::right`]).

use crate::cases::{short_protocol, value, Case, Class};
use capstan_physics::{Effect, EffectKind, Model};
use capstan_rig::StepOrder;
use capstan_sim::campaign::CampaignConfig;
use capstan_sim::noise::{thesis, NoiseProfile};
use capstan_sim::plant::rng::{derive_seed, Rng};
use capstan_sim::plant::Disturbances;

/// What a set hides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// Nothing, or the catalogue only: a term proposed is a false discovery.
    Null,
    /// Physics a library term can express.
    Expressible,
    /// Physics no single library term can express: a term proposed is a false discovery.
    Inexpressible,
    /// A catalogue effect beyond the thesis's pair and a distinguishable expressible kind.
    Mixed,
}

/// One kind of planted truth.
#[derive(Clone, Copy, Debug)]
pub struct Kind {
    /// Name (an `Unmodelled` name, or `clean` / `catalogue` / `mixed`).
    pub name: &'static str,
    /// Its group.
    pub group: Group,
    /// Its size range (absolute value) and whether its sign is drawn.
    pub size: (f64, f64, bool),
    /// The variable sets (a term's `depends_on`, as names) that count as the right dependence.
    pub right: &'static [&'static [&'static str]],
    /// Up-down runs (the step direction must vary).
    pub updown: bool,
    /// Two capstan diameters (its dependence is on the diameter).
    pub diameters: bool,
    /// An expressible kind that is a near-twin, at this design and noise, of what the model
    /// already has (a catalogue effect, or every run's own mu and zero error): what it is a twin
    /// of. The validation reports these apart ("indistinguishable at this design"): the
    /// oracle (the best term of the right dependence, given the catalogue as the engine
    /// selected it) does not pass the search's bar in ~90 % of the calibration sets at any
    /// physically plausible size (docs/README-discover.md).
    pub twin: Option<&'static str>,
}

const fn kind(name: &'static str, group: Group, size: (f64, f64, bool)) -> Kind {
    Kind {
        name,
        group,
        size,
        right: &[],
        updown: false,
        diameters: false,
        twin: None,
    }
}

/// Every kind, in the order of the tables (the first ten keep their seeds of s32-s35).
pub const KINDS: [Kind; 14] = [
    kind("clean", Group::Null, (0.0, 0.0, false)),
    kind("catalogue", Group::Null, (0.0, 0.0, false)),
    Kind {
        right: &[&["t2"]],
        twin: Some(
            "the catalogue's T2 offset (above a few newtons the error is a constant; within runs their columns share up to 99 %)",
        ),
        ..kind("t2_lowforce", Group::Expressible, (0.5, 1.0, true))
    },
    Kind {
        // q 1.2-2.4 N: a T1 tare ±q/3 = ±0.4-0.8 N at each capstan, 0.8-1.6 N apart (the
        // oracle's power on seed 26: 6/12 at 0.4-0.8 N, 9/12 at ×2, 12/12 at ×3).
        right: &[&["t1", "diameter"], &["diameter"]],
        diameters: true,
        ..kind("t1_tare_diameter", Group::Expressible, (1.2, 2.4, true))
    },
    Kind {
        right: &[&["wrap"]],
        twin: Some(
            "every run's own mu and its slow wander (a run sees one wrap; what its mu leaves is a tilt along a monotone run, which the wander makes too)",
        ),
        ..kind("t2_offset_wrap", Group::Expressible, (0.4, 0.8, true))
    },
    Kind {
        right: &[&["time", "step"]],
        twin: Some(
            "the catalogue's thermal drift (a fall of mu with time in the run; within runs their columns share 86-96 %)",
        ),
        ..kind("settling", Group::Expressible, (0.08, 0.15, true))
    },
    Kind {
        right: &[&["step_direction"]],
        updown: true,
        ..kind("hysteresis", Group::Expressible, (0.08, 0.2, false))
    },
    kind("regime_change", Group::Inexpressible, (0.15, 0.25, true)),
    kind("t2_nonlinearity", Group::Inexpressible, (0.6, 1.2, true)),
    kind("t2_range_step", Group::Inexpressible, (0.4, 0.8, true)),
    Kind {
        // The T2 reading's error at 20 N, N (a bowed load cell: 1-2 % of the reading there).
        right: &[&["t2"]],
        twin: Some(
            "the catalogue's contact heating (a fall of mu with the load bends T2 against T1 the same way, most at the largest wraps; a cell bowed upwards cancels it and the engine leaves heating out)",
        ),
        ..kind("t2_quadratic", Group::Expressible, (0.2, 0.4, true))
    },
    Kind {
        // mu 16-30 % higher or lower over a band of T1 around 6 N (SD 0.5 in ln T1: 3.6-10 N).
        right: &[&["t1"], &["t1", "t2"]],
        ..kind("mu_bump", Group::Expressible, (0.16, 0.3, true))
    },
    kind("mixed", Group::Mixed, (0.0, 0.0, false)),
    Kind {
        // The T1 reading's error at 20 N, N (a bowed load cell: 1-2 % of the reading there).
        right: &[&["t1"]],
        twin: Some(
            "the catalogue's contact heating and T1 offset (the error, amplified by e^(mu β), bends T2 against T1 as a fall of mu with the load does)",
        ),
        ..kind("t1_quadratic", Group::Expressible, (0.2, 0.4, true))
    },
];

/// The outside kinds of the mixed sets: the distinguishable expressible ones.
pub const MIXED_OUTSIDE: [&str; 3] = ["hysteresis", "mu_bump", "t1_tare_diameter"];

/// The catalogue effects the mixed sets add to the thesis's pair (at a size that matters, as
/// the diagnose cases draw it).
pub const MIXED_EFFECTS: [EffectKind; 4] = [
    EffectKind::T1Offset,
    EffectKind::ThermalDrift,
    EffectKind::Wear,
    EffectKind::PressureFriction,
];

/// The thesis's catalogue pair: contact heating (ln mu per newton of load) and the T2 offset.
pub const THESIS_HEATING: f64 = 0.0067;
/// The thesis's T2 offset, N.
pub const THESIS_T2_OFFSET_N: f64 = -0.9;

/// Which designs the sets are drawn on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variety {
    /// The thesis's design: two capstans × five wraps, six runs, monotone steps (up-down
    /// for the kinds that need them), a time column. The sets of s32-s35, draw for draw.
    Thesis,
    /// The thesis's design with every run up-down (s35's comparison).
    ThesisUpDown,
    /// Monotone or up-down steps (half each, up-down where the kind needs it), a time column
    /// in two sets of three, one or two capstans (two where the kind needs them), three to
    /// six runs; five wraps always.
    Varied,
}

/// The design of one set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Up-down steps.
    pub updown: bool,
    /// The data keep their time column.
    pub timed: bool,
    /// Capstan diameters.
    pub diameters: usize,
    /// Runs per cord.
    pub runs: u32,
}

/// A planted set.
#[derive(Clone, Debug)]
pub struct DiscoverCase {
    /// The simulator's case.
    pub case: Case,
    /// Its kind.
    pub kind: Kind,
    /// The outside physics planted (the kind itself, or a mixed set's draw), if any.
    pub planted: Option<Kind>,
    /// The planted size (0 for clean and catalogue).
    pub size: f64,
    /// A mixed set's catalogue effect beyond the thesis's pair.
    pub extra: Option<Effect>,
    /// Its design.
    pub layout: Layout,
}

impl DiscoverCase {
    /// The variable sets that count as the right dependence (none for null and inexpressible
    /// sets).
    pub fn right(&self) -> &'static [&'static [&'static str]] {
        self.planted.map_or(&[], |k| k.right)
    }

    /// Multiply the planted size by `factor` (the power curve).
    pub fn scale(&mut self, factor: f64) {
        if let Some(k) = self.planted {
            self.size *= factor;
            self.case.config.unmodelled.set(k.name, self.size);
            self.case.outside = Some((k.name, self.size));
        }
    }

    /// One line: kind, planted physics, design.
    pub fn label(&self) -> String {
        let l = self.layout;
        format!(
            "{}{}{} | {} {}, {} capstan{}, {} runs",
            self.kind.name,
            self.planted
                .filter(|_| self.kind.group == Group::Mixed)
                .map_or(String::new(), |k| format!(" ({} {:+.3}", k.name, self.size)),
            self.extra.map_or(String::new(), |e| format!(
                " + {} {:.3})",
                e.kind.name(),
                e.value
            )),
            if l.updown { "up-down" } else { "monotone" },
            if l.timed { "timed" } else { "no time column" },
            l.diameters,
            if l.diameters == 1 { "" } else { "s" },
            l.runs
        )
    }
}

/// The campaign of `layout` (catalogue pair in unless `clean`).
fn design(rng: &mut Rng, clean: bool, layout: Layout) -> CampaignConfig {
    let mut cfg = CampaignConfig {
        diameters_mm: vec![12.7, 25.4],
        wraps_deg: vec![270.0, 360.0, 450.0, 630.0, 720.0],
        drive_vs: vec![10.0],
        runs: layout.runs,
        order: if layout.updown {
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

/// A varied set's design: what `planted` needs, the rest drawn.
fn varied_layout(rng: &mut Rng, planted: Option<&Kind>) -> Layout {
    let updown = planted.is_some_and(|k| k.updown) || rng.uniform() < 0.5;
    let timed = rng.uniform() < 2.0 / 3.0;
    let diameters = if planted.is_some_and(|k| k.diameters) || rng.uniform() < 0.5 {
        2
    } else {
        1
    };
    let runs = 3 + (rng.uniform() * 4.0) as u32 % 4;
    Layout {
        updown,
        timed,
        diameters,
        runs,
    }
}

/// The thesis's layout (up-down where `planted` needs it, or everywhere).
fn thesis_layout(planted: Option<&Kind>, all_updown: bool) -> Layout {
    Layout {
        updown: all_updown || planted.is_some_and(|k| k.updown),
        timed: true,
        diameters: 2,
        runs: 6,
    }
}

/// The kind of `name`.
pub fn kind_of(name: &str) -> Option<&'static Kind> {
    KINDS.iter().find(|k| k.name == name)
}

/// Set `index` of `kind` from `master_seed`, on designs of `variety`.
pub fn draw(master_seed: u64, kind: &Kind, index: u64, variety: Variety) -> DiscoverCase {
    let k = KINDS.iter().position(|x| x.name == kind.name).unwrap_or(0) as u64;
    let seed = derive_seed(master_seed, &[0x26, k, index]);
    let mut rng = Rng::new(seed);
    let planted: Option<Kind> = match kind.group {
        Group::Null => None,
        Group::Mixed => kind_of(MIXED_OUTSIDE[index as usize % MIXED_OUTSIDE.len()]).copied(),
        _ => Some(*kind),
    };
    // The thesis designs draw as s32-s35 did (mu, then the size); the varied one draws its
    // layout after them.
    let mut cfg = design(&mut rng, kind.name == "clean", thesis_layout(None, false));
    let (lo, hi, signed) = planted.map_or((0.0, 0.0, false), |p| p.size);
    let mut size = lo + (hi - lo) * rng.uniform();
    if signed && rng.uniform() < 0.5 {
        size = -size;
    }
    let layout = match variety {
        Variety::Thesis => thesis_layout(planted.as_ref(), false),
        Variety::ThesisUpDown => thesis_layout(planted.as_ref(), true),
        Variety::Varied => varied_layout(&mut rng, planted.as_ref()),
    };
    apply_layout(&mut cfg, &mut rng, layout);
    let extra = (kind.group == Group::Mixed).then(|| {
        // Every outside kind meets every effect once in 12 sets.
        let j = (index as usize / MIXED_OUTSIDE.len()) % MIXED_EFFECTS.len();
        let kind = MIXED_EFFECTS[j];
        Effect {
            kind,
            value: value(&mut rng, kind, false, &cfg),
        }
    });
    if let Some(e) = extra {
        cfg.effects.push(e);
        cfg.effects.sort_by_key(|e| e.kind);
    }
    if let Some(p) = planted {
        cfg.unmodelled.set(p.name, size);
    } else {
        size = 0.0;
    }
    cfg.seed = seed;
    let effects = cfg.effects.clone();
    // A set without its time column (a drift needs it: its mixed sets keep it).
    let needs_time = extra.is_some_and(|e| e.kind.required_column() == Some("time_s"));
    let drop_columns = if layout.timed || needs_time {
        Vec::new()
    } else {
        vec!["time_s"]
    };
    DiscoverCase {
        case: Case {
            seed,
            class: if planted.is_some() {
                Class::Outside
            } else {
                Class::Clean
            },
            effects,
            outside: planted.map(|p| (p.name, size)),
            config: cfg,
            drop_columns,
        },
        kind: *kind,
        planted,
        size,
        extra,
        layout: Layout {
            timed: layout.timed || needs_time,
            ..layout
        },
    }
}

/// `layout` on `cfg`: the step order, the runs, one capstan (drawn) or two.
fn apply_layout(cfg: &mut CampaignConfig, rng: &mut Rng, layout: Layout) {
    cfg.order = if layout.updown {
        StepOrder::UpDown
    } else {
        StepOrder::Monotone
    };
    cfg.runs = layout.runs;
    if layout.diameters == 1 {
        let d = if rng.uniform() < 0.5 { 12.7 } else { 25.4 };
        cfg.diameters_mm = vec![d];
    }
}

/// `per_kind` sets of every kind from `master_seed`, kind by kind.
pub fn draw_all(master_seed: u64, per_kind: usize, variety: Variety) -> Vec<DiscoverCase> {
    KINDS
        .iter()
        .flat_map(|k| (0..per_kind as u64).map(move |i| draw(master_seed, k, i, variety)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thesis_designs_keep_their_sets_and_the_varied_one_spans_the_variety() {
        let hyst = kind_of("hysteresis").unwrap();
        let c = draw(26, hyst, 3, Variety::Thesis);
        assert_eq!(c.layout, thesis_layout(Some(hyst), false));
        assert_eq!(c.case.config.runs, 6);
        assert_eq!(c.case.config.diameters_mm.len(), 2);
        assert!(c.size >= 0.08 && c.size <= 0.2);
        let mut seen = (false, false, false, false, u32::MAX, 0);
        for k in &KINDS {
            for i in 0..12 {
                let c = draw(26, k, i, Variety::Varied);
                let l = c.layout;
                assert!((3..=6).contains(&l.runs) && l.runs == c.case.config.runs);
                assert_eq!(l.diameters, c.case.config.diameters_mm.len());
                assert_eq!(l.timed, c.case.drop_columns.is_empty());
                if let Some(p) = c.planted {
                    assert!(!p.updown || l.updown, "{}", p.name);
                    assert!(!p.diameters || l.diameters == 2, "{}", p.name);
                    assert!(c.size.abs() >= p.size.0 && c.size.abs() <= p.size.1);
                }
                seen.0 |= l.updown;
                seen.1 |= !l.updown;
                seen.2 |= !l.timed;
                seen.3 |= l.diameters == 1;
                seen.4 = seen.4.min(l.runs);
                seen.5 = seen.5.max(l.runs);
            }
        }
        assert!(seen.0 && seen.1 && seen.2 && seen.3 && seen.4 == 3 && seen.5 == 6);
    }

    #[test]
    fn a_mixed_set_holds_a_third_catalogue_effect_and_a_distinguishable_kind() {
        let mixed = kind_of("mixed").unwrap();
        for i in 0..8 {
            let c = draw(26, mixed, i, Variety::Varied);
            let p = c.planted.expect("planted");
            assert!(MIXED_OUTSIDE.contains(&p.name) && p.twin.is_none());
            let e = c.extra.expect("extra");
            assert_eq!(c.case.effects.len(), 3);
            assert!(c
                .case
                .effects
                .iter()
                .any(|x| x.kind == e.kind && x.value == e.value));
            assert!(!c.right().is_empty());
        }
    }
}
