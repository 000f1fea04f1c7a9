//! The records' defmt macro, from the wire schema (`capstan-wire`): defmt takes its format
//! string as a literal, so this script writes `wire_record!` into `OUT_DIR/wire_record.rs`
//! with one arm per record kind, its format string spelled out from the schema's table and
//! its arguments named after the schema's fields (`defmt_sink.rs` includes it). A field
//! renamed, added or moved in the schema is then a compile error at the call, not a record
//! the host reads wrongly. (The board binary's link set-up is `firmware/board/build.rs`.)

use capstan_wire::records::Part;
use capstan_wire::settings::SETTINGS;
use capstan_wire::{RecordKind, Setting, Value};
use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::write(out.join("wire_record.rs"), wire_record_macro())
        .expect("cannot write wire_record.rs to OUT_DIR");
}

/// `wire_record!(WORD: field = EXPR, ...)`: one arm per record kind. A settings block is one
/// argument, `settings = [u32; SETTINGS]` (the settings' bits in wire order, as
/// `Settings::fields` gives them), spelled out into its fields here.
fn wire_record_macro() -> String {
    let mut m = String::new();
    m.push_str(
        "// Written by firmware/rig/build.rs from capstan-wire's record table: do not edit.\n\
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
