//! What the extended model's residuals still trend with, read as one family of tests: its
//! cord-clustered slope tests (the T2 and ln(T2/T1) residuals against every column,
//! [`capstan_engine::analysis::residuals`]) with their Holm-adjusted p-values, so that one small
//! p among a dozen is quoted as what it is.

use crate::cells::{fp, fx};
use capstan_engine::analysis::residuals::Pattern;
use capstan_engine::analysis::Analysis;

/// The residual in words.
fn residual_words(p: &Pattern) -> String {
    let (what, unit) = match p.residual {
        "t2_n" => ("the T2 residual", " N"),
        _ => ("the ln(T2/T1) residual", ""),
    };
    format!(
        "{what} against {} (slope {}{unit} per SD of {})",
        p.column,
        fx(p.slope_per_sd, 3),
        p.column
    )
}

/// The fewest cords whose cord-clustered slope tests the report reads: with fewer, a sandwich
/// over the cords is degenerate (two cords fit any column that is constant within a cord
/// exactly, and give p < 0.0001 on nothing). The claim's size was measured at the thesis's 10
/// (`science/validation/tests/cord_calibration.rs`).
pub const MIN_CORDS: usize = 5;

/// "p = 0.039", or "p < 0.0001".
fn p_is(p: f64) -> String {
    match fp(p) {
        t if t.starts_with('<') => format!("p {t}"),
        t => format!("p = {t}"),
    }
}

/// One sentence on the extended model's residual trends: those established after Holm's
/// adjustment over its family of slope tests, or the smallest p with its adjusted value and
/// that nothing is established; with fewer than [`MIN_CORDS`] cords, that they are not judged.
/// Empty when the model's residuals could not be tested at all.
pub fn extended_trends(a: &Analysis) -> String {
    let mut family: Vec<&Pattern> = (a.residual_patterns.iter())
        .filter(|p| p.model == "extended" && p.slope_p_cluster.is_finite())
        .collect();
    family.sort_by(|x, y| x.slope_p_cluster.total_cmp(&y.slope_p_cluster));
    let m = family.len();
    let cords = a.obs.groups.len();
    let Some(first) = family.first() else {
        return String::new();
    };
    if cords < MIN_CORDS {
        return format!("Whether the extended model's residuals still trend is not judged on {cords} cord{}: its cord-clustered slope tests need {MIN_CORDS} cords or more.", if cords == 1 { "" } else { "s" });
    }
    let tests = format!("its {m} cord-clustered slope tests (the T2 and ln(T2/T1) residuals against every column, t on {} degrees of freedom)", cords - 1);
    let found: Vec<String> = (family.iter())
        .filter(|p| p.slope_p_holm < 0.05)
        .map(|p| format!("{}, adjusted {}", residual_words(p), p_is(p.slope_p_holm)))
        .collect();
    match found.is_empty() {
        false => format!(
            "The extended model's residuals still trend, by Holm's adjustment over {tests}: {}.",
            found.join("; ")
        ),
        true => format!(
            "No trend of the extended model's residuals is established: of {tests}, the smallest p is {}, for {}, and {} after Holm's adjustment for the {m}; a trend of that size is neither established nor excluded on {cords} cords.",
            fp(first.slope_p_cluster),
            residual_words(first),
            fp(first.slope_p_holm)
        ),
    }
}
