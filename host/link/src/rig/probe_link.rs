//! The board through a debug probe: attach to the running firmware (never flash, never reset),
//! write command lines into its RTT down channel 0, read its defmt up-channel 0 and decode it
//! with the same decoder `capstan log` uses.

use super::link::{LinkError, RigLink};
use crate::decoder::{Decoder, Located};
use crate::frame::Event;
use crate::probe::{attach, Connection, ProbeError, ProbeOptions};
use crate::seq::SeqEvent;
use crate::Firmware;
use std::path::Path;
use std::time::{Duration, Instant};

/// The RTT down channel the firmware reads its command lines from.
pub const COMMAND_CHANNEL: usize = 0;

/// How long a command line may wait for room in the down channel's buffer.
const WRITE_WITHIN: Duration = Duration::from_secs(1);

/// At most this long spent skipping what the up-channel held before we attached.
const DRAIN_FOR: Duration = Duration::from_millis(500);

/// Why the board's command line could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The board could not be reached.
    #[error(transparent)]
    Probe(#[from] ProbeError),
    /// The firmware has no RTT down channel.
    #[error(
        "this firmware has no RTT down channel: rebuild it from this repository (cargo build \
         --release -p capstan-board --target thumbv6m-none-eabi) and flash it"
    )]
    NoDownChannel,
    /// Reading what the up-channel held before now failed.
    #[error("lost the probe: {0}")]
    Lost(ProbeError),
}

/// A board reached through a debug probe.
pub struct ProbeLink<'f> {
    conn: Connection,
    decoder: Decoder<'f>,
    buf: Vec<u8>,
}

/// Attach to the firmware running on the board (`opts.flash` is ignored: never flashed), find
/// its command channel, and skip what its log held before now.
pub fn open<'f>(
    fw: &'f Firmware,
    elf: &Path,
    mut opts: ProbeOptions,
) -> Result<ProbeLink<'f>, OpenError> {
    opts.flash = false;
    // Never flashed: nothing to say.
    let mut conn = attach(elf, &opts, &mut |_| {})?;
    if conn.down_buffer_size(COMMAND_CHANNEL).is_none() {
        return Err(OpenError::NoDownChannel);
    }
    let mut link = ProbeLink {
        conn,
        decoder: Decoder::new(fw),
        buf: vec![0; 16 * 1024],
    };
    link.drain()?;
    Ok(link)
}

impl ProbeLink<'_> {
    /// Read and drop what the up-channel holds: records logged before this command (a stale
    /// reply must not be taken for the answer). Decoded, so the framing is in step.
    fn drain(&mut self) -> Result<(), OpenError> {
        let until = Instant::now() + DRAIN_FOR;
        while Instant::now() < until {
            if self.read().map_err(OpenError::Lost)?.is_none() {
                break;
            }
        }
        Ok(())
    }

    /// One read of the up-channel, decoded (`None`: nothing was there).
    fn read(&mut self) -> Result<Option<Vec<Event>>, ProbeError> {
        let n = self.conn.read_up(&mut self.buf)?;
        if n == 0 {
            return Ok(None);
        }
        let (mut located, mut bad) = (Vec::new(), Vec::new());
        self.decoder.push(&self.buf[..n], &mut located, &mut bad);
        Ok(Some(located.into_iter().flat_map(with_gaps).collect()))
    }
}

/// An event, preceded by a note when records were lost before it.
fn with_gaps(l: Located) -> Vec<Event> {
    let mut out = Vec::new();
    if let Some(SeqEvent::Gap(g)) = &l.seq {
        out.push(Event::Message {
            level: String::new(),
            text: format!(
                "capstan rig: {} record(s) lost after seq {} (RTT buffer full, or another \
                 reader took them)",
                g.missing, g.after_seq
            ),
        });
    }
    out.push(l.event);
    out
}

impl RigLink for ProbeLink<'_> {
    fn send_line(&mut self, line: &str) -> Result<(), LinkError> {
        let bytes = format!("{line}\n").into_bytes();
        let mut sent = 0;
        let until = Instant::now() + WRITE_WITHIN;
        while sent < bytes.len() {
            sent += (self.conn.write_down(COMMAND_CHANNEL, &bytes[sent..]))
                .map_err(LinkError::broken)?;
            if sent < bytes.len() {
                if Instant::now() >= until {
                    return Err(LinkError::broken(format!(
                        "the board did not take the command line within {} s (its RTT down \
                         buffer stayed full): is the firmware running?",
                        WRITE_WITHIN.as_secs()
                    )));
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        Ok(())
    }

    fn poll(&mut self, timeout: Duration) -> Result<Vec<Event>, LinkError> {
        let until = Instant::now() + timeout;
        loop {
            let read = (self.read()).map_err(|e| LinkError::broken(OpenError::Lost(e)))?;
            if let Some(events) = read.filter(|e| !e.is_empty()) {
                return Ok(events);
            }
            if Instant::now() >= until {
                return Ok(Vec::new());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}
