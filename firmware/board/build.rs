//! The RP2040 board binary's link set-up, and only when building for the Pico's target
//! (thumbv6m-none-eabi): the RP2040's `memory.x` (beside this file) goes on the linker's search
//! path, and the link arguments (`--nmagic`, cortex-m-rt's `link.x`, embassy-rp's `link-rp.x`
//! with the boot2 section, defmt's `defmt.x`) are given to the binary, as embassy's own
//! examples do. They are not `rustflags` in `.cargo/config.toml`: a `RUSTFLAGS` in the
//! environment (common in CI) replaces config rustflags and would drop them silently. On the
//! host the binary is a stub and nothing is linked specially.

use std::env;
use std::fs;
use std::path::PathBuf;

/// The one target the RP2040 board binary is built for.
const BOARD_TARGET: &str = "thumbv6m-none-eabi";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    let target = env::var("TARGET").expect("cargo sets TARGET for build scripts");
    if target != BOARD_TARGET {
        return;
    }
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let memory_x = manifest_dir.join("memory.x");
    println!("cargo:rerun-if-changed={}", memory_x.display());
    let layout =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    fs::write(out.join("memory.x"), layout).expect("cannot write memory.x to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
    // For the board binary only (the rig core is a library: nothing to link).
    for arg in ["--nmagic", "-Tlink.x", "-Tlink-rp.x", "-Tdefmt.x"] {
        println!("cargo:rustc-link-arg-bins={arg}");
    }
}
