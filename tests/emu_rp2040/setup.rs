//! Getting the emulated board going: the tools (node, rp2040js, the two targets), the board
//! image and the bench built by nested cargo invocations, one case run by the harness, and its
//! stream decoded by `capstan log`.

use capstan_emu_bench::Case;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// `CAPSTAN_EMU=full`: every case. Otherwise the fixed slice (`Case::quick`).
pub fn full() -> bool {
    std::env::var("CAPSTAN_EMU").is_ok_and(|v| v == "full")
}

/// The test cannot run here: say why (and pass), except in CI, where it fails.
pub fn unavailable(reason: &str) {
    if in_ci() {
        panic!("the emulated-board test cannot run in CI: {reason}");
    }
    eprintln!("SKIPPED (not a failure outside CI): emulated RP2040 board test: {reason}");
}

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A target directory of its own (a nested cargo cannot take the running one's lock), under
/// the workspace's, so a second build is a no-op.
pub fn work_dir() -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    base.join("emu-rp2040")
}

/// The board image, as loaded into the emulated flash.
pub struct Image {
    pub elf: PathBuf,
    /// Loadable segments in flash: (physical address, file offset, size).
    pub segments: Vec<(u64, u64, u64)>,
    /// `_SEGGER_RTT`, defmt-rtt's control block.
    pub rtt: u64,
    /// `core::panicking::panic`.
    pub panic_fn: u64,
    /// Where the stack starts (its top) and ends, and where the statics begin (`memory.x`).
    pub stack: (u64, u64, u64),
}

pub struct Setup {
    pub node: String,
    pub image: Image,
    pub wasm: PathBuf,
    pub build_time: Duration,
}

/// Once per test binary: check the tools, build the image and the bench.
pub fn setup() -> Result<&'static Setup, String> {
    static SETUP: OnceLock<Result<Setup, String>> = OnceLock::new();
    SETUP.get_or_init(make_setup).as_ref().map_err(Clone::clone)
}

fn make_setup() -> Result<Setup, String> {
    let t0 = Instant::now();
    let node = node_version()?;
    let rp2040js = root().join("sim/emu/node_modules/rp2040js/package.json");
    if !rp2040js.exists() {
        return Err(format!(
            "rp2040js is not installed ({} is missing): run `npm ci --prefix sim/emu` (the version is \
             pinned in sim/emu/package-lock.json)",
            rp2040js.display()
        ));
    }
    // `CAPSTAN_EMU_ELF`: another build of the board image instead (e.g. an earlier
    // firmware's, to see the cases fail on it); otherwise this tree's, built here.
    let elf = match std::env::var_os("CAPSTAN_EMU_ELF") {
        Some(path) => PathBuf::from(path),
        None => cargo_build(
            &[
                "build",
                "--release",
                "-p",
                "capstan-board",
                "--target",
                "thumbv6m-none-eabi",
            ],
            "thumbv6m-none-eabi",
        )?
        .join("thumbv6m-none-eabi/release/capstan-board"),
    };
    // The bench as a WebAssembly module, without its debug info (4 MiB of it).
    let wasm = cargo_build(
        &[
            "rustc",
            "--release",
            "-p",
            "capstan-emu-bench",
            "--target",
            "wasm32-unknown-unknown",
            "--crate-type",
            "cdylib",
            "--",
            "-C",
            "strip=debuginfo",
        ],
        "wasm32-unknown-unknown",
    )?
    .join("wasm32-unknown-unknown/release/capstan_emu_bench.wasm");
    Ok(Setup {
        node,
        image: image(&elf),
        wasm,
        build_time: t0.elapsed(),
    })
}

fn node_version() -> Result<String, String> {
    let out = Command::new("node")
        .arg("--version")
        .output()
        .map_err(|_| {
            "node is not installed (Node.js 18 or later runs rp2040js; Debian/Ubuntu: apt-get \
         install nodejs npm)"
                .to_string()
        })?;
    let v = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let major: u32 = v
        .trim_start_matches('v')
        .split('.')
        .next()
        .and_then(|m| m.parse().ok())
        .unwrap_or(0);
    if major < 18 {
        return Err(format!(
            "node {v} is too old: rp2040js needs Node.js 18 or later"
        ));
    }
    Ok(v)
}

/// Run a nested cargo into [`work_dir`]; `Err` = the target is not installed.
fn cargo_build(args: &[&str], target: &str) -> Result<PathBuf, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let dir = work_dir();
    let out = Command::new(cargo)
        .current_dir(root())
        .args(args)
        .env("CARGO_TARGET_DIR", &dir)
        .output()
        .expect("cannot run cargo");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        if stderr.contains("target may not be installed")
            || stderr.contains("can't find crate for `core`")
            || stderr.contains("can't find crate for `std`")
        {
            return Err(format!(
                "the {target} target is not installed (rustup target add {target})"
            ));
        }
        panic!("cargo {} failed:\n{stderr}", args.join(" "));
    }
    Ok(dir)
}

/// Segments and symbols of the board ELF.
fn image(elf: &Path) -> Image {
    use object::read::elf::{ElfFile32, ProgramHeader};
    use object::{Object, ObjectSymbol};
    let data = std::fs::read(elf).unwrap_or_else(|e| panic!("{}: {e}", elf.display()));
    let file = ElfFile32::<object::Endianness>::parse(&*data).expect("the board image is an ELF");
    let e = file.endian();
    let segments = file
        .elf_program_headers()
        .iter()
        .filter(|ph| ph.p_type(e) == object::elf::PT_LOAD && ph.p_filesz(e) > 0)
        .map(|ph| {
            (
                ph.p_paddr(e) as u64,
                ph.p_offset(e) as u64,
                ph.p_filesz(e) as u64,
            )
        })
        .filter(|&(paddr, _, _)| (0x1000_0000..0x1100_0000).contains(&paddr))
        .collect();
    let symbol = |want: &dyn Fn(&str) -> bool, what: &str| -> u64 {
        file.symbols()
            .find(|s| s.name().is_ok_and(want))
            .unwrap_or_else(|| panic!("the board image has no {what}"))
            .address()
    };
    Image {
        elf: elf.to_path_buf(),
        segments,
        rtt: symbol(&|n| n == "_SEGGER_RTT", "_SEGGER_RTT (defmt-rtt)"),
        // v0 mangling ends with the path; legacy mangling adds a hash.
        panic_fn: symbol(
            &|n| n.ends_with("4core9panicking5panic") || n.contains("4core9panicking5panic17h"),
            "core::panicking::panic",
        ),
        stack: (
            symbol(&|n| n == "_stack_start", "_stack_start"),
            symbol(&|n| n == "_stack_end", "_stack_end"),
            symbol(&|n| n == "__sdata", "__sdata"),
        ),
    }
}

/// What one case produced.
pub struct Emulated {
    pub case: Case,
    pub dir: PathBuf,
    /// `emulation.json`: the harness's summary, with the bench's report under `bench`.
    pub emulation: Value,
    /// `log/summary.json` from `capstan log`.
    pub log: Value,
    pub messages: String,
    /// pairs.csv: (run, step, time_s, t1_n, t2_n).
    pub pairs: Vec<(u32, u32, f64, f64, f64)>,
    /// raw.csv: (run, time_s, t1 counts, t2 counts).
    pub raw: Vec<(u32, f64, u16, u16)>,
    /// faults.csv: (run, 0 for none, time_s, kind).
    pub faults: Vec<(u32, f64, String)>,
    pub wall: Duration,
}

impl Emulated {
    pub fn bench(&self) -> &Value {
        &self.emulation["bench"]
    }
}

/// The message the harness's panic carries, and its source location.
pub const PANIC_MESSAGE: &str = "panic injected by the emulator harness";
pub const PANIC_FILE: &str = "sim/emu/harness.mjs";
pub const PANIC_LINE: u32 = 1;
/// Unused RAM for the message (SRAM bank 5, scratch Y, above everything `memory.x` places).
const PANIC_RAM: u64 = 0x2004_1000;

/// Run `case` on the emulated board and decode its stream.
pub fn emulate(setup: &Setup, case: Case) -> Emulated {
    let dir = work_dir().join("cases").join(case.name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let img = &setup.image;
    let job = json!({
        "case": case.name,
        "elf": img.elf,
        "wasm": setup.wasm,
        "out": dir,
        "segments": img.segments.iter()
            .map(|&(paddr, offset, size)| json!({"paddr": paddr, "offset": offset, "size": size}))
            .collect::<Vec<_>>(),
        "rtt": img.rtt,
        // The board's pins, from the wire schema (the harness has no numbers of its own).
        "pins": capstan_emu_bench::bench::pin_map_json(),
        "panic": {"fn": img.panic_fn, "message": PANIC_MESSAGE, "file": PANIC_FILE,
                  "line": PANIC_LINE, "col": 1, "ram": PANIC_RAM},
        // Boot2 first, as the boot ROM would start it, with the stack the ROM leaves.
        "boot": {"pc": 0x1000_0000u32, "sp": 0x2004_1f00u32},
        "wall_limit_s": 600,
        "emulated_limit_s": 200,
        // The host's stall of the log, emulated µs since power-up.
        "rtt_stall": case.rtt_stall_us.map(|(a, b)| [a, b]),
        // The host's command lines, written into RTT down channel 0 when due.
        "commands": case.commands.iter()
            .map(|c| json!({"at_s": c.at_us as f64 / 1e6, "line": c.line}))
            .collect::<Vec<_>>(),
    });
    let job_path = dir.join("job.json");
    std::fs::write(&job_path, serde_json::to_vec_pretty(&job).unwrap()).unwrap();
    let t0 = Instant::now();
    let out = Command::new("node")
        .arg(root().join("sim/emu/harness.mjs"))
        .arg(&job_path)
        .output()
        .expect("cannot run node");
    let wall = t0.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprint!("{stderr}");
    assert!(
        out.status.success(),
        "the harness failed on case {} ({}):\n{stderr}",
        case.name,
        out.status
    );
    let emulation = read_json(&dir.join("emulation.json"));
    let log_dir = dir.join("log");
    // Every frame whole and no record lost; a run that a chip fault cut short never
    // completes, a case without a press has no run, a host that stops reading loses records
    // and a press late in the case leaves its run unfinished, which `--strict` would refuse on
    // its own (checked from summary.json below).
    // A run a fault ends (an injected fault, a load at the tare) is cut short, not complete.
    let strict = case.strict_log.then_some("--strict");
    // Those other cases may end with no complete run (a fault at boot, no press): their
    // session is kept all the same, which `log` does only when asked.
    let allow_empty = strict.is_none().then_some("--allow-empty");
    let log = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(["log", "--quiet"])
        .args(strict)
        .args(allow_empty)
        .arg("--elf")
        .arg(&img.elf)
        .arg("--from")
        .arg(dir.join("stream.defmt"))
        .arg("--out")
        .arg(&log_dir)
        .args(["--wrap-deg", &case.cord.wrap_deg.to_string()])
        .args(["--diameter-mm", &case.diameter_mm().to_string()])
        .output()
        .expect("cannot run capstan");
    assert!(
        log.status.success(),
        "capstan log failed on case {}:\n{}",
        case.name,
        String::from_utf8_lossy(&log.stderr)
    );
    let summary = read_json(&log_dir.join("summary.json"));
    if case.rtt_stall_us.is_none() {
        assert_eq!(summary["bad_frames"], 0, "case {}: {summary}", case.name);
        assert_eq!(
            summary["missing_records"], 0,
            "case {}: {summary}",
            case.name
        );
    }
    let csv = |name: &str| -> Vec<Vec<String>> {
        std::fs::read_to_string(log_dir.join(name))
            .unwrap_or_default()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    };
    let pairs = csv("pairs.csv")
        .iter()
        .map(|c| {
            (
                c[3].parse().unwrap(),
                c[4].parse().unwrap(),
                c[5].parse().unwrap(),
                c[6].parse().unwrap(),
                c[7].parse().unwrap(),
            )
        })
        .collect();
    let raw = csv("raw.csv")
        .iter()
        .map(|c| {
            (
                c[0].parse().unwrap(),
                c[2].parse().unwrap(),
                c[3].parse().unwrap(),
                c[4].parse().unwrap(),
            )
        })
        .collect();
    // (A fault outside a run, latched at boot or while idle, has no run: 0 here.)
    let faults = csv("faults.csv")
        .iter()
        .map(|c| {
            (
                c[0].parse().unwrap_or(0),
                c[2].parse().unwrap(),
                c[3].clone(),
            )
        })
        .collect();
    Emulated {
        log: read_json(&log_dir.join("summary.json")),
        messages: std::fs::read_to_string(log_dir.join("messages.txt")).unwrap_or_default(),
        case,
        dir,
        emulation,
        pairs,
        raw,
        faults,
        wall,
    }
}

fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
