//! The words of Table 1's rows: each quantity's name and unit, mu's reference conditions,
//! a cord's label and degrees of freedom, kept apart from the numbers ([`super`]).

/// Unit and words of a model parameter.
pub fn describe(name: &str) -> (&'static str, &'static str) {
    match name {
        "mu" => ("1", "friction coefficient mu (population)"),
        "n" => ("1", "tension exponent n of dT/dθ = k·Tⁿ"),
        "b_nm2" => ("N m²", "bending stiffness of the cord"),
        "mu_change_per_100s" => ("1/(100 s)", "fractional drift of mu per 100 s"),
        "mu_change_per_run" => ("1/run", "fractional change of mu per repeat run"),
        "mu_change_per_mm" => ("1/mm", "fractional change of mu per mm of diameter"),
        "mu_change_per_v" => ("1/V", "fractional change of mu per volt of drive"),
        "mu_log_slope_per_rad" => ("1/rad", "change of ln mu per radian of wrap"),
        "heat_per_ns" => (
            "1/(N s)",
            "contact heating h: mu is multiplied by exp(−h·H), H the friction load remembered (N s)",
        ),
        "heat_per_n" => (
            "1/N",
            "contact heating k = h·τ: at a steady load, mu is multiplied by exp(−k·(T2 − T1))",
        ),
        "heat_tau_s" => ("s", "memory time of the friction load"),
        "t1_offset_n" => ("N", "zero offset (or path loss) of the T1 reading"),
        "t2_offset_n" => ("N", "additive offset of the T2 reading"),
        "t2_gain" => ("1", "gain of the T2 reading relative to T1"),
        _ => ("?", "model parameter"),
    }
}

/// The words of a model's mu: the population value at the reference conditions of the terms
/// the model has (`names`, its parameters), and of no other: "at 1 N" only with Howell's
/// exponent, "at no friction load" only with contact heating ([`capstan_physics`]'s
/// references).
pub fn mu_words(names: &[&str]) -> String {
    let has = |n: &str| names.contains(&n);
    let refs: Vec<String> = [
        (has("n"), format!("at {} N", capstan_physics::REF_TENSION_N)),
        (
            has("heat_per_n") || has("heat_per_ns"),
            "at no friction load".into(),
        ),
        (has("mu_change_per_run"), "on run 1".into()),
        (has("mu_change_per_100s"), "at time 0 of a run".into()),
        (
            has("mu_change_per_mm"),
            format!("at {} mm diameter", capstan_physics::REF_DIAMETER_MM),
        ),
        (
            has("mu_change_per_v"),
            format!("at {} V drive", capstan_physics::REF_DRIVE_V),
        ),
        (
            has("mu_log_slope_per_rad"),
            format!(
                "at {:.0}° of wrap",
                capstan_physics::REF_WRAP_RAD.to_degrees()
            ),
        ),
    ]
    .into_iter()
    .filter_map(|(on, w)| on.then_some(w))
    .collect();
    match refs.is_empty() {
        true => "friction coefficient mu (population)".into(),
        false => format!("friction coefficient mu (population, {})", refs.join(", ")),
    }
}

/// A model parameter as the data identify it: its table name and the factor from the model's
/// value. Contact heating's h (1/(N s)) is fitted at the catalogue's assumed memory time τ,
/// which window means cannot resolve: the data fix only k = h·τ (1/N), so the table gives k.
pub(crate) fn identified(name: &str) -> (&str, f64) {
    match name {
        "heat_per_ns" => ("heat_per_n", capstan_physics::HEAT_TAU_S),
        n => (n, 1.0),
    }
}

/// What a heating row's note adds: h at the catalogue's τ, for a reader who wants it.
pub(crate) fn heating_note(name: &str, k: f64) -> String {
    match name {
        "heat_per_n" => format!(
            "; the data fix only k = h·τ: at the catalogue's assumed memory time τ = {} s, h = k/τ = {} 1/(N s)",
            capstan_physics::HEAT_TAU_S,
            crate::cells::fx(k / capstan_physics::HEAT_TAU_S, 4)
        ),
        _ => String::new(),
    }
}

/// A cord's row label: its wrap and diameter in words, and whatever else its label names (a
/// drive voltage, the data's own cord labels) once: "mu, 270°, D = 12.7 mm" for the label
/// `D12.7/270deg`, "mu, 270°, D = 12.7 mm (9V/red)" for `D12.7/270deg/9V/red`.
pub(super) fn cord_words(label: &str, wrap_deg: f64, diameter_mm: f64) -> String {
    let words = format!("mu, {wrap_deg:.0}°, D = {diameter_mm} mm");
    match label.strip_prefix(&format!("D{diameter_mm}/{wrap_deg}deg")) {
        Some("") => words,
        Some(rest) => format!("{words} ({})", rest.trim_start_matches('/')),
        None => format!("{words} (cord {label})"),
    }
}

/// A whole number of degrees of freedom in words: "9 degrees of freedom", "1 degree of freedom".
pub(super) fn dof_count(df: f64) -> String {
    match df == 1.0 {
        true => "1 degree of freedom".into(),
        false => format!("{df:.0} degrees of freedom"),
    }
}

/// Degrees of freedom in words: "8.3 degrees of freedom", or that the data do not identify
/// them (one cord, one run per cord: never "NaN").
pub(super) fn dof_words(df: f64) -> String {
    if df.is_finite() && df > 0.0 {
        format!("{df:.1} degrees of freedom")
    } else {
        "degrees of freedom these data do not identify".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::{cord_words, dof_count, mu_words};

    #[test]
    fn mu_names_only_the_references_of_its_terms() {
        assert_eq!(
            mu_words(&["mu", "t2_offset_n", "heat_per_n"]),
            "friction coefficient mu (population, at no friction load)"
        );
        assert_eq!(mu_words(&["mu"]), "friction coefficient mu (population)");
        assert_eq!(
            mu_words(&["mu", "n", "mu_change_per_run"]),
            "friction coefficient mu (population, at 1 N, on run 1)"
        );
    }

    #[test]
    fn a_cord_is_named_once() {
        assert_eq!(
            cord_words("D12.7/270deg", 270.0, 12.7),
            "mu, 270°, D = 12.7 mm"
        );
        assert_eq!(
            cord_words("D25.4/720deg/9V/red", 720.0, 25.4),
            "mu, 720°, D = 25.4 mm (9V/red)"
        );
        assert_eq!(dof_count(1.0), "1 degree of freedom");
        assert_eq!(dof_count(9.0), "9 degrees of freedom");
    }
}
