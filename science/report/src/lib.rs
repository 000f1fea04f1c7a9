//! The outputs of `capstan analyze`: `metrics.json`, `predictions.csv` and a self-contained
//! `report.html` (inline SVG figures, no external resources), from the engine's analysis
//! (`capstan_engine::analysis`).
//!
//! * [`metrics`]: `metrics.json`, written and read back; [`files`]: `predictions.csv`.
//! * [`html`]: the page and its sections; [`tables`]: its tables; [`cells`]: the text in them
//!   (numbers or a dash, escaped text).
//! * [`headline`]: the plain headline; [`parameters`]: the one parameter table;
//! * [`table_files`]: the tables as CSV and LaTeX files for a paper ([`tex_layout`]: their
//!   layout for an 85 mm column or the 170 mm page; [`latex_text`]: the words as LaTeX);
//! * [`next`]: the "Next experiment" section (from `capstan plan`);
//! * [`tracking`]: the report of a force-control session (how the rig held its T2 target);
//! * [`context`]: provenance and the thesis comparison; [`export`]: the figure files;
//!   [`stamp`]: the provenance inside each figure file (SVG, PNG, PDF);
//! * [`figures`]: the figures; [`plot`]: their charts (panels and bar charts, drawn by
//!   `plotters`).

pub mod cells;
pub mod check;
pub mod components;
pub mod context;
pub mod discovered;
pub mod error;
pub mod export;
pub mod figures;
pub mod files;
pub mod headline;
pub mod html;
pub mod latex_text;
pub mod metrics;
pub mod next;
pub mod parameters;
pub mod plot;
pub mod stamp;
pub mod table_files;
pub mod tables;
pub mod tex_layout;
pub mod tracking;
pub mod trends;

pub use capstan_engine::analysis::closed_loop::SimCurve;
pub use context::{apply_thesis_choice, Context, ThesisComparison};
pub use error::{FigureError, FileCheckError};
pub use export::{figure_files, FigureOptions, Format};
pub use files::write_predictions_csv;
pub use html::report_html;
pub use metrics::{read_and_validate, Metrics, MetricsError};
