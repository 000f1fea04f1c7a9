//! The outputs of `capstan analyze`: `metrics.json`, `predictions.csv` and a self-contained
//! `report.html` (inline SVG figures, no external resources), from the engine's analysis
//! (`capstan_engine::analysis`).
//!
//! * [`files`]: `metrics.json` and `predictions.csv`.
//! * [`html`]: the page and its sections; [`tables`]: its tables; [`cells`]: the text in them
//!   (numbers or a dash, escaped text).
//! * [`figures`]: the figures; [`plot`]: their charts (panels and bar charts, drawn by
//!   `plotters`).

pub mod cells;
pub mod discovered;
pub mod figures;
pub mod files;
pub mod html;
pub mod plot;
pub mod tables;

pub use capstan_engine::analysis::closed_loop::SimCurve;
pub use files::{metrics_json, write_predictions_csv};
pub use html::report_html;
