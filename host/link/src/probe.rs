//! The real board: flash (or attach to) the chip through a debug probe with the probe-rs
//! library, find the firmware's RTT control block, and read the defmt up-channel (`capstan
//! log` feeds it to its session until Ctrl-C, a limit, or the probe goes away). `capstan rig`
//! attaches the same way (never flashing) and also writes command lines into the RTT down
//! channel. What is worth saying meanwhile (flashing, the channel read) goes to the caller's
//! `say`.
//!
//! The RTT channel stays in the firmware's mode (never block, drop what does not fit). The
//! rig's sample loop must not stall on a slow host; a record that is dropped instead shows up
//! as a sequence gap in the summary.

use anyhow::{anyhow, bail, Context};
use probe_rs::flashing::{DownloadOptions, ElfLoader, ElfOptions};
use probe_rs::probe::list::Lister;
use probe_rs::probe::DebugProbeSelector;
use probe_rs::rtt::{find_rtt_control_block_in_raw_file, try_attach_to_rtt, Rtt, ScanRegion};
use probe_rs::{Permissions, Session};
use std::path::Path;
use std::time::{Duration, Instant};

/// How to reach the board.
#[derive(Clone, Debug)]
pub struct ProbeOptions {
    /// probe-rs chip name (`RP2040`).
    pub chip: String,
    /// `VID:PID[:SERIAL]` of the probe, if more than one is plugged in.
    pub probe: Option<String>,
    /// Flash the ELF and reset before logging (otherwise attach to what is running).
    pub flash: bool,
    /// Attach with the reset line held (for a chip that does not answer otherwise).
    pub connect_under_reset: bool,
    /// SWD clock, kHz.
    pub speed_khz: Option<u32>,
    /// RTT up-channel carrying defmt.
    pub rtt_channel: usize,
    /// How long to wait for the firmware to set up RTT.
    pub rtt_timeout: Duration,
}

fn open_session(opts: &ProbeOptions) -> anyhow::Result<(Session, String)> {
    let lister = Lister::new();
    let probes = lister.list_all();
    let probe = match &opts.probe {
        Some(sel) => {
            let selector: DebugProbeSelector = sel
                .parse()
                .map_err(|e| anyhow!("--probe {sel}: expected VID:PID[:SERIAL] ({e})"))?;
            lister
                .open(selector)
                .with_context(|| format!("cannot open the debug probe {sel}"))?
        }
        None => match probes.as_slice() {
            [] => bail!(
                "no debug probe found. Plug in the Pico's debug probe (or a second Pico running \
                 debugprobe) and check USB permissions (Linux: the probe-rs udev rules, see \
                 docs/README-log.md)"
            ),
            [one] => one
                .open()
                .with_context(|| format!("cannot open the debug probe {one}"))?,
            many => {
                let list: Vec<String> = many.iter().map(|p| format!("  {p}")).collect();
                bail!(
                    "{} debug probes found; choose one with --probe VID:PID[:SERIAL]:\n{}",
                    many.len(),
                    list.join("\n")
                )
            }
        },
    };
    let name = probe.get_name();
    let mut probe = probe;
    if let Some(khz) = opts.speed_khz {
        probe
            .set_speed(khz)
            .with_context(|| format!("cannot set the SWD clock of {name} to {khz} kHz"))?;
    }
    let session = if opts.connect_under_reset {
        probe.attach_under_reset(opts.chip.as_str(), Permissions::default())
    } else {
        probe.attach(opts.chip.as_str(), Permissions::default())
    }
    .with_context(|| format!("cannot attach to the {} through {name}", opts.chip))?;
    Ok((session, name))
}

/// A board with the firmware running and its RTT control block found.
pub struct Connection {
    session: Session,
    rtt: Rtt,
    channel: usize,
    /// The probe's name (for messages).
    pub probe_name: String,
}

/// Reach the board: open the probe, attach to the chip, flash the ELF and reset (unless
/// `opts.flash` is off), and find the RTT control block. Every failure here is an error that
/// says what is missing; nothing has been logged yet. Progress goes to `say`, one line each.
pub fn connect(
    elf_path: &Path,
    opts: &ProbeOptions,
    say: &mut dyn FnMut(String),
) -> anyhow::Result<Connection> {
    let mut conn = attach(elf_path, opts, say)?;
    let size = conn.up_buffer_size();
    say(format!(
        "capstan log: reading defmt from RTT channel {} ({size} bytes buffer); Ctrl-C stops and \
         keeps everything",
        conn.channel
    ));
    Ok(conn)
}

/// [`connect`] without a word to `say` unless it flashes: the board reached, its RTT control
/// block found, and its up-channel `opts.rtt_channel` checked to exist.
pub fn attach(
    elf_path: &Path,
    opts: &ProbeOptions,
    say: &mut dyn FnMut(String),
) -> anyhow::Result<Connection> {
    let elf = std::fs::read(elf_path)
        .with_context(|| format!("cannot read the firmware ELF {}", elf_path.display()))?;
    let region = match find_rtt_control_block_in_raw_file(&elf) {
        Ok(Some(addr)) => ScanRegion::Exact(addr),
        Ok(None) => bail!(
            "{} has no `_SEGGER_RTT` symbol: the firmware does not log over RTT (build it from \
             this repository)",
            elf_path.display()
        ),
        Err(e) => bail!("{}: {e}", elf_path.display()),
    };
    let (mut session, probe_name) = open_session(opts)?;
    if opts.flash {
        say(format!(
            "capstan log: flashing {} to the {} through {probe_name}...",
            elf_path.display(),
            opts.chip
        ));
        let t = Instant::now();
        let mut dl = DownloadOptions::default();
        dl.verify = true;
        let loader = ElfLoader(ElfOptions::default());
        probe_rs::flashing::download_file_with_options(&mut session, elf_path, loader, dl)
            .with_context(|| format!("flashing {} failed", elf_path.display()))?;
        say(format!(
            "capstan log: flashed in {:.1} s",
            t.elapsed().as_secs_f64()
        ));
    }
    let rtt = {
        let mut core = session
            .core(0)
            .with_context(|| format!("cannot reach core 0 of the {}", opts.chip))?;
        if opts.flash {
            core.reset()
                .with_context(|| format!("cannot reset the {} after flashing", opts.chip))?;
        }
        try_attach_to_rtt(&mut core, opts.rtt_timeout, &region).with_context(|| {
            format!(
                "no RTT control block on the {} after {:.0} s: is the firmware running, and is \
                 it the ELF given?",
                opts.chip,
                opts.rtt_timeout.as_secs_f64()
            )
        })?
    };
    let mut conn = Connection {
        session,
        rtt,
        channel: opts.rtt_channel,
        probe_name,
    };
    if conn.rtt.up_channel(conn.channel).is_none() {
        bail!(
            "the firmware has no RTT up-channel {} (defmt uses 0)",
            opts.rtt_channel
        );
    }
    Ok(conn)
}

impl Connection {
    fn up_buffer_size(&mut self) -> usize {
        self.rtt
            .up_channel(self.channel)
            .map_or(0, |c| c.buffer_size())
    }

    /// Read what the defmt up-channel holds (0 bytes: nothing yet). An error is a probe or
    /// target that stopped answering.
    pub fn read_up(&mut self, buf: &mut [u8]) -> Result<usize, String> {
        let mut core = self.session.core(0).map_err(|e| e.to_string())?;
        let channel = self
            .rtt
            .up_channel(self.channel)
            .ok_or("the RTT up-channel went away")?;
        channel.read(&mut core, buf).map_err(|e| e.to_string())
    }

    /// The size of down-channel `n`'s buffer, if the firmware has that channel.
    pub fn down_buffer_size(&mut self, n: usize) -> Option<usize> {
        self.rtt.down_channel(n).map(|c| c.buffer_size())
    }

    /// Write `bytes` into down-channel `n`, as much as its buffer takes now; how much it took.
    pub fn write_down(&mut self, n: usize, bytes: &[u8]) -> anyhow::Result<usize> {
        let mut core = self.session.core(0).context("cannot reach core 0")?;
        let channel = self
            .rtt
            .down_channel(n)
            .ok_or_else(|| anyhow!("the firmware has no RTT down channel {n}"))?;
        channel
            .write(&mut core, bytes)
            .with_context(|| format!("cannot write RTT down channel {n}"))
    }
}
