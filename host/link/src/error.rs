//! Why a firmware ELF was refused, or a frame of its stream did not decode. The frame errors
//! are reasons, not locations: the caller knows the frame number and offset
//! ([`crate::BadFrame`]).

use capstan_wire::Prim;

/// Why a format string of the defmt table cannot be decoded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FormatError {
    /// defmt-parser refused it (its message).
    #[error("unparsable format string: {0}")]
    Unparsable(String),
    /// A bitfield's bit range is empty or beyond 128 bits.
    #[error("bad bitfield range")]
    Bitfield,
}

/// Why a rig record's format string does not match this decoder (checked when the ELF loads).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LayoutError {
    /// defmt-parser refused it (its message).
    #[error("unparsable: {0}")]
    Unparsable(String),
    /// A field of a type the records do not use, or with a display hint.
    #[error("field `{0}` has a type this decoder cannot read")]
    FieldType(String),
    /// The arguments are not numbered in order.
    #[error("arguments out of order")]
    OutOfOrder,
    /// A field the schema requires is missing.
    #[error("no field `{0}`")]
    NoField(&'static str),
    /// A field has another wire type than the schema's.
    #[error("field `{field}` is {found:?}, expected {expected:?}")]
    WrongType {
        /// The field.
        field: &'static str,
        /// Its type in the format.
        found: Prim,
        /// The schema's type.
        expected: Prim,
    },
}

/// Why a firmware ELF (or a table given as formats) was refused. `path` names it as given.
#[derive(Debug, thiserror::Error)]
pub enum ElfError {
    /// The file could not be read.
    #[error("cannot read the firmware ELF {path}")]
    Read {
        /// The file.
        path: String,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file is larger than any firmware ELF.
    #[error("{path} is over {mib} MiB: not a firmware ELF")]
    TooLarge {
        /// The file.
        path: String,
        /// The limit, MiB.
        mib: u64,
    },
    /// defmt-decoder panicked reading its table.
    #[error("ELF {path}: defmt-decoder could not read it (it panicked)")]
    DecoderPanicked {
        /// The file.
        path: String,
    },
    /// defmt-decoder or the ELF reader refused it (their message, with its causes).
    #[error("ELF {path}: {why}")]
    Unreadable {
        /// The file.
        path: String,
        /// Their message.
        why: String,
    },
    /// No `.defmt` section.
    #[error(
        "ELF {path} has no defmt table (no `.defmt` section): build the rig firmware with defmt \
         and give the ELF cargo built (not a .bin/.uf2, not stripped)"
    )]
    NoTable {
        /// The file.
        path: String,
    },
    /// defmt's `raw` encoding, which a lost byte would desynchronise.
    #[error(
        "ELF {path}: the firmware uses defmt's `raw` encoding; `capstan log` needs the default \
         rzcobs encoding, which lets a lost byte cost one record instead of the rest of the \
         stream"
    )]
    RawEncoding {
        /// The file.
        path: String,
    },
    /// A log level that is none of trace, debug, info, warn, error ([`crate::Firmware::from_formats`]).
    #[error("{path}: `{level}` is not a log level")]
    Level {
        /// The table's name.
        path: String,
        /// The level given.
        level: String,
    },
    /// The table made of formats did not deserialize ([`crate::Firmware::from_formats`]).
    #[error("{path}: defmt table: {why}")]
    Table {
        /// The table's name.
        path: String,
        /// serde's message.
        why: serde_json::Error,
    },
    /// A rig record's format does not match this decoder.
    #[error(
        "ELF {path}: its `{word}` record does not match this decoder ({why}); format: \
         \"{format}\". Rebuild `capstan` from the same source as the firmware."
    )]
    Record {
        /// The file.
        path: String,
        /// The record's word (`run_start` ...).
        word: String,
        /// What does not match.
        why: LayoutError,
        /// The record's format string.
        format: String,
    },
    /// None of the rig's run records: another firmware.
    #[error(
        "ELF {path} is not the capstan rig firmware: its defmt table has none of the rig's \
         records (run_start, raw, pair, fault, run_end)"
    )]
    NotRig {
        /// The file.
        path: String,
    },
    /// Some of the rig's run records are missing: an older or newer firmware.
    #[error(
        "ELF {path}: the defmt table lacks the rig record(s) {}: is it an older or newer \
         firmware than this `capstan`?",
        missing.join(", ")
    )]
    MissingRecords {
        /// The file.
        path: String,
        /// The missing records' words.
        missing: Vec<&'static str>,
    },
}

/// Why one frame did not decode.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// More bytes than any frame without a separator.
    #[error("{bytes} bytes without a frame separator (longest accepted: {max})")]
    NoSeparator {
        /// Bytes seen.
        bytes: u64,
        /// The longest frame accepted, bytes.
        max: usize,
    },
    /// No firmware table was given to decode with.
    #[error("no firmware table to decode it with")]
    NoFirmware,
    /// The rzCOBS encoding is broken (its reason).
    #[error("not rzCOBS: {0}")]
    NotRzcobs(&'static str),
    /// Shorter than its format index.
    #[error("frame shorter than its 2-byte index")]
    NoIndex,
    /// The table's timestamp format cannot be decoded.
    #[error("timestamp format: {0}")]
    TimestampFormat(FormatError),
    /// The timestamp is malformed.
    #[error("timestamp: {0}")]
    Timestamp(Box<FrameError>),
    /// The format index is not in the table.
    #[error("format index {0} is not in the ELF's defmt table")]
    UnknownIndex(u64),
    /// The frame's format cannot be decoded.
    #[error("format index {index} cannot be decoded: {why}")]
    Undecodable {
        /// The format index.
        index: u64,
        /// Why.
        why: FormatError,
    },
    /// The arguments of a format are malformed.
    #[error("`{format}`: {why}")]
    Arguments {
        /// The format, cut for messages.
        format: String,
        /// What is wrong.
        why: Box<FrameError>,
    },
    /// Bytes other than rzCOBS padding after the arguments.
    #[error("`{format}`: {bytes} bytes left over after the arguments")]
    LeftOver {
        /// The format, cut for messages.
        format: String,
        /// Bytes left.
        bytes: usize,
    },
    /// A nested format's index is a log statement's.
    #[error("nested format index {0} is a log statement")]
    NestedLog(u64),
    /// A nested format's index is not in the table.
    #[error("nested format index {0} is not in the table")]
    NestedUnknown(u64),
    /// A nested format cannot be decoded.
    #[error(transparent)]
    Format(FormatError),
    /// An enum format with more variants than a 16-bit discriminant.
    #[error("enum with too many variants")]
    TooManyVariants,
    /// An enum discriminant past its variants.
    #[error("enum variant {0} out of range")]
    Variant(usize),
    /// Formats nested deeper than the decoder's stack allows.
    #[error("formats nested too deep")]
    TooDeep,
    /// More arguments than any record has.
    #[error("too many arguments")]
    TooManyArguments,
    /// A bool byte other than 0 or 1.
    #[error("bool is neither 0 nor 1")]
    Bool,
    /// A char that is no Unicode scalar value.
    #[error("{0:#x} is not a char")]
    Char(u32),
    /// A string that is not UTF-8.
    #[error("string is not UTF-8")]
    Str,
    /// A slice longer than the decoder accepts.
    #[error("slice of {0} elements")]
    Slice(u64),
    /// A sequence element whose index is not a nested format.
    #[error("sequence element index {0} is not a format")]
    Sequence(u64),
    /// An argument type the check does not know (its defmt-parser name).
    #[error("argument type {0} not handled")]
    Unhandled(String),
    /// The frame ends inside an argument.
    #[error("frame ends inside an argument")]
    Truncated,
    /// A preformatted argument without its 0xff end.
    #[error("unterminated preformatted string")]
    Unterminated,
    /// A preformatted argument that is not UTF-8.
    #[error("preformatted string is not UTF-8")]
    Preformatted,
    /// defmt-decoder panicked on the frame.
    #[error("defmt-decoder panicked on this frame")]
    DecoderPanicked,
    /// defmt-decoder refused the frame (its message).
    #[error("defmt-decoder: {0}")]
    Decoder(String),
    /// A record with another number of values than its layout has fields.
    #[error("`{word}` record with {values} values for {fields} fields")]
    ValueCount {
        /// The record's word.
        word: &'static str,
        /// Values decoded.
        values: usize,
        /// Fields in its layout.
        fields: usize,
    },
    /// A record (its word and sequence number) whose fields are wrong.
    #[error("`{word}` record seq {seq}: {why}")]
    Record {
        /// The record's word.
        word: &'static str,
        /// Its sequence number.
        seq: u32,
        /// What is wrong.
        why: Box<FrameError>,
    },
    /// The record's CRC-32 does not match its fields.
    #[error(
        "checksum mismatch (sent {sent:#010x}, computed {computed:#010x}): the record was \
         corrupted on its way"
    )]
    Checksum {
        /// The CRC the record carries.
        sent: u32,
        /// The CRC of its fields as received.
        computed: u32,
    },
    /// The layout has no such field.
    #[error("no field `{0}`")]
    NoField(String),
    /// The frame has fewer values than the layout.
    #[error("field `{0}` missing from the frame")]
    MissingValue(String),
    /// A value that is not of its field's type (`what`: "an unsigned integer", "an integer",
    /// "a number", "its type").
    #[error("field `{field}`: `{value}` is not {what}")]
    NotOfType {
        /// The field.
        field: String,
        /// The value as decoded.
        value: String,
        /// What it should be.
        what: &'static str,
    },
    /// An integer too large for its field.
    #[error("field `{field}`: {value} does not fit {what}")]
    DoesNotFit {
        /// The field.
        field: String,
        /// The value as decoded.
        value: String,
        /// The field's width ("a byte", "16 bits", "32 bits").
        what: &'static str,
    },
    /// A code the firmware does not know.
    #[error("unknown {what} code {code}")]
    Code {
        /// What the codes are ("fault kind", "step order", or the field).
        what: &'static str,
        /// The code.
        code: u8,
    },
    /// The firmware's record refuses a field's type.
    #[error("field `{0}` is not of its type")]
    FieldType(&'static str),
    /// More values than the record has fields.
    #[error("more fields than the record has")]
    Extra,
}
