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

/// Why the board could not be reached or read through the probe. `what` says what was being
/// done ("cannot open the debug probe 2e8a:000c", "flashing fw.elf failed" ...); the probe-rs
/// error is its source.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// A probe-rs operation failed.
    #[error("{what}")]
    ProbeRs {
        /// What was being done, in words.
        what: String,
        /// probe-rs's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// `--probe` is not `VID:PID[:SERIAL]`.
    #[error("--probe {given}: expected VID:PID[:SERIAL] ({why})")]
    Selector {
        /// The selector given.
        given: String,
        /// probe-rs's reason.
        why: String,
    },
    /// No probe is plugged in (or none can be seen).
    #[error(
        "no debug probe found. Plug in the Pico's debug probe (or a second Pico running \
         debugprobe) and check USB permissions (Linux: the probe-rs udev rules, see \
         docs/README-log.md)"
    )]
    NoProbe,
    /// Several probes and no `--probe`.
    #[error(
        "{} debug probes found; choose one with --probe VID:PID[:SERIAL]:\n{}",
        probes.len(),
        probes.iter().map(|p| format!("  {p}")).collect::<Vec<_>>().join("\n")
    )]
    SeveralProbes {
        /// The probes found, as probe-rs names them.
        probes: Vec<String>,
    },
    /// The ELF could not be read.
    #[error("cannot read the firmware ELF {}", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The ELF has no RTT control block.
    #[error(
        "{} has no `_SEGGER_RTT` symbol: the firmware does not log over RTT (build it from \
         this repository)",
        path.display()
    )]
    NoRtt {
        /// The file.
        path: std::path::PathBuf,
    },
    /// probe-rs could not search the ELF for the RTT control block (its message).
    #[error("{}: {why}", path.display())]
    RttSymbol {
        /// The file.
        path: std::path::PathBuf,
        /// probe-rs's message.
        why: String,
    },
    /// The firmware has no such RTT up-channel.
    #[error("the firmware has no RTT up-channel {0} (defmt uses 0)")]
    NoUpChannel(usize),
    /// The probe or the target stopped answering while the up-channel was read (probe-rs's
    /// message).
    #[error(transparent)]
    Lost(Box<dyn std::error::Error + Send + Sync>),
    /// The RTT up-channel is gone (the target reset?).
    #[error("the RTT up-channel went away")]
    UpChannelGone,
    /// The firmware has no such RTT down channel.
    #[error("the firmware has no RTT down channel {0}")]
    NoDownChannel(usize),
}

/// A probe-rs failure while doing `what`.
fn probe_rs<E: std::error::Error + Send + Sync + 'static>(
    what: String,
) -> impl FnOnce(E) -> ProbeError {
    move |e| ProbeError::ProbeRs {
        what,
        source: Box::new(e),
    }
}

fn open_session(opts: &ProbeOptions) -> Result<(Session, String), ProbeError> {
    let lister = Lister::new();
    let probes = lister.list_all();
    let probe = match &opts.probe {
        Some(sel) => {
            let selector = sel
                .parse::<DebugProbeSelector>()
                .map_err(|e| ProbeError::Selector {
                    given: sel.clone(),
                    why: e.to_string(),
                })?;
            lister
                .open(selector)
                .map_err(probe_rs(format!("cannot open the debug probe {sel}")))?
        }
        None => match probes.as_slice() {
            [] => return Err(ProbeError::NoProbe),
            [one] => one
                .open()
                .map_err(probe_rs(format!("cannot open the debug probe {one}")))?,
            many => {
                return Err(ProbeError::SeveralProbes {
                    probes: many.iter().map(|p| p.to_string()).collect(),
                })
            }
        },
    };
    let name = probe.get_name();
    let mut probe = probe;
    if let Some(khz) = opts.speed_khz {
        probe.set_speed(khz).map_err(probe_rs(format!(
            "cannot set the SWD clock of {name} to {khz} kHz"
        )))?;
    }
    let session = if opts.connect_under_reset {
        probe.attach_under_reset(opts.chip.as_str(), Permissions::default())
    } else {
        probe.attach(opts.chip.as_str(), Permissions::default())
    }
    .map_err(probe_rs(format!(
        "cannot attach to the {} through {name}",
        opts.chip
    )))?;
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
) -> Result<Connection, ProbeError> {
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
) -> Result<Connection, ProbeError> {
    let elf = std::fs::read(elf_path).map_err(|source| ProbeError::Read {
        path: elf_path.to_path_buf(),
        source,
    })?;
    let region = match find_rtt_control_block_in_raw_file(&elf) {
        Ok(Some(addr)) => ScanRegion::Exact(addr),
        Ok(None) => {
            return Err(ProbeError::NoRtt {
                path: elf_path.to_path_buf(),
            })
        }
        Err(e) => {
            return Err(ProbeError::RttSymbol {
                path: elf_path.to_path_buf(),
                why: e.to_string(),
            })
        }
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
            .map_err(probe_rs(format!("flashing {} failed", elf_path.display())))?;
        say(format!(
            "capstan log: flashed in {:.1} s",
            t.elapsed().as_secs_f64()
        ));
    }
    let rtt = {
        let mut core = session.core(0).map_err(probe_rs(format!(
            "cannot reach core 0 of the {}",
            opts.chip
        )))?;
        if opts.flash {
            core.reset().map_err(probe_rs(format!(
                "cannot reset the {} after flashing",
                opts.chip
            )))?;
        }
        try_attach_to_rtt(&mut core, opts.rtt_timeout, &region).map_err(probe_rs(format!(
            "no RTT control block on the {} after {:.0} s: is the firmware running, and is it \
             the ELF given?",
            opts.chip,
            opts.rtt_timeout.as_secs_f64()
        )))?
    };
    let mut conn = Connection {
        session,
        rtt,
        channel: opts.rtt_channel,
        probe_name,
    };
    if conn.rtt.up_channel(conn.channel).is_none() {
        return Err(ProbeError::NoUpChannel(opts.rtt_channel));
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
    pub fn read_up(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        let mut core = (self.session.core(0)).map_err(|e| ProbeError::Lost(Box::new(e)))?;
        let channel = self
            .rtt
            .up_channel(self.channel)
            .ok_or(ProbeError::UpChannelGone)?;
        channel
            .read(&mut core, buf)
            .map_err(|e| ProbeError::Lost(Box::new(e)))
    }

    /// The size of down-channel `n`'s buffer, if the firmware has that channel.
    pub fn down_buffer_size(&mut self, n: usize) -> Option<usize> {
        self.rtt.down_channel(n).map(|c| c.buffer_size())
    }

    /// Write `bytes` into down-channel `n`, as much as its buffer takes now; how much it took.
    pub fn write_down(&mut self, n: usize, bytes: &[u8]) -> Result<usize, ProbeError> {
        let mut core = (self.session.core(0)).map_err(probe_rs("cannot reach core 0".into()))?;
        let channel = self
            .rtt
            .down_channel(n)
            .ok_or(ProbeError::NoDownChannel(n))?;
        channel
            .write(&mut core, bytes)
            .map_err(probe_rs(format!("cannot write RTT down channel {n}")))
    }
}
