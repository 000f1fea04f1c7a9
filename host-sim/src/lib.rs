//! host-sim: placeholder.
