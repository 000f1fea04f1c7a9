//! Why a figure or its files could not be made ([`FigureError`]), or a written figure file
//! does not read as one ([`FileCheckError`]).

/// A result whose error is a [`FigureError`].
pub type Result<T, E = FigureError> = std::result::Result<T, E>;

/// Why a figure, or one of its files, could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// plotters could not draw a chart (its message).
    #[error(transparent)]
    Draw(#[from] plotters::drawing::DrawingAreaErrorKind<std::io::Error>),
    /// `--figures` names a format other than svg, png and pdf.
    #[error("--figures {list}: unknown format {format:?} (svg, png or pdf)")]
    UnknownFormat {
        /// The list given.
        list: String,
        /// The unknown format.
        format: String,
    },
    /// `--figures` names no format.
    #[error("--figures {0:?}: name at least one of svg, png, pdf")]
    NoFormat(String),
    /// `--width-mm` outside 40 to 400 mm.
    #[error("--width-mm {0}: must be 40 to 400 (85 for a journal column, 170 for a page)")]
    Width(f64),
    /// `--font-pt` outside 4 to 24 pt.
    #[error("--font-pt {0}: must be 4 to 24")]
    FontPt(f64),
    /// usvg could not parse a figure's SVG.
    #[error("the figure's SVG does not parse")]
    Svg(#[source] resvg::usvg::Error),
    /// The PNG would exceed what tiny-skia can allocate.
    #[error("the figure is too large for a PNG")]
    TooLarge,
    /// The PNG encoder failed.
    #[error("cannot encode the PNG")]
    PngEncode(#[source] png::EncodingError),
    /// svg2pdf failed (its message).
    #[error("cannot make the PDF: {0}")]
    Pdf(String),
    /// A renderer thread panicked.
    #[error("a figure's renderer panicked")]
    Panicked,
    /// A PNG file does not decode.
    #[error("the PNG does not decode")]
    PngDecode(#[source] Box<dyn std::error::Error + Send + Sync>),
}

/// Why a written figure file does not read as one (the checks of [`crate::check`]).
#[derive(Debug, thiserror::Error)]
pub enum FileCheckError {
    /// The SVG does not parse.
    #[error("the figure's SVG does not parse")]
    Svg(#[source] resvg::usvg::Error),
    /// The SVG's root lacks a width or height attribute.
    #[error("no {0} attribute")]
    NoAttribute(&'static str),
    /// A width or height not in mm.
    #[error("{name}={value:?} is not in mm")]
    NotMm {
        /// `width` or `height`.
        name: &'static str,
        /// The attribute's value.
        value: String,
    },
    /// A width or height in mm that is not a number.
    #[error("{name}={value:?}")]
    NotNumber {
        /// `width` or `height`.
        name: &'static str,
        /// The attribute's value.
        value: String,
        /// The parser's reason.
        source: std::num::ParseFloatError,
    },
    /// The PNG does not decode.
    #[error("the PNG does not decode")]
    Png(#[source] png::DecodingError),
    /// The PDF has no `/MediaBox`.
    #[error("no /MediaBox")]
    NoMediaBox,
    /// A `/MediaBox` without its `[...]`.
    #[error("a /MediaBox without its numbers")]
    MediaBoxEmpty,
    /// A `/MediaBox` with something else than numbers.
    #[error("a /MediaBox that is not numbers")]
    MediaBoxNotNumbers(#[source] std::num::ParseFloatError),
    /// A `/MediaBox` of another count than 4 numbers.
    #[error("a /MediaBox of {0} numbers")]
    MediaBoxCount(usize),
}
