//! The report's headline: at most five sentences in plain words, generated from the verdicts.
//! What Euler-Eytelwein gets wrong, what the data establish, what is left, and the gain with
//! its interval.
//!
//! [`Facts`] is the adapter: everything the sentences need, read from the engine's analysis in
//! one place ([`Facts::of`]). When the verdict layer changes shape, only that function follows.
//! Every number of the headline is listed with the JSON pointer of its value in
//! `metrics.json` (`headline.numbers`), so that a test can check each against the file.

use crate::cells::fx;
use capstan_engine::analysis::Analysis;
use serde::Serialize;

/// A number quoted in the headline: its text and where `metrics.json` holds its value.
#[derive(Clone, Debug, Serialize)]
pub struct Number {
    /// As printed.
    pub text: String,
    /// JSON pointer into `metrics.json`.
    pub pointer: String,
    /// Decimals printed.
    pub decimals: usize,
}

/// The headline.
#[derive(Clone, Debug, Serialize)]
pub struct Headline {
    /// The sentences (at most five).
    pub sentences: Vec<String>,
    /// Every number quoted in them.
    pub numbers: Vec<Number>,
}

/// A named cause in plain words, with the parameter row that sizes it.
struct Cause {
    words: &'static str,
    row: Option<usize>,
}

/// What the headline says, read from the analysis (the adapter to the verdict layer).
struct Facts {
    mu_row: Option<usize>,
    baseline_rmse: f64,
    cord_pct: f64,
    causes: Vec<Cause>,
    left: Option<&'static str>,
    gain: (f64, f64, f64),
    better: (usize, usize),
}

/// Plain words for a cause (no abbreviation), with `{}` where its size goes.
fn cause_words(name: &str) -> &'static str {
    match name {
        "t2_offset" => "the T2 force sensor reads with a zero offset of {}",
        "t1_offset" => "the T1 reading carries an offset or a loss of {} on its path",
        "sensor_gain" => "the T2 force sensor's gain is {} times the T1 sensor's",
        "contact_heating" => "friction falls while the contact carries load (contact heating: mu falls by a factor exp(−h·load memory), h = {})",
        "pressure_friction" => "friction falls as the tension rises (Howell's power law, exponent {})",
        "bending_stiffness" => "the stiff cord lifts off the capstan at low tension (bending stiffness {})",
        "thermal_drift" => "friction drifts with time during a run ({})",
        "wear" => "friction changes from one run to the next ({})",
        "diameter_dependence" => "friction depends on the capstan diameter ({})",
        "speed_dependence" => "friction depends on the drive speed ({})",
        _ => "a catalogue effect ({})",
    }
}

/// Plain words for the pattern no cause explains.
fn left_words(pattern: Option<&str>) -> &'static str {
    match pattern {
        Some("step_direction") => "T2 differs between rising and falling tension",
        Some("t1_shape") => "the way T2 grows with T1 departs from every fitted model",
        Some("time") => "T2 drifts with time inside runs",
        Some("wrap") => "the way T2 grows with T1 changes with the wrap angle",
        Some("diameter") => "the way T2 grows with T1 changes with the capstan diameter",
        _ => "T2 departs from the model at particular steps",
    }
}

impl Facts {
    fn of(a: &Analysis, params: &[crate::parameters::Row]) -> Facts {
        let row = |key: &str| params.iter().position(|r| r.key == key);
        let causes = a
            .mechanisms
            .causes
            .iter()
            .map(|c| {
                let p = capstan_physics::EffectKind::from_name(c.name)
                    .and_then(capstan_engine::fit::Param::from_effect);
                Cause {
                    words: cause_words(c.name),
                    row: p.and_then(|p| row(&format!("extended.{}", p.name()))),
                }
            })
            .collect();
        let u = &a.mechanisms.unexplained;
        Facts {
            mu_row: row("baseline.mu"),
            baseline_rmse: a.models.first().map_or(f64::NAN, |m| m.rmse_t2_n),
            cord_pct: a.evidence.scatter.cord_pct,
            causes,
            left: u.flag.then(|| left_words(u.pattern)),
            gain: (a.gain.value, a.gain.ci95.lo, a.gain.ci95.hi),
            better: (
                a.held_out.iter().filter(|c| c.extended_better).count(),
                a.held_out.len(),
            ),
        }
    }
}

/// Collects the numbers as the sentences quote them.
struct Quote<'a> {
    numbers: Vec<Number>,
    params: &'a [crate::parameters::Row],
}

impl Quote<'_> {
    fn num(&mut self, v: f64, d: usize, pointer: String) -> String {
        let text = fx(v, d);
        self.numbers.push(Number {
            text: text.clone(),
            pointer,
            decimals: d,
        });
        text
    }

    /// A parameter row's value with its unit ("−0.82 N").
    fn param(&mut self, k: usize, d: usize) -> String {
        let r = &self.params[k];
        let t = self.num(r.value, d, format!("/parameters/{k}/value"));
        match r.unit {
            "1" => t,
            u => format!("{t} {u}"),
        }
    }
}

/// The headline of `a`.
pub fn headline(a: &Analysis) -> Headline {
    let params = crate::parameters::rows(a);
    let f = Facts::of(a, &params);
    let mut q = Quote {
        numbers: Vec::new(),
        params: &params,
    };
    let mut s = Vec::new();
    let mu = f.mu_row.map_or("–".into(), |k| q.param(k, 4));
    let rmse = q.num(f.baseline_rmse, 2, "/models/0/rmse_t2_n".into());
    let cord = q.num(f.cord_pct, 1, "/evidence/scatter/cord_pct".into());
    s.push(format!("Euler-Eytelwein's law, T2 = T1·exp(mu·wrap angle) with one friction coefficient mu = {mu}, misses the measured T2 by {rmse} N (root mean square), and mu itself varies by {cord} % from cord to cord."));
    if f.causes.is_empty() {
        s.push("The data establish no cause from the catalogue of known departures.".into());
    } else {
        let parts: Vec<String> = f
            .causes
            .iter()
            .map(|c| match c.row {
                Some(k) => c.words.replacen("{}", &q.param(k, 4), 1),
                None => c.words.replacen(" of {}", "", 1).replacen(" ({})", "", 1),
            })
            .collect();
        s.push(format!("The data establish that {}.", join_and(&parts)));
    }
    s.push(match f.left {
        Some(w) => format!("Left unexplained: {w}, and no cause in the catalogue accounts for it."),
        None => {
            "Nothing systematic is left beyond the scatter between cords, runs and readings.".into()
        }
    });
    let g = q.num(
        f.gain.0,
        2,
        "/gain/loco_rmse_ratio_extended_over_baseline/value".into(),
    );
    let lo = q.num(
        f.gain.1,
        2,
        "/gain/loco_rmse_ratio_extended_over_baseline/ci95/lo".into(),
    );
    let hi = q.num(
        f.gain.2,
        2,
        "/gain/loco_rmse_ratio_extended_over_baseline/ci95/hi".into(),
    );
    let better = q.num(f.better.0 as f64, 0, "/gain/cords_predicted_better".into());
    let cords = q.num(f.better.1 as f64, 0, "/gain/cords".into());
    let verdict = if f.gain.2 < 1.0 {
        "the gain on new cords is established"
    } else {
        "the interval includes 1, so a gain on new cords is not established"
    };
    s.push(format!("On a cord left out of the fit, the model with these causes has {g} times Euler-Eytelwein's error (95 % interval {lo} to {hi}), better on {better} of {cords} cords: {verdict}."));
    Headline {
        sentences: s,
        numbers: q.numbers,
    }
}

/// "a", "a and b", "a, b and c".
fn join_and(parts: &[String]) -> String {
    match parts {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}
