//! Logging shim: human-readable messages go to defmt on bare metal and vanish on the host,
//! where the structured [`crate::record::Record`]s reach a [`crate::record::LogSink`] instead.
#![allow(unused_macros)]

macro_rules! info {
    ($($arg:tt)*) => {{
        #[cfg(target_os = "none")]
        ::defmt::info!($($arg)*);
    }};
}

macro_rules! warn {
    ($($arg:tt)*) => {{
        #[cfg(target_os = "none")]
        ::defmt::warn!($($arg)*);
    }};
}
