//! Text for a LaTeX file: the report's words and symbols (μ, σ_u, −, ·, ° ...) as ASCII LaTeX,
//! so a table file compiles with any engine.

/// Text for LaTeX: its special characters escaped, the non-ASCII ones the report uses as
/// commands, anything else as `?` (the file stays ASCII for any engine).
pub fn latex(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let chars: Vec<char> = s.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        i += 1;
        // A Greek letter with a one-character subscript ("σ_u"): one math group, σ_u.
        if let (Some(g), Some('_'), Some(sub)) = (greek(c), chars.get(i), chars.get(i + 1)) {
            if sub.is_ascii_alphanumeric() {
                out.push_str(&format!("${g}_{{{sub}}}$"));
                i += 2;
                continue;
            }
        }
        if let Some(g) = greek(c) {
            out.push('$');
            out.push_str(g);
            out.push('$');
            continue;
        }
        let r: &str = match c {
            '\\' => "\\textbackslash{}",
            '&' => "\\&",
            '%' => "\\%",
            '$' => "\\$",
            '#' => "\\#",
            '_' => "\\_",
            '{' => "\\{",
            '}' => "\\}",
            '~' => "\\textasciitilde{}",
            '^' => "\\textasciicircum{}",
            '<' => "$<$",
            '>' => "$>$",
            '|' => "$|$",
            '−' => "$-$",
            '–' => "--",
            '—' => "---",
            '·' | '⋅' => "$\\cdot$",
            '×' => "$\\times$",
            '±' => "$\\pm$",
            '≤' => "$\\leq$",
            '≥' => "$\\geq$",
            '≈' => "$\\approx$",
            '°' => "$^\\circ$",
            '²' => "$^2$",
            '³' => "$^3$",
            'ⁿ' => "$^n$",
            '₁' => "$_1$",
            '₂' => "$_2$",
            '₀' => "$_0$",
            '₃' => "$_3$",
            '¹' => "$^1$",
            '⁻' => "$^{-}$",
            '√' => "$\\surd$",
            '’' => "'",
            '‘' => "`",
            '“' => "``",
            '”' => "''",
            '…' => "\\ldots{}",
            'é' => "\\'e",
            c if c.is_ascii() => {
                out.push(c);
                continue;
            }
            _ => "?",
        };
        out.push_str(r);
    }
    out
}

/// A Greek letter's LaTeX command (math mode).
fn greek(c: char) -> Option<&'static str> {
    Some(match c {
        'α' => "\\alpha",
        'β' => "\\beta",
        'γ' => "\\gamma",
        'δ' => "\\delta",
        'ε' => "\\varepsilon",
        'η' => "\\eta",
        'θ' => "\\theta",
        'κ' => "\\kappa",
        'λ' => "\\lambda",
        'μ' | 'µ' => "\\mu",
        'ν' => "\\nu",
        'π' => "\\pi",
        'ρ' => "\\rho",
        'σ' => "\\sigma",
        'τ' => "\\tau",
        'φ' => "\\phi",
        'χ' => "\\chi",
        'ψ' => "\\psi",
        'ω' => "\\omega",
        'Γ' => "\\Gamma",
        'Δ' => "\\Delta",
        'Λ' => "\\Lambda",
        'Σ' => "\\Sigma",
        'Φ' => "\\Phi",
        'Ω' => "\\Omega",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latex_escapes_and_stays_ascii() {
        let t = latex("mu falls by exp(−h·H), σ_u = 5 % & {x} ~ 10°");
        assert!(t.is_ascii(), "{t}");
        assert_eq!(
            t,
            "mu falls by exp($-$h$\\cdot$H), $\\sigma_{u}$ = 5 \\% \\& \\{x\\} \\textasciitilde{} 10$^\\circ$"
        );
    }
}
