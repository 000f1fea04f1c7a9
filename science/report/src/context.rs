//! What the report says about its own making: provenance, and whether the thesis's Table 3
//! comparison belongs in it.

use capstan_data::Provenance;
use capstan_engine::analysis::Analysis;

/// Whether the thesis's Table 3 is compared, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ThesisComparison {
    /// Shown in the report, `metrics.json` and the figures.
    pub shown: bool,
    /// Why (the data are the thesis's by their SHA-256, or it was asked for, or neither).
    pub why: String,
}

impl ThesisComparison {
    /// Shown for the thesis data (recognised by `is_thesis`) or when `asked`.
    pub fn decide(is_thesis: bool, asked: bool) -> ThesisComparison {
        let (shown, why) = match (is_thesis, asked) {
            (true, _) => (true, "the input is the thesis data set (its SHA-256 matches the bundled copy)"),
            (false, true) => (true, "asked for (--thesis-comparison): Table 3's constants were fitted to the thesis rig, not to these data"),
            (false, false) => (false, "not the thesis data set: Table 3's hand-set constants belong to the thesis rig (--thesis-comparison shows them anyway)"),
        };
        ThesisComparison {
            shown,
            why: why.into(),
        }
    }
}

/// The report's context.
#[derive(Clone, Debug)]
pub struct Context {
    /// Program, commit, input hash, command line.
    pub provenance: Provenance,
    /// The thesis comparison.
    pub thesis: ThesisComparison,
    /// Figure files and their size.
    pub figures: crate::export::FigureOptions,
}

/// Drop the thesis's Table 3 from an analysis (its model row, its per-angle R² and its
/// predictions) when the comparison is not shown.
pub fn apply_thesis_choice(a: &mut Analysis, t: &ThesisComparison) {
    if t.shown {
        return;
    }
    a.models.retain(|m| m.name != "thesis");
    a.thesis_per_angle_r2.clear();
    a.pred.thesis.iter_mut().for_each(|v| *v = f64::NAN);
}

impl Context {
    /// A context for a library call (a bench, a test): no input file or command line, the
    /// thesis comparison shown as the analysis computed it, no figure files.
    pub fn library() -> Context {
        Context {
            provenance: Provenance {
                program: format!("capstan-report {}", env!("CARGO_PKG_VERSION")),
                commit: "unknown".into(),
                input: None,
                input_sha256: None,
                command_line: "(library call)".into(),
            },
            thesis: ThesisComparison {
                shown: true,
                why: "a library call: the analysis's own choice".into(),
            },
            figures: crate::export::FigureOptions::default(),
        }
    }
}
