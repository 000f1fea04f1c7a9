//! The "discovered" part of the report and of `metrics.json`: what `capstan discover` proposes
//! beyond the catalogue (docs/README-discover.md), kept apart from the catalogue's causes and
//! never worded as an established cause, with the held-out RMSE with and without each term.

use crate::cells::esc;
use capstan_discover::heldout::Interval;
use capstan_discover::library::{ActsOn, Var};
use capstan_discover::{Declined, Discovery, Proposed, Rival};
use capstan_engine::evidence::adequacy::LackOfFit;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// What a proposed term is called in the report: never an established cause.
const STATUS: &str = "discovered (a candidate, not an established cause)";

/// The `discovered` object of `metrics.json`.
#[derive(Serialize)]
pub struct Discovered<'a> {
    /// The terms proposed.
    pub terms: Vec<Term<'a>>,
    /// Structure still left after them (`None`: not testable).
    pub unexplained_after: Option<bool>,
    /// The pattern of what is left.
    pub residual_pattern: Option<&'static str>,
    /// The answer in words.
    pub verdict: &'a str,
    /// Terms looked at closely and not proposed.
    pub declined: &'a [Declined],
    /// Terms in the library.
    pub library_size: usize,
    /// Terms testable on these data.
    pub library_tried: usize,
    /// The bar the first term had to pass.
    pub first_bar: f64,
    /// Wall time of the search, s.
    pub elapsed_s: f64,
}

/// A proposed term as `metrics.json` carries it.
#[derive(Serialize)]
pub struct Term<'a> {
    /// Library name.
    pub name: &'static str,
    /// [`STATUS`]: a candidate, not an established cause.
    pub status: &'static str,
    /// Formula.
    pub formula: &'static str,
    /// Where it acts.
    pub acts_on: ActsOn,
    /// What it depends on.
    pub depends_on: &'static [Var],
    /// Its parameter.
    pub parameters: &'a BTreeMap<&'static str, f64>,
    /// Its standard error.
    pub parameter_se: &'a BTreeMap<&'static str, f64>,
    /// ΔBIC given the catalogue and the terms before it.
    pub delta_bic_given_others: f64,
    /// Share of whole-cord resamples that pick it.
    pub stability: f64,
    /// Held-out RMSE without and with it.
    pub held_out: HeldOut<'a>,
    /// The held-out upper end is below 1.
    pub shown_to_predict_better: bool,
    /// Structure still left with it, most of it resolved.
    pub partial: bool,
    /// Lack of fit against the replicate runs with it in.
    pub lack_of_fit_after: &'a Option<LackOfFit>,
    /// Library terms within the rival gap of it.
    pub rivals: &'a [Rival],
    /// Why it was proposed without the replicate gate, if it was.
    pub replicate_gate_not_applied: Option<&'static str>,
}

/// A term's held-out RMSE ratio.
#[derive(Serialize)]
pub struct HeldOut<'a> {
    /// Held-out RMSE without it, N.
    pub rmse_without_n: f64,
    /// Held-out RMSE with it, N.
    pub rmse_with_n: f64,
    /// With over without.
    pub ratio: f64,
    /// Its 95 % interval (cord jackknife).
    pub ci95: &'a Interval,
    /// How a held-out cord is predicted.
    pub method: &'static str,
}

impl<'a> Term<'a> {
    fn of(t: &'a Proposed) -> Self {
        let r = &t.loco_rmse_ratio;
        Term {
            name: t.name,
            status: STATUS,
            formula: t.formula,
            acts_on: t.acts_on,
            depends_on: t.depends_on,
            parameters: &t.parameters,
            parameter_se: &t.parameter_se,
            delta_bic_given_others: t.delta_bic_given_others,
            stability: t.stability,
            held_out: HeldOut {
                rmse_without_n: r.rmse_without_n,
                rmse_with_n: r.rmse_with_n,
                ratio: r.value,
                ci95: &r.ci95,
                method: r.method,
            },
            shown_to_predict_better: t.shown_to_predict_better,
            partial: t.partial,
            lack_of_fit_after: &t.lack_of_fit_after,
            rivals: &t.rivals,
            replicate_gate_not_applied: t.replicate_gate_not_applied,
        }
    }
}

/// The `discovered` object of `metrics.json` from `capstan discover`'s answer, with the
/// search's wall time as the analysis measured it, s.
pub fn discovered(d: &Discovery, elapsed_s: f64) -> Discovered<'_> {
    Discovered {
        terms: d.terms.iter().map(Term::of).collect(),
        unexplained_after: d.unexplained_after,
        residual_pattern: d.residual_pattern,
        verdict: &d.verdict,
        declined: &d.declined,
        library_size: d.search.library_size,
        library_tried: d.search.tried,
        first_bar: d.search.first_bar,
        elapsed_s,
    }
}

/// A number to three decimals, "-" where JSON has none (not finite).
fn f3(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "-".into()
    }
}

/// `v`, NaN where JSON has no number (the sentence then says NaN, as it always did).
fn or_nan(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::NAN
    }
}

/// The report's section.
pub fn discovered_html(d: &Discovery) -> String {
    let mut h = String::from("<h2>Beyond the catalogue: discovered</h2>");
    let _ = write!(
        h,
        "<p><code>capstan discover</code> searched {} of {} library terms (those these data can test) for what the catalogue leaves (bar ΔBIC &lt; {:.1}, the search paid for; stability over whole-cord resamples; held-out cords). {}</p>",
        d.search.tried,
        d.search.library_size,
        or_nan(d.search.first_bar),
        esc(&d.verdict)
    );
    if !d.terms.is_empty() {
        h.push_str("<table><tr><th>term (discovered, not an established cause)</th><th>acts on</th><th>depends on</th><th>held-out RMSE without → with (N)</th><th>ratio [95 %]</th><th>predicts new cords better</th><th>lack of fit after it</th><th>stability</th></tr>");
        for t in &d.terms {
            term_row(&mut h, t);
        }
        h.push_str("</table>");
    }
    if let Some(x) = d.declined.first() {
        let held = match &x.loco_rmse_ratio {
            Some(r)
                if [r.value, r.ci95.lo, r.ci95.hi]
                    .iter()
                    .all(|v| v.is_finite()) =>
            {
                format!(
                    " Held-out RMSE ratio with it: {:.3} [{:.3}, {:.3}].",
                    r.value, r.ci95.lo, r.ci95.hi
                )
            }
            _ => String::new(),
        };
        let _ = write!(
            h,
            "<p>The strongest candidate not proposed: <code>{}</code> (ΔBIC {:.1}): {}.{held}</p>",
            esc(x.name),
            or_nan(x.delta_bic),
            esc(&x.reason)
        );
    }
    h
}

/// One proposed term's row of the section's table.
fn term_row(h: &mut String, t: &Proposed) {
    let r = &t.loco_rmse_ratio;
    let gate = match t.replicate_gate_not_applied {
        Some(why) => format!(" (without the replicate gate: {})", esc(why)),
        None => String::new(),
    };
    let depends: Vec<&str> = t.depends_on.iter().map(|v| v.name()).collect();
    let _ = write!(
        h,
        "<tr><td>{}{gate}</td><td>{}</td><td>{}</td><td>{} → {}</td><td>{} [{}, {}]</td><td>{}</td><td>{}</td><td>{}</td></tr>",
        esc(t.name),
        esc(t.acts_on.name()),
        esc(&depends.join(", ")),
        f3(r.rmse_without_n),
        f3(r.rmse_with_n),
        f3(r.value),
        f3(r.ci95.lo),
        f3(r.ci95.hi),
        if t.shown_to_predict_better {
            "shown (upper end below 1)"
        } else {
            "not shown (interval reaches 1)"
        },
        esc(&lack_of_fit_words(t)),
        f3(t.stability)
    );
}

/// A term's lack of fit against the replicate runs with it in, and whether it is partial.
fn lack_of_fit_words(t: &Proposed) -> String {
    let p = (t.lack_of_fit_after.as_ref().map(|l| l.p)).filter(|p| p.is_finite());
    match (p, t.partial) {
        (Some(p), true) => {
            format!("partial: structure still left (p = {p:.3}); explains most, not all")
        }
        (Some(p), _) if p < 0.01 => format!("still significant (p = {p:.3})"),
        (Some(p), _) => format!("not significant (p = {p:.3})"),
        (None, _) => "cannot be tested (no replicate runs)".into(),
    }
}

/// `html` with `section` placed before its "Reproducing" heading (or at the end), its text
/// typeset as the page's is (minus signs).
pub fn insert_section(html: String, section: &str) -> String {
    let section = &crate::html::typeset(section);
    match html.find("<h2>Reproducing</h2>") {
        Some(i) => format!("{}{section}{}", &html[..i], &html[i..]),
        None => html + section,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_discover::heldout::Ratio;
    use capstan_discover::screen::Level;
    use serde_json::json;

    /// `capstan discover` on the thesis data.
    fn thesis() -> Discovery {
        let data = capstan_data::thesis_dataset();
        capstan_discover::discover(&data, &Default::default(), &mut |_, _| {})
    }

    fn term() -> Proposed {
        let ci = |lo, hi| Interval { lo, hi };
        Proposed {
            name: "t1_offset_diameter",
            formula: "t1 + θ·d",
            acts_on: ActsOn::T1Reading,
            depends_on: &[Var::T1, Var::Diameter],
            parameters: BTreeMap::from([("theta", 0.01)]),
            parameter_se: BTreeMap::from([("theta", 0.002)]),
            units: "N/mm",
            delta_bic_given_others: -20.0,
            stability: 0.9,
            loco_rmse_ratio: Ratio {
                value: 0.9,
                ci95: ci(0.8, 0.99),
                ci95_bootstrap: ci(0.82, 0.98),
                rmse_with_n: 0.3,
                rmse_without_n: 0.33,
                method: "population-averaged",
            },
            shown_to_predict_better: true,
            level: Level::WithinRun,
            reading: "a T1 offset growing with the diameter",
            source: "test",
            lack_of_fit_after: Some(LackOfFit {
                cells: 12,
                f: 3.0,
                df_lof: 10.0,
                df_pe: 20.0,
                p: 0.002,
                p_at_floor: false,
                systematic_ratio: 0.5,
                saturated: false,
            }),
            partial: true,
            replicate: None,
            replicate_gate_not_applied: None,
            rivals: vec![],
            displaced: None,
            restored: None,
            catalogue_given: None,
            words: String::new(),
        }
    }

    #[test]
    fn nothing_discovered_is_said_and_a_term_is_kept_apart() {
        let mut none = thesis();
        none.terms.clear();
        none.verdict =
            "Nothing in the library explains what the catalogue leaves (pattern: diameter).".into();
        none.declined = vec![Declined {
            name: "t2_lowforce",
            delta_bic: -13.1,
            stability: None,
            loco_rmse_ratio: None,
            displaced: None,
            reason: "unstable".into(),
        }];
        let h = discovered_html(&none);
        assert!(h.contains("Nothing in the library") && h.contains("t2_lowforce"));
        let m = serde_json::to_value(discovered(&none, 0.1)).unwrap();
        assert_eq!(m["terms"], json!([]));
        assert_eq!(m["elapsed_s"], json!(0.1));
        assert_eq!(m["library_tried"], json!(none.search.tried));
        let mut one = none;
        one.terms.push(term());
        one.search.tried = 26;
        one.search.library_size = 28;
        let m = serde_json::to_value(discovered(&one, 0.1)).unwrap();
        assert!(m["terms"][0]["status"]
            .as_str()
            .unwrap()
            .contains("not an established cause"));
        assert_eq!(m["terms"][0]["held_out"]["rmse_without_n"], json!(0.33));
        assert_eq!(m["terms"][0]["depends_on"], json!(["t1", "diameter"]));
        assert_eq!(m["terms"][0]["acts_on"], json!(ActsOn::T1Reading.name()));
        // Partial and "shown to predict better" are carried, and shown in words (D5).
        assert_eq!(m["terms"][0]["partial"], json!(true));
        assert_eq!(m["terms"][0]["shown_to_predict_better"], json!(true));
        assert_eq!(m["terms"][0]["lack_of_fit_after"]["p"], json!(0.002));
        let h = discovered_html(&one);
        assert!(h.contains("t1, diameter") && !h.contains("[\"t1\""), "{h}");
        assert!(h.contains("<td>t1_reading</td>"), "{h}");
        assert!(
            h.contains("0.330 → 0.300") && h.contains("0.900 [0.800, 0.990]"),
            "{h}"
        );
        assert!(h.contains("partial: structure still left"), "{h}");
        assert!(h.contains("searched 26 of 28 library terms"), "{h}");
        let h = insert_section(
            "<h2>A</h2><h2>Reproducing</h2>".into(),
            &discovered_html(&one),
        );
        assert!(h.find("t1_offset_diameter").unwrap() < h.find("Reproducing").unwrap());
    }
}
