//! Puts the RP2040's `memory.x` (at the workspace root) on the linker's search path, and only
//! when building for the Pico's target (thumbv6m-none-eabi). Every other target — the host, and
//! the thumbv7m QEMU firmware with its own memory layout — gets nothing from this script.
//!
//! The link arguments themselves (`link.x`, `link-rp.x`, `defmt.x`, `--nmagic`) live in
//! `.cargo/config.toml` under `[target.thumbv6m-none-eabi]`, not here.

use std::env;
use std::fs;
use std::path::PathBuf;

/// The one target the RP2040 board binary is built for.
const BOARD_TARGET: &str = "thumbv6m-none-eabi";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let target = env::var("TARGET").expect("cargo sets TARGET for build scripts");
    if target != BOARD_TARGET {
        return;
    }

    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let memory_x = manifest_dir.join("..").join("memory.x");
    println!("cargo:rerun-if-changed={}", memory_x.display());
    let layout =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));

    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::write(out.join("memory.x"), layout).expect("cannot write memory.x to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
}
