//! The engine's developer traces: `CAPSTAN_FIT_LOG` (every fit: rows, parameters, evaluations,
//! budget and how it ended) and `CAPSTAN_LAPS` (the assessment's laps). The engine prints
//! nothing: a program that wants the traces says where they go ([`set_sink`]; the `capstan`
//! CLI sends them to stderr). Without a sink they are dropped.

use std::fmt::Arguments;
use std::sync::OnceLock;

static SINK: OnceLock<fn(Arguments<'_>)> = OnceLock::new();

/// Send the traces to `sink`, one line per call (without its newline). The first sink set
/// stays.
pub fn set_sink(sink: fn(Arguments<'_>)) {
    let _ = SINK.set(sink);
}

/// One line of trace, to the sink if there is one.
pub(crate) fn line(args: Arguments<'_>) {
    if let Some(sink) = SINK.get() {
        sink(args);
    }
}
