//! What the extended model's residuals still trend with, read as one family of tests: its
//! cord-clustered slope tests (the T2 and ln(T2/T1) residuals against every column but the
//! measured T2, [`capstan_engine::analysis::residuals`]) with their Holm-adjusted p-values, so
//! that one small p among a dozen is quoted as what it is.

use crate::cells::{fp, fx};
use capstan_engine::analysis::residuals::{Pattern, MIN_CLUSTERS};
use capstan_engine::analysis::Analysis;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// The residual and its slope in words.
fn residual_words(p: &Pattern) -> (&'static str, &'static str) {
    match p.residual {
        "t2_n" => ("the T2 residual", " N"),
        _ => ("the ln(T2/T1) residual", ""),
    }
}

/// A column's unit for "per …": a physical column's own, else "unit of" it.
fn per(column: &str) -> String {
    match column {
        "t1_n" | "t2_n" => "N".into(),
        "wrap_deg" => "degree of wrap".into(),
        "capstan_diameter_mm" => "mm of diameter".into(),
        "drive_v" => "V of drive".into(),
        "run" => "run".into(),
        "step" => "step".into(),
        "time_s" => "s".into(),
        other => format!("unit of {other}"),
    }
}

/// "p = 0.039", or "p < 0.0001".
fn p_is(p: f64) -> String {
    match fp(p) {
        t if t.starts_with('<') => format!("p {t}"),
        t => format!("p = {t}"),
    }
}

/// The slope per unit of the column, and its 95 % interval adjusted for `m` tests
/// (Bonferroni: t at 1 − 0.025/m on cords − 1 degrees of freedom, the SE the cord-clustered
/// t's), as "−0.086 N per run (95 % interval adjusted for the 10 tests −0.22 to 0.05)".
fn slope_words(p: &Pattern, m: usize, cords: usize) -> String {
    let (_, unit) = residual_words(p);
    let b = p.slope_per_sd / p.column_sd;
    let se = (b / p.slope_t_cluster).abs();
    let q = StudentsT::new(0.0, 1.0, cords.saturating_sub(1).max(1) as f64)
        .map_or(f64::NAN, |t| t.inverse_cdf(1.0 - 0.025 / m.max(1) as f64));
    let d = crate::cells::se_decimals(b, Some(se));
    format!(
        "{}{unit} per {} (95 % interval adjusted for the {m} tests {} to {})",
        fx(b, d),
        per(&p.column),
        fx(b - q * se, d),
        fx(b + q * se, d)
    )
}

/// One sentence on the extended model's residual trends: those established after Holm's
/// adjustment over its family of slope tests, or the smallest p, its adjusted value and its
/// slope's interval adjusted for the family; with fewer than [`MIN_CLUSTERS`] cords, that they
/// are not judged. Empty when the model's residuals have no test at all.
pub fn extended_trends(a: &Analysis) -> String {
    let cords = a.obs.groups.len();
    if cords < MIN_CLUSTERS {
        return format!("Whether the extended model's residuals still trend is not judged on {cords} cord{}: their cord-clustered slope tests need {MIN_CLUSTERS} cords or more.", if cords == 1 { "" } else { "s" });
    }
    let mut family: Vec<&Pattern> = (a.residual_patterns.iter())
        .filter(|p| p.model == "extended" && p.slope_p_holm.is_finite())
        .collect();
    family.sort_by(|x, y| x.slope_p_cluster.total_cmp(&y.slope_p_cluster));
    let m = family.len();
    let Some(first) = family.first() else {
        return String::new();
    };
    let tests = format!("its {m} cord-clustered slope tests (the T2 and ln(T2/T1) residuals against every column but the measured T2, t on {} degrees of freedom)", cords - 1);
    let slope = |p: &Pattern| {
        let (what, _) = residual_words(p);
        format!(
            "{what} against {}, whose slope is {}",
            p.column,
            slope_words(p, m, cords)
        )
    };
    let found: Vec<String> = (family.iter())
        .filter(|p| p.slope_p_holm < 0.05)
        .map(|p| format!("{}, adjusted {}", slope(p), p_is(p.slope_p_holm)))
        .collect();
    // The logarithm of a noisy T2 leans low where T2 is small (by about σ²/(2·T2²)): on
    // simulated campaigns with no trend planted, most claims were ln(T2/T1) against T1.
    let log_bias = match (family.iter()).any(|p| p.slope_p_holm < 0.05 && p.residual == "ln_amp") {
        true => " (a ln(T2/T1) residual leans low where T2 is small by the noise alone, about σ²/(2·T2²), so its trend with tension may be the noise's)",
        false => "",
    };
    match found.is_empty() {
        false => format!(
            "The extended model's residuals still trend, by Holm's adjustment over {tests}: {}{log_bias}.",
            found.join("; ")
        ),
        true => format!(
            "No trend of the extended model's residuals is established: of {tests}, the smallest p is {} ({} after Holm's adjustment for the {m}), for {}.",
            fp(first.slope_p_cluster),
            fp(first.slope_p_holm),
            slope(first)
        ),
    }
}
