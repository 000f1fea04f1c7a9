//! The report's headline: at most five sentences in plain words, generated from the verdicts.
//! What Euler-Eytelwein gets wrong, what the data establish, what is left, and the gain with
//! its interval.
//!
//! [`Facts`] is the adapter: everything the sentences need, read from the engine's analysis in
//! one place ([`Facts::of`]). When the verdict layer changes shape, only that function follows.
//! Every number of the headline is listed with the JSON pointer of its value in
//! `metrics.json` (`headline.numbers`), so that a test can check each against the file.

use crate::cells::{fx, se_decimals};
use capstan_engine::analysis::Analysis;
use capstan_engine::evidence::adequacy;
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
    /// The value at which the cause is absent (0 for an offset or heating).
    neutral: f64,
}

/// What the headline says, read from the analysis (the adapter to the verdict layer).
struct Facts<'a> {
    mu_row: Option<usize>,
    baseline_rmse: f64,
    cord_pct: f64,
    causes: Vec<Cause>,
    left: Option<&'static str>,
    scatter: Vec<&'static str>,
    /// The cords' summaries were tested against wrap and diameter.
    orders_tested: bool,
    /// Too few replicate runs to tell whether anything is left (the verdict layer's test).
    inconclusive: bool,
    gain: &'a capstan_engine::analysis::gain::Gain,
    better: (usize, usize),
}

/// Plain words for a cause (no abbreviation), with `{}` where its size goes. Each says what the
/// data identify, not more: an offset on T2 is additive whatever causes it, and heating's h is
/// sized at the catalogue's assumed load memory, which window means cannot resolve.
fn cause_words(name: &str) -> &'static str {
    match name {
        "t2_offset" => "T2 needs an additive offset of {}{ci} (a zero error of the T2 sensor or a constant force lost on the load side: these data cannot tell which)",
        "contact_heating" => "mu falls with the friction load T2 − T1 the contact carries (contact heating: at a steady load by a factor exp(−k·(T2 − T1)), k = {}{ci}; the data fix only k = h·τ, not the heating rate h and the contact's memory time τ apart, and cannot tell heating from a friction law that depends on the load T2 − T1 itself)",
        "t1_offset" => "the T1 reading carries an offset or a loss of {}{ci} on its path",
        "sensor_gain" => "the T2 force sensor's gain is {} times the T1 sensor's",
        "pressure_friction" => {
            "friction falls as the tension rises (Howell's power law, exponent {})"
        }
        "bending_stiffness" => {
            "the stiff cord lifts off the capstan at low tension (bending stiffness {})"
        }
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
        Some("wrap_between") => "something that changes with the wrap angle from cord to cord",
        Some("step_direction") => "T2 differs between rising and falling tension",
        Some("t1_shape") => "the way T2 grows with T1 departs from every fitted model",
        Some("time") => "T2 drifts with time inside runs",
        Some("wrap") => "the way T2 grows with T1 changes with the wrap angle",
        Some("diameter") => "the way T2 grows with T1 changes with the capstan diameter",
        _ => "T2 departs from the model at particular steps",
    }
}

impl<'a> Facts<'a> {
    fn of(a: &'a Analysis, params: &[crate::parameters::Row]) -> Facts<'a> {
        let row = |key: &str| params.iter().position(|r| r.key == key);
        let causes = a
            .mechanisms
            .causes
            .iter()
            .map(|c| {
                let kind = capstan_physics::EffectKind::from_name(c.name);
                let p = kind.and_then(capstan_engine::fit::Param::from_effect);
                Cause {
                    neutral: kind.map_or(0.0, |k| k.neutral_value()),
                    words: cause_words(c.name),
                    row: p.and_then(|p| {
                        let (name, _) = crate::parameters::identified(p.name());
                        row(&format!("extended.{name}"))
                    }),
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
            scatter: a.evidence.adequacy.left_between_cords.clone(),
            orders_tested: !a.evidence.adequacy.cords.patterns.is_empty(),
            inconclusive: capstan_engine::verdict::words::inconclusive(&a.evidence.adequacy),
            gain: &a.gain,
            better: (a.gain.cords_better, a.gain.cords),
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

    /// A parameter row's 95 % interval as the headline words it (", 95 % interval 0.0059 to
    /// 0.0107 by the cord jackknife"), and where it reaches `neutral` (the cause absent) that
    /// over the cords its size is not established; nothing when the row has no interval.
    fn interval(&mut self, k: usize, d: usize, neutral: f64) -> String {
        let r = &self.params[k];
        match (r.ci95_lo, r.ci95_hi, r.key.starts_with("extended.")) {
            (Some(lo), Some(hi), true) => {
                let reaches = lo <= neutral && neutral <= hi;
                let lo = self.num(lo, d, format!("/parameters/{k}/ci95_lo"));
                let hi = self.num(hi, d, format!("/parameters/{k}/ci95_hi"));
                match reaches {
                    true => format!(", 95 % interval {lo} to {hi} by the cord jackknife, which includes {neutral}: with the cords as the units it is not established"),
                    false => format!(", 95 % interval {lo} to {hi} by the cord jackknife"),
                }
            }
            _ => String::new(),
        }
    }

    /// The 95 % interval of the parameter row `key` in percent ("95 % interval 3.3 to 9.7 %; "),
    /// or nothing when the row or its interval is missing.
    fn spread_interval(&mut self, key: &str, d: usize) -> String {
        let Some(k) = self.params.iter().position(|r| r.key == key) else {
            return String::new();
        };
        match (self.params[k].ci95_lo, self.params[k].ci95_hi) {
            (Some(lo), Some(hi)) => {
                let lo = self.num(lo, d, format!("/parameters/{k}/ci95_lo"));
                let hi = self.num(hi, d, format!("/parameters/{k}/ci95_hi"));
                format!("95 % interval {lo} to {hi} %; ")
            }
            _ => String::new(),
        }
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
    let at_se = |k: usize| se_decimals(params[k].value, params[k].se);
    let mu = f.mu_row.map_or("–".into(), |k| q.param(k, at_se(k)));
    let rmse = q.num(f.baseline_rmse, 2, "/models/0/rmse_t2_n".into());
    let spread = if f.cord_pct.is_finite() {
        let cord = q.num(f.cord_pct, 1, "/evidence/scatter/cord_pct".into());
        let ci = q.spread_interval("scatter.cord_pct", 1);
        format!("mu still differs from cord to cord with a standard deviation of {cord} % ({ci}the evidence engine's estimate, every run its own mu)")
    } else {
        "how much mu differs from cord to cord is not estimable on these data (it needs two cords or more)".into()
    };
    s.push(format!("Euler-Eytelwein's law, T2 = T1·exp(mu·wrap angle) with one friction coefficient mu = {mu}, misses the measured T2 by {rmse} N (root mean square); with the causes below, {spread}."));
    let parts: Vec<String> = f
        .causes
        .iter()
        .map(|c| match c.row {
            Some(k) => {
                let d = at_se(k);
                let w = c.words.replacen("{}", &q.param(k, d), 1);
                match w.contains("{ci}") {
                    true => w.replacen("{ci}", &q.interval(k, d, c.neutral), 1),
                    false => w,
                }
            }
            None => (c.words.replacen("{ci}", "", 1))
                .replacen(" of {}", "", 1)
                .replacen(" ({})", "", 1)
                .replacen(", k = {}", "", 1),
        })
        .collect();
    // The verdict layer's stance (`verdict::words`): causes are established only when nothing
    // is left unexplained; otherwise they improve the fit but are not a diagnosis.
    match (f.left, parts.is_empty()) {
        (None, true) => {
            s.push("The data establish no cause from the catalogue of known departures.".into())
        }
        (None, false) => s.push(format!("The data establish that {}.", join_and(&parts))),
        (Some(w), true) => s.push(format!(
            "Left unexplained: {w}; no cause in the catalogue is supported on its own."
        )),
        (Some(w), false) => s.push(format!(
            "Left unexplained: {w}. The catalogue effects that improve the fit — {} — do not account for it, so they are not a diagnosis.",
            join_and(&parts)
        )),
    }
    let low = low_tension_sentence(a, &mut q);
    let above = low.is_some();
    s.extend(low);
    if f.left.is_none() {
        let left = if f.scatter.is_empty() && f.inconclusive {
            "These replicate runs are too few to tell whether anything systematic is left.".into()
        } else if f.scatter.is_empty() {
            "Nothing systematic is left beyond the scatter between cords, runs and readings.".into()
        } else {
            let what: Vec<String> = (f.scatter.iter())
                .map(|p| adequacy::scatter_words(p).to_string())
                .collect();
            let order = if f.orders_tested {
                format!("{} (the cords as units)", adequacy::NO_ORDER)
            } else {
                String::new()
            };
            format!("{}{order}.", adequacy::scatter_head(&what))
        };
        // After a sentence on the lowest tensions, what is left is said of the rest.
        s.push(match left.strip_prefix("What is left") {
            Some(rest) if above => format!("Above them, what is left{rest}"),
            _ => left,
        });
    }
    s.push(gain_sentence(&f, &mut q));
    Headline {
        sentences: s,
        numbers: q.numbers,
    }
}

/// What the extended model gets wrong at the lowest tensions, which the fits in T2 (where a
/// low-tension row weighs little) cannot show: a predicted T2 at or below zero where every
/// reading is above it (its constant T2 offset cannot hold down to zero tension), or else an
/// amplification further off than Euler-Eytelwein's (RMS ln(T2/T1) residual over the rows
/// where both are defined). None where neither happens.
fn low_tension_sentence(a: &Analysis, q: &mut Quote<'_>) -> Option<String> {
    let steps = a.ln_amp_by_step.as_ref()?;
    let mut order: Vec<usize> = (0..steps.len()).collect();
    order.sort_by(|&i, &j| steps[i].mean_t1_n.total_cmp(&steps[j].mean_t1_n));
    let p = |i: usize, f: &str| format!("/ln_amp_by_step/{i}/{f}");
    let first = *order.first()?;
    let st = &steps[first];
    if st.extended_nonpositive > 0 && st.measured_lowest_n > 0.0 {
        let k = q.num(
            st.extended_nonpositive as f64,
            0,
            p(first, "extended_nonpositive"),
        );
        let n = q.num(st.rows as f64, 0, p(first, "rows"));
        let t1 = q.num(st.mean_t1_n, 2, p(first, "mean_t1_n"));
        let low = q.num(st.extended_lowest_n, 2, p(first, "extended_lowest_n"));
        let m = q.num(st.measured_lowest_n, 2, p(first, "measured_lowest_n"));
        let more = if order[1..]
            .iter()
            .any(|&i| steps[i].extended_nonpositive > 0)
        {
            " (and at higher steps too)"
        } else {
            ""
        };
        return Some(format!("At the lowest tensions the model with these causes fails: at the lowest step (mean T1 {t1} N) it predicts T2 at or below zero for {k} of {n} readings{more}, down to {low} N, where no measured T2 is below {m} N, so the constant offset on T2 cannot hold down to zero tension; its fit is in T2, where those rows weigh little."));
    }
    let worse = |i: usize| steps[i].extended_rms > steps[i].baseline_rms;
    let n_worse = order.iter().filter(|&&i| worse(i)).count();
    if n_worse == 0 {
        return None;
    }
    let lowest_run = order.iter().take_while(|&&i| worse(i)).count();
    if lowest_run < n_worse {
        return Some("At some steps the extended model's amplification is further off than Euler-Eytelwein's (the ln-amplification residuals by step): its fit is in T2, where a low-tension row weighs little.".into());
    }
    let top = order[lowest_run - 1];
    let t1 = q.num(steps[top].mean_t1_n, 2, p(top, "mean_t1_n"));
    let ext = q.num(steps[first].extended_rms, 2, p(first, "extended_rms"));
    let base = q.num(steps[first].baseline_rms, 2, p(first, "baseline_rms"));
    Some(format!("At the lowest tensions (steps of mean T1 up to {t1} N) the extended model's amplification is further off than Euler-Eytelwein's (RMS residual of ln(T2/T1) {ext} against {base} at the lowest step): its fit is in T2, where those rows weigh little."))
}

/// The gain: the whole procedure's held-out error against Euler-Eytelwein's, with its test's
/// name, p and verdict (and the cords a gain of this size would need); cords whose folds failed
/// counted apart and named, and no ratio quoted when too few folds are left to identify it.
fn gain_sentence(f: &Facts<'_>, q: &mut Quote<'_>) -> String {
    let g = f.gain;
    const PTR: &str = "/gain/loco_rmse_ratio_extended_over_baseline";
    if g.cords + g.failed.len() < 2 {
        return "No cord can be left out of the fit (one cord): the gain on new cords is not measured.".into();
    }
    use capstan_engine::analysis::gain::GainVerdict as V;
    // Quoted only when said: the headline's numbers are the ones its sentences show.
    let apart = if g.failed.is_empty() {
        String::new()
    } else {
        set_apart(g, q)
    };
    if g.verdict == V::NotIdentified {
        return format!(
            "On a cord left out of the fit the gain is not identified: {apart}, and the {} cords left are too few to test it.",
            q.num(g.cords as f64, 0, format!("{PTR}/cords"))
        );
    }
    let ratio = q.num(g.value, 2, format!("{PTR}/value"));
    let interval = if g.ci95.lo.is_finite() && g.ci95.hi.is_finite() {
        let lo = q.num(g.ci95.lo, 2, format!("{PTR}/ci95/lo"));
        let hi = q.num(g.ci95.hi, 2, format!("{PTR}/ci95/hi"));
        format!(" (95 % interval {lo} to {hi}, by inverting the sign-flip test)")
    } else {
        String::new()
    };
    let better = q.num(f.better.0 as f64, 0, format!("{PTR}/cords_better"));
    let cords = q.num(f.better.1 as f64, 0, format!("{PTR}/cords"));
    // Two decimals, three under 0.1: a p of 0.047 must not read 0.05 beside "established".
    let p = q.num(g.p, if g.p < 0.1 { 3 } else { 2 }, format!("{PTR}/p"));
    let needed = match g.cords_needed.as_ref().map(|n| (n.cords, n.power)) {
        Some((Some(k), power)) => {
            let k = q.num(k as f64, 0, format!("{PTR}/cords_needed/cords"));
            let power = q.num(power, 2, format!("{PTR}/cords_needed/power"));
            format!("; about {k} cords would establish a gain of this size with power {power} (by simulation, resampling these cords' held-out errors)")
        }
        Some((None, _)) => {
            "; no number of cords the simulation tried would establish a gain of this size".into()
        }
        None => String::new(),
    };
    let verdict = match g.verdict {
        V::Established => format!("p = {p}: a gain on new cords is established"),
        V::NotEstablished if g.value >= 1.0 => {
            format!("p = {p}: the model with these causes is not better on new cords")
        }
        V::NotEstablished => {
            format!("p = {p}: a gain on new cords is not established{needed}")
        }
        V::Worse => format!("p = {p}: the model with these causes predicts new cords worse"),
        V::TooFewCords => format!(
            "p = {p}, and it cannot go below {} with so few cords: a gain on new cords cannot be established on these data{needed}",
            q.num(g.p_smallest, 3, format!("{PTR}/p_smallest"))
        ),
        V::NotIdentified => unreachable!("said above"),
    };
    let apart = if g.failed.is_empty() {
        String::new()
    } else {
        format!(" ({apart}, never counted as held-out successes)")
    };
    let test = if g.method.starts_with("exact") {
        "the exact sign-flip test over the cords"
    } else {
        "a sign-flip test over the cords (random sign patterns)"
    };
    format!(
        "On a cord left out of the fit, with the causes chosen again without it, the model with these causes has {ratio} times Euler-Eytelwein's error{interval}, better on {better} of {cords} cords{apart}; by {test}, {verdict}."
    )
}

/// "2 cords set apart because their fits failed (A, B)": the cords whose folds failed, counted
/// and named (the first three).
fn set_apart(g: &capstan_engine::analysis::gain::Gain, q: &mut Quote<'_>) -> String {
    let k = g.failed.len();
    let names: Vec<&str> = g.failed.iter().take(3).map(|(c, _)| c.as_str()).collect();
    let more = if k > 3 { ", ..." } else { "" };
    format!(
        "{} {} set apart because {} fits failed ({}{more})",
        q.num(
            k as f64,
            0,
            "/gain/loco_rmse_ratio_extended_over_baseline/set_apart".into()
        ),
        if k == 1 { "cord is" } else { "cords are" },
        if k == 1 { "its" } else { "their" },
        names.join(", ")
    )
}

/// "a", "a and b", "a, b and c".
fn join_and(parts: &[String]) -> String {
    match parts {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::headline;
    use capstan_engine::analysis::gain::{gain, GainVerdict};
    use capstan_engine::analysis::uncertainty::{CordErrors, Interval};

    /// The thesis analysed (on two threads).
    fn thesis() -> capstan_engine::analysis::Analysis {
        capstan_engine::analysis::run(
            &capstan_data::thesis_dataset(),
            capstan_engine::analysis::Options {
                threads: 2,
                ..Default::default()
            },
        )
        .unwrap()
    }

    /// The thesis analysed, then the extended model's held-out predictions of the cords
    /// `failed` made not finite — what a fold that did not converge leaves (the thesis
    /// with 5 % of its rows' T1 and T2 swapped did this to every fold) — and the gain taken
    /// again from them: the failure built directly at the library's level.
    fn with_failed(a: &capstan_engine::analysis::Analysis, failed: &[usize]) -> String {
        let mut a = a.clone();
        let obs = &a.obs;
        let mut ext = a.pred.extended_loco.clone();
        for &g in failed {
            for i in obs.rows_of_group(g) {
                ext[i] = f64::NAN;
            }
        }
        let labels: Vec<String> = obs.groups.iter().map(|g| g.label.clone()).collect();
        let nan = Interval {
            lo: f64::NAN,
            hi: f64::NAN,
        };
        a.gain = gain(
            &CordErrors::of(obs, &ext),
            &CordErrors::of(obs, &a.pred.baseline_loco),
            Vec::new(),
            (nan, f64::NAN),
            &labels,
        );
        assert_eq!(a.gain.set_apart, failed.len());
        let h = headline(&a);
        h.sentences.last().cloned().unwrap_or_default()
    }

    /// Structure left that no cause accounts for: the causes are not "established" in the
    /// headline while the verdict layer calls them no diagnosis (issue 42: analyze said "The
    /// data establish …" and diagnose "Unexplained … not a diagnosis" of the same data). The
    /// thesis analysis with its verdict turned to unexplained, built at the library's level.
    #[test]
    fn causes_beside_unexplained_structure_are_no_diagnosis_in_the_headline() {
        let mut a = thesis();
        let clean = headline(&a).sentences.join(" ");
        assert!(clean.contains("The data establish that"), "{clean}");
        a.mechanisms.unexplained.flag = true;
        a.mechanisms.unexplained.pattern = Some("time");
        let h = headline(&a).sentences.join(" ");
        assert!(!h.contains("The data establish"), "{h}");
        assert!(
            h.contains("Left unexplained: T2 drifts with time inside runs.")
                && h.contains("fit — T2 needs an additive offset of")
                && h.contains("do not account for it, so they are not a diagnosis."),
            "{h}"
        );
        assert!(!h.contains("cord-to-cord scatter"), "{h}");
    }

    #[test]
    fn an_offset_whose_cord_interval_includes_zero_is_said_not_established_over_cords() {
        let mut a = thesis();
        let s = headline(&a).sentences.join(" ");
        assert!(
            s.contains("additive offset of -0.82 N, 95 % interval -1.07 to -0.58 by the cord jackknife (a zero")
                && !s.contains("it is not established"),
            "{s}"
        );
        // The same offset with an SE from a few cords: its interval reaches 0.
        let v = (a.extended.values.iter_mut())
            .find(|v| v.name == "t2_offset_n")
            .expect("the thesis names a T2 offset");
        v.jackknife_se = 0.5;
        let s = headline(&a).sentences.join(" ");
        assert!(
            s.contains("by the cord jackknife, which includes 0: with the cords as the units it is not established (a zero"),
            "{s}"
        );
    }

    #[test]
    fn failed_folds_are_counted_apart_and_named_never_held_out_successes() {
        let a = thesis();
        assert_eq!(a.gain.verdict, GainVerdict::NotEstablished);
        // Three cords' folds failed: named, counted apart, the test over the seven left.
        let s = with_failed(&a, &[0, 1, 4]);
        assert!(
            s.contains("3 cords are set apart because their fits failed (D12.7/270deg, D12.7/360deg, D12.7/720deg), never counted as held-out successes"),
            "{s}"
        );
        assert!(s.contains("of 7 cords"), "{s}");
        assert!(!s.contains("is established"), "{s}");
        // Six of ten: too few folds left: not identified, and no ratio quoted.
        let s = with_failed(&a, &[0, 1, 2, 3, 4, 5]);
        assert!(
            s.contains("the gain is not identified: 6 cords are set apart"),
            "{s}"
        );
        assert!(!s.contains("times Euler-Eytelwein's error"), "{s}");
    }

    #[test]
    fn the_low_tension_misfit_is_said_where_the_extended_model_fails_there() {
        let mut a = thesis();
        // The thesis: at the lowest step (T1 0.55 N on average) the model predicts T2 ≤ 0 for
        // 11 of 60 readings, down to −0.45 N, where every reading is at least 0.10 N.
        let h = headline(&a);
        let s = h.sentences.join(" ");
        assert!(
            s.contains("at the lowest step (mean T1 0.55 N) it predicts T2 at or below zero for 11 of 60 readings")
                && s.contains("down to -0.45 N, where no measured T2 is below 0.10 N")
                && s.contains("Above them, what is left is cord-to-cord scatter"),
            "{s}"
        );
        assert!(h
            .numbers
            .iter()
            .any(|n| n.pointer == "/ln_amp_by_step/0/extended_nonpositive"));
        // No T2 ≤ 0 predicted, but worse in ln(T2/T1) at a middle step only: said, without a
        // tension.
        let steps = a.ln_amp_by_step.as_mut().unwrap();
        for st in steps.iter_mut() {
            st.extended_nonpositive = 0;
            st.extended_rms = 0.5 * st.baseline_rms;
        }
        steps[5].extended_rms = 2.0 * steps[5].baseline_rms;
        let s = headline(&a).sentences.join(" ");
        assert!(
            s.contains("At some steps the extended model's amplification"),
            "{s}"
        );
        // ... worse at the two lowest: said with the tension up to which.
        let steps = a.ln_amp_by_step.as_mut().unwrap();
        steps[5].extended_rms = 0.0;
        steps[0].extended_rms = 2.0 * steps[0].baseline_rms;
        steps[1].extended_rms = 2.0 * steps[1].baseline_rms;
        let s = headline(&a).sentences.join(" ");
        assert!(
            s.contains("At the lowest tensions (steps of mean T1 up to 1.12 N)"),
            "{s}"
        );
        // Nowhere worse: nothing said, and what is left is said plainly.
        for st in a.ln_amp_by_step.as_mut().unwrap().iter_mut() {
            st.extended_rms = 0.0;
        }
        let s = headline(&a).sentences.join(" ");
        assert!(!s.contains("At the lowest tensions"), "{s}");
        assert!(s.contains("What is left is cord-to-cord scatter"), "{s}");
    }
}
