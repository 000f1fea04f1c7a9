//! How the LaTeX table files are laid out: for a journal's 85 mm column (241 pt) at
//! `\footnotesize`, as a `tabularx` as wide as the line (`\linewidth`) whose first,
//! descriptive column (`X`, ragged right) wraps. On a narrow line (below
//! [`TEX_WIDE_FROM_PT`], 148 mm: an 85 mm column) each value stands over its interval in one cell; on a
//! wider line (the full 170 mm width, a `table*`) they stand side by side. The file chooses by
//! `\ifdim\linewidth`, so the same file fits both.

/// The line width the narrow layout is made for: an 85 mm journal column.
pub const TEX_TARGET_WIDTH_PT: f64 = 241.0;

/// From this line width on, the wide layout (a value and its interval side by side).
pub const TEX_WIDE_FROM_PT: f64 = 420.0;

/// The column gap (`\tabcolsep`) of the table files.
pub const TEX_TABCOLSEP_PT: f64 = 4.0;

/// The least width the wrapping column keeps (at [`TEX_TARGET_WIDTH_PT`] in the narrow layout,
/// at [`TEX_WIDE_FROM_PT`] in the wide one): the longest word it must hold unbroken,
/// "Eytelwein," of "Euler-Eytelwein, one mu", is 38.5 pt at `\footnotesize`.
pub const TEX_MIN_WRAP_PT: f64 = 40.0;

/// A wrapping fixed-width column (`p`, ragged on the right or left) of `em` ems.
pub fn p_col(em: f64, right: bool) -> String {
    let align = if right { "raggedleft" } else { "raggedright" };
    format!(">{{\\{align}\\arraybackslash}}p{{{em}em}}")
}

/// Opens a table: the font and column gap; the layout chosen by the line width; the
/// `tabularx`, its wrapping first column followed by the `narrow` or the `wide` columns (the
/// column type `Q`). In a cell, `\CapstanPair{a}{b}` is `a` over `b` when narrow, two cells
/// when wide; `\CapstanOver{a}{b}` is `a` over `b` when narrow, `a b` when wide.
pub fn tex_open(narrow: &[String], wide: &[String]) -> String {
    format!(
        "\\begingroup\\footnotesize\\setlength{{\\tabcolsep}}{{{TEX_TABCOLSEP_PT}pt}}%\n\
         \\ifdim\\linewidth<{TEX_WIDE_FROM_PT}pt % a journal column: each value over its interval\n\
         \\def\\CapstanPair#1#2{{#1\\newline #2}}\\def\\CapstanOver#1#2{{#1\\newline #2}}%\n\
         \\newcolumntype{{Q}}{{{}}}%\n\
         \\else % a wider line: side by side\n\
         \\def\\CapstanPair#1#2{{#1 & #2}}\\def\\CapstanOver#1#2{{#1 #2}}%\n\
         \\newcolumntype{{Q}}{{{}}}%\n\
         \\fi\n\
         \\begin{{tabularx}}{{\\linewidth}}{{@{{}}>{{\\raggedright\\arraybackslash}}XQ@{{}}}}\n\\toprule\n",
        narrow.concat(),
        wide.concat()
    )
}

/// Closes what [`tex_open`] opened, with `notes` (LaTeX lines) under the table.
pub fn tex_close(notes: &str) -> String {
    format!("\\bottomrule\n\\end{{tabularx}}\n\n\\par\\smallskip\\scriptsize\n{notes}\\endgroup\n")
}

/// The comment lines a table file opens with: what it is, where it came from, how it is laid
/// out and what it needs.
pub fn tex_header(what: &str, made_by: &str) -> String {
    let ascii: String = made_by
        .chars()
        .map(|c| if c.is_ascii() { c } else { '?' })
        .collect();
    format!(
        "% {what}\n% Made by {ascii}.\n\
         % Laid out for an 85 mm journal column ({TEX_TARGET_WIDTH_PT} pt) at \\footnotesize (its notes \\scriptsize): a tabularx as wide as \\linewidth whose first column wraps, each value over its interval; from a line of {TEX_WIDE_FROM_PT} pt on (the full 170 mm width, a table* float) side by side.\n\
         % Needs \\usepackage{{booktabs,tabularx}}; \\input it inside a table float.\n"
    )
}
