//! The report's tables as files for a paper: `tables/parameters.{csv,tex}` (every fitted
//! quantity: value ± SE, its 95 % interval, unit, what it is and how its interval is computed)
//! and `tables/models.{csv,tex}` (the model comparison). The CSV carries every number at full
//! precision; the LaTeX is a booktabs `tabular` (ASCII only, `\usepackage{booktabs}`) with the
//! interval methods as lettered notes under it, ready for `\input` inside a `table` float.

pub use crate::latex_text::latex;
use crate::parameters::Row;
use crate::tex_layout::{p_col, tex_close, tex_header, tex_open};
use capstan_data::text_cell;
use capstan_engine::analysis::Analysis;
use std::fmt::Write as _;

/// `v` with `digits` significant digits ("–" when not finite; scientific below 1e-3 and from
/// 1e5).
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if !(-3..5).contains(&e) {
        return format!("{v:.*e}", digits.saturating_sub(1));
    }
    let d = (digits as i32 - 1 - e).max(0) as usize;
    format!("{v:.d$}")
}

/// A number for a CSV cell: full precision, empty when missing.
fn num(v: Option<f64>) -> String {
    v.filter(|v| v.is_finite())
        .map_or(String::new(), |v| format!("{v}"))
}

/// `parameters.csv`.
pub fn parameters_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "key,quantity,estimate_of,value,se,ci95_lo,ci95_hi,unit,interval_method_or_note\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            text_cell(&r.key),
            text_cell(&r.quantity),
            text_cell(&r.source),
            num(Some(r.value)),
            num(r.se),
            num(r.ci95_lo),
            num(r.ci95_hi),
            text_cell(r.unit),
            text_cell(&r.note)
        );
    }
    s
}

/// A value ± SE and its interval in LaTeX, at the SE's precision (two significant digits), or
/// two significant digits of the value without an SE ([`crate::cells::se_decimals`]); a common
/// power of ten for very small or large values.
fn tex_value(v: f64, se: Option<f64>, ci: Option<(f64, f64)>) -> (String, String) {
    if !v.is_finite() {
        return ("--".into(), "--".into());
    }
    let e = if v != 0.0 {
        v.abs().log10().floor() as i32
    } else {
        0
    };
    let (scale, power) = if (-3..5).contains(&e) {
        (1.0, None)
    } else {
        (10f64.powi(-e), Some(e))
    };
    let se = se.filter(|s| s.is_finite() && *s > 0.0).map(|s| s * scale);
    let d = crate::cells::se_decimals(v * scale, se);
    let f = |x: f64| format!("{:.d$}", x * scale);
    let body = match se {
        Some(s) => format!("{} \\pm {s:.d$}", f(v)),
        None => f(v),
    };
    let value = match power {
        Some(p) if se.is_some() => format!("$({body})\\times 10^{{{p}}}$"),
        Some(p) => format!("${body}\\times 10^{{{p}}}$"),
        None => format!("${body}$"),
    };
    let interval = match ci {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() => match power {
            Some(p) => format!("${}$ to ${}$ ($\\times 10^{{{p}}}$)", f(lo), f(hi)),
            None => format!("${}$ to ${}$", f(lo), f(hi)),
        },
        _ => "--".into(),
    };
    (value, interval)
}

/// The letter of note `k` (a, b, ..., z, aa, ab, ...).
fn letter(k: usize) -> String {
    let a = |i: usize| char::from(b'a' + (i % 26) as u8);
    if k < 26 {
        a(k).to_string()
    } else {
        format!("{}{}", a(k / 26 - 1), a(k))
    }
}

/// Notes under a table: each distinct text once, lettered in order of first use. A note that
/// is an earlier one followed by "; more" is marked with both letters, the second note holding
/// only "more" (the extended model's heating row: its interval method, then h = k/τ), so no
/// sentence is printed twice under one table.
#[derive(Default)]
struct Notes(Vec<String>);

impl Notes {
    fn letter_of(&mut self, text: &str) -> String {
        let k = match self.0.iter().position(|n| n == text) {
            Some(k) => k,
            None => {
                self.0.push(text.to_string());
                self.0.len() - 1
            }
        };
        letter(k)
    }

    fn mark(&mut self, text: &str) -> String {
        let shared = (self.0.iter()).find_map(|n| {
            let rest = text.strip_prefix(n.as_str())?.strip_prefix("; ")?;
            Some((n.clone(), rest.to_string()))
        });
        let letters = match shared {
            Some((first, rest)) => format!("{},{}", self.letter_of(&first), self.letter_of(&rest)),
            None => self.letter_of(text),
        };
        format!("\\textsuperscript{{{letters}}}")
    }

    fn tex(&self) -> String {
        let mut s = String::new();
        for (k, n) in self.0.iter().enumerate() {
            let _ = writeln!(s, "\\textsuperscript{{{}}}~{}\\par", letter(k), latex(n));
        }
        s
    }
}

/// The columns of `parameters.tex` after the quantity: value ± SE over its interval (narrow)
/// or value ± SE, interval (wide); unit.
fn parameter_columns() -> (Vec<String>, Vec<String>) {
    let l = || String::from("l");
    (vec![p_col(9.2, false), l()], vec![l(), l(), l()])
}

/// Whether a row is one cord's own mu (`parameters-cords.tex`, apart: ten cords would make
/// Table 1 taller than an 85 mm column).
fn per_cord(r: &Row) -> bool {
    r.key.starts_with("cord.")
}

/// `parameters.tex`: a row per quantity (the value ± SE over its 95 % interval), grouped under
/// what it is an estimate of, the interval methods as lettered notes under the table; every
/// row but the cords' own mu, which are [`cord_parameters_tex`].
pub fn parameters_tex(rows: &[Row], made_by: &str) -> String {
    let rows: Vec<&Row> = rows.iter().filter(|r| !per_cord(r)).collect();
    rows_tex(
        &rows,
        "Every fitted quantity of capstan analyze but each cord's own mu (parameters-cords.tex), grouped by what it is an estimate of: value +- standard error over its 95 % interval, unit; the notes say how each interval is computed (or why two estimates of one quantity differ). With more named causes than the thesis's two it may be taller than a column: then set it in a table* float.",
        made_by,
    )
}

/// `parameters-cords.tex`: each cord's own Euler-Eytelwein mu, as `parameters.tex` lays it out.
pub fn cord_parameters_tex(rows: &[Row], made_by: &str) -> String {
    let rows: Vec<&Row> = rows.iter().filter(|r| per_cord(r)).collect();
    rows_tex(
        &rows,
        "Each cord's own Euler-Eytelwein mu from capstan analyze (the rest of Table 1 is parameters.tex): value +- standard error over its 95 % interval, unit; the note says how the interval is computed.",
        made_by,
    )
}

/// A parameter table of `rows` under the header `what`.
fn rows_tex(rows: &[&Row], what: &str, made_by: &str) -> String {
    let mut s = tex_header(what, made_by);
    let (narrow, wide) = parameter_columns();
    s.push_str(&tex_open(&narrow, &wide));
    s.push_str(
        "Quantity & \\CapstanPair{Value $\\pm$ SE}{95\\,\\% interval} & Unit \\\\\n\\midrule\n",
    );
    let mut notes = Notes::default();
    let mut group: Option<&str> = None;
    for r in rows {
        if group != Some(r.source.as_str()) {
            if group.is_some() {
                s.push_str("\\addlinespace\n");
            }
            let _ = writeln!(s, "\\textit{{{}}} \\\\", latex(&r.source));
            group = Some(r.source.as_str());
        }
        let ci = r.ci95_lo.zip(r.ci95_hi);
        let (value, interval) = tex_value(r.value, r.se, ci);
        let mark = if r.note.is_empty() {
            String::new()
        } else {
            notes.mark(&r.note)
        };
        let _ = writeln!(
            s,
            "{}{mark} & \\CapstanPair{{{value}}}{{{interval}}} & {} \\\\",
            latex(&r.quantity),
            latex(r.unit)
        );
    }
    s.push_str(&tex_close(&notes.tex()));
    s
}

/// The interval method of the model table, in both files.
const MODEL_NOTE: &str = "95 % intervals: percentiles of a bootstrap over cords (whole cords resampled), descriptive and too narrow at ten or fewer cords (a comparison of the models is the held-out gain's exact sign-flip test, in the report). LOCO: each cord predicted by a fit to the other cords. Parameters: fixed values plus the effective degrees of freedom of the cord effects. AIC and BIC treat rows as independent and are for comparison with the thesis only.";

/// What `models.csv` adds to [`MODEL_NOTE`]: its SE columns (`models.tex` has none).
const MODEL_NOTE_SE: &str = " The _se columns: the cord jackknife's SE.";

/// `models.csv`.
pub fn models_csv(a: &Analysis) -> String {
    let mut s = String::from("model,name,description,parameters,fixed,edf_cord_effects,rmse_t2_n,rmse_t2_se,rmse_t2_ci95_lo,rmse_t2_ci95_hi,loco_rmse_t2_n,loco_rmse_t2_se,loco_rmse_t2_ci95_lo,loco_rmse_t2_ci95_hi,rmse_ln_amp,ln_amp_rows_left_out,median_per_cord_r2_amp,aic,bic,interval_method\n");
    for m in &a.models {
        let u = &m.rmse_t2_uncertainty;
        let l = m.loco_rmse_t2_uncertainty.as_ref();
        let cells = [
            text_cell(&crate::figures::model_label(&m.name)),
            text_cell(&m.name),
            text_cell(&m.description),
            num(Some(m.n_params)),
            m.n_params_detail.fixed.to_string(),
            num(Some(m.n_params_detail.edf_random)),
            num(Some(u.value)),
            num(Some(u.jackknife_se)),
            num(Some(u.ci95.lo)),
            num(Some(u.ci95.hi)),
            num(l.map(|l| l.value)),
            num(l.map(|l| l.jackknife_se)),
            num(l.map(|l| l.ci95.lo)),
            num(l.map(|l| l.ci95.hi)),
            num(Some(m.rmse_ln_amp)),
            m.ln_amp_undefined_rows.to_string(),
            num(Some(m.per_cord_r2_amp_median)),
            num(Some(m.aic)),
            num(Some(m.bic)),
            text_cell(&format!("{MODEL_NOTE}{MODEL_NOTE_SE}")),
        ];
        let _ = writeln!(s, "{}", cells.join(","));
    }
    s
}

/// An RMSE over its interval: "$1.718$\newline [$1.149$, $2.253$]".
fn tex_rmse(w: Option<&capstan_engine::analysis::uncertainty::WithInterval>) -> String {
    match w {
        Some(w) if w.value.is_finite() => {
            format!(
                "\\CapstanOver{{${:.3}$}}{{[${:.3}$, ${:.3}$]}}",
                w.value, w.ci95.lo, w.ci95.hi
            )
        }
        _ => "not refittable".into(),
    }
}

/// The columns of `models.tex` after the model: parameters, the two RMSEs (each over its
/// interval when narrow, beside it when wide), AIC over BIC (narrow) or AIC, BIC (wide).
fn model_columns() -> (Vec<String>, Vec<String>) {
    let narrow = vec![
        p_col(3.4, true),
        p_col(6.4, false),
        p_col(6.4, false),
        p_col(3.4, true),
    ];
    let wide = ["r", "l", "l", "r", "r"].map(String::from).to_vec();
    (narrow, wide)
}

/// `models.tex`: a row per model, each RMSE over its 95 % interval, AIC over BIC.
pub fn models_tex(a: &Analysis, made_by: &str) -> String {
    let mut s = tex_header(
        "The models of capstan analyze compared: RMSE of T2 in-sample and leaving one cord out, each over its 95 % interval over cords; AIC over BIC.",
        made_by,
    );
    let (narrow, wide) = model_columns();
    s.push_str(&tex_open(&narrow, &wide));
    s.push_str("Model & Param. & \\CapstanOver{RMSE $T_2$ (N)}{[95\\,\\% CI]} & \\CapstanOver{LOCO RMSE $T_2$ (N)}{[95\\,\\% CI]} & \\CapstanPair{AIC}{BIC} \\\\\n\\midrule\n");
    for m in &a.models {
        let params = if m.n_params_detail.edf_random > 0.0 {
            format!(
                "{} + {:.1}",
                m.n_params_detail.fixed, m.n_params_detail.edf_random
            )
        } else {
            format!("{}", m.n_params)
        };
        let _ = writeln!(
            s,
            "{} & {params} & {} & {} & \\CapstanPair{{${:.1}$}}{{${:.1}$}} \\\\",
            latex(&crate::figures::model_label(&m.name)),
            tex_rmse(Some(&m.rmse_t2_uncertainty)),
            tex_rmse(m.loco_rmse_t2_uncertainty.as_ref()),
            m.aic,
            m.bic
        );
    }
    s.push_str(&tex_close(&format!("{}\\par\n", latex(MODEL_NOTE))));
    s
}

/// Every table file: its name under the output directory and its text.
pub fn table_files(a: &Analysis, made_by: &str) -> Vec<(String, String)> {
    let rows = crate::parameters::rows(a);
    vec![
        ("tables/parameters.csv".into(), parameters_csv(&rows)),
        (
            "tables/parameters.tex".into(),
            parameters_tex(&rows, made_by),
        ),
        (
            "tables/parameters-cords.tex".into(),
            cord_parameters_tex(&rows, made_by),
        ),
        ("tables/models.csv".into(), models_csv(a)),
        ("tables/models.tex".into(), models_tex(a, made_by)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_take_their_se_precision() {
        assert_eq!(
            tex_value(0.145275, Some(0.00454), Some((0.135, 0.1555))),
            ("$0.1453 \\pm 0.0045$".into(), "$0.1350$ to $0.1555$".into())
        );
        assert_eq!(
            tex_value(-0.8234, Some(0.107), None),
            ("$-0.82 \\pm 0.11$".into(), "--".into())
        );
        let (v, i) = tex_value(1.6e-5, Some(3.2e-6), Some((0.0, 2.2e-5)));
        assert_eq!(v, "$(1.60 \\pm 0.32)\\times 10^{-5}$");
        assert_eq!(i, "$0.00$ to $2.20$ ($\\times 10^{-5}$)");
        assert_eq!(tex_value(4.9515, None, None).0, "$5.0$");
        assert_eq!(sig(0.004539, 2), "0.0045");
        assert_eq!(sig(1.6e-6, 2), "1.6e-6");
    }
}
