//! Two jobs:
//!
//! 1. The records' defmt macro, from the wire schema (`capstan-wire`): defmt takes its format
//!    string as a literal, so this script writes `wire_record!` into `OUT_DIR/wire_record.rs`
//!    with one arm per record kind, its format string spelled out from the schema's table and
//!    its arguments named after the schema's fields (`defmt_sink.rs` includes it). A field
//!    renamed, added or moved in the schema is then a compile error at the call, not a record
//!    the host reads wrongly.
//! 2. The RP2040 board binary's link set-up, and only when building for the Pico's target
//!    (thumbv6m-none-eabi): the RP2040's `memory.x` (at the workspace root) goes on the
//!    linker's search path, and the link arguments (`--nmagic`, cortex-m-rt's `link.x`,
//!    embassy-rp's `link-rp.x` with the boot2 section, defmt's `defmt.x`) are given to the
//!    binary only, as embassy's own examples do. They are not `rustflags` in
//!    `.cargo/config.toml`: a `RUSTFLAGS` in the environment (common in CI) replaces config
//!    rustflags and would drop them silently. Every other target — the host, and the thumbv7m
//!    QEMU firmware with its own memory layout — gets no link arguments from this script.

use capstan_wire::records::Part;
use capstan_wire::settings::SETTINGS;
use capstan_wire::{RecordKind, Setting, Value};
use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::PathBuf;

/// The one target the RP2040 board binary is built for.
const BOARD_TARGET: &str = "thumbv6m-none-eabi";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::write(out.join("wire_record.rs"), wire_record_macro())
        .expect("cannot write wire_record.rs to OUT_DIR");

    let target = env::var("TARGET").expect("cargo sets TARGET for build scripts");
    if target != BOARD_TARGET {
        return;
    }
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let memory_x = manifest_dir.join("..").join("memory.x");
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

/// `wire_record!(WORD: field = EXPR, ...)`: one arm per record kind. A settings block is one
/// argument, `settings = [u32; SETTINGS]` (the settings' bits in wire order, as
/// `Settings::fields` gives them), spelled out into its fields here.
fn wire_record_macro() -> String {
    let mut m = String::new();
    m.push_str(
        "// Written by firmware/build.rs from capstan-wire's record table: do not edit.\n\
         /// One record as one defmt frame, its format string from the wire schema:\n\
         /// `wire_record!(WORD: seq = .., FIELD = .., ..., crc = ..)`, every field named, in\n\
         /// wire order; the settings as one `settings = [u32; SETTINGS]`.\n\
         macro_rules! wire_record {\n",
    );
    for kind in RecordKind::ALL {
        let mut params = Vec::new();
        let mut args = Vec::new();
        for part in kind.parts() {
            match part {
                Part::Field(f) => {
                    params.push(format!("{0} = ${0}:expr", f.name));
                    args.push(format!("${}", f.name));
                }
                Part::Settings => {
                    params.push("settings = $settings:expr".to_string());
                    args.extend(Setting::ALL.iter().map(|s| setting_arg(*s)));
                }
            }
        }
        let has_settings = kind.parts().contains(&Part::Settings);
        let bind = if has_settings {
            format!("let s: [u32; {SETTINGS}] = $settings; ")
        } else {
            String::new()
        };
        writeln!(
            m,
            "    ({word}: {params} $(,)?) => {{{{ {bind}::defmt::{level}!(\"{format}\", {args}) }}}};",
            word = kind.word(),
            params = params.join(", "),
            level = kind.level().name(),
            format = kind.format(),
            args = args.join(", "),
        )
        .unwrap();
    }
    m.push_str("}\n");
    m
}

/// A setting's argument, from its bits `s[i]`, at its wire type.
fn setting_arg(s: Setting) -> String {
    let i = s.index();
    match s.value() {
        Value::Code => format!("s[{i}] as u8"),
        Value::Whole => format!("s[{i}]"),
        Value::Real => format!("f32::from_bits(s[{i}])"),
    }
}
