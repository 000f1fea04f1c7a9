//! Puts this image's own linker script on the link search path, for thumbv7m-none-eabi only.
//!
//! Why not cortex-m-rt's `link.x`: it does `INCLUDE memory.x`, and the linker looks in its
//! current directory (the workspace root, where cargo runs rustc) before any `-L` path. The
//! root holds the RP2040's `memory.x`, so `link.x` would lay this image out for the Pico
//! (checked: the link fails on the vector table's alignment). This crate therefore has its own
//! startup (src/rt.rs) and a script with a name nothing else uses, `qemu-lm3s6965evb.x`.
//!
//! The link arguments (that script and defmt's `defmt.x`) are given here, for this binary
//! only, rather than as `rustflags` in `.cargo/config.toml`: a `RUSTFLAGS` in the environment
//! (common in CI) replaces config rustflags and would silently drop them.

use std::env;
use std::fs;
use std::path::PathBuf;

const SCRIPT: &str = "qemu-lm3s6965evb.x";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed={SCRIPT}");
    if env::var("TARGET").as_deref() != Ok("thumbv7m-none-eabi") {
        return;
    }
    let dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    let script = fs::read(dir.join(SCRIPT)).expect("qemu-fw: cannot read the linker script");
    fs::write(out.join(SCRIPT), script).expect("qemu-fw: cannot write to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
    // No page alignment of the segments in the file: otherwise .data, which starts above the
    // 48 KiB stack, is padded to its address modulo 64 KiB (+48 KiB of zeros in the ELF kept
    // in tests/data).
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-T{SCRIPT}");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
