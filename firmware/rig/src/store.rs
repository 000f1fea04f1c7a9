//! The settings kept in flash across resets, on any `embedded-storage-async` NOR flash: the
//! RP2040's (embassy-rp) on the board, a RAM flash in the simulator.
//!
//! `sequential-storage` does the flash work: a key-value map over a few erase pages, each item
//! CRC-checked, wear-levelled, and safe against a reset in the middle of a write. It skips an
//! item whose CRC fails and returns the newest good one, which on its own would bring back an
//! *older* calibration without a word. So each save also stores a generation counter under a
//! second key, after the settings: at load, settings older than the newest generation mean the
//! newest settings were lost, and the rig falls back to its defaults and says so, rather than
//! run with values the operator replaced.
//!
//! The runner sees a store only through [`SettingsFlash`] (no flash: `()`).

use crate::record::{LogSink, SettingsSource};
use crate::rig::Rig;
use crate::settings::{Settings, SETTINGS_BYTES};
use core::ops::Range;
use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

/// Map key of the settings record.
const SETTINGS_KEY: u8 = 1;
/// Map key of the generation counter.
const GENERATION_KEY: u8 = 2;
/// Work buffer: the longest item (key + settings), rounded up to any flash's word.
const BUFFER_BYTES: usize = 256;
const _: () = assert!(SETTINGS_BYTES < BUFFER_BYTES);

/// The flash range is not whole erase pages, or fewer than two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct BadRange;

/// A write to the flash failed; what was stored before is kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct StoreFailed;

type Map<F> = MapStorage<u8, F, Cache<Uncached, Uncached, Uncached, u8>>;

/// Where the settings are kept ([`SettingsStore`] on a flash).
#[allow(async_fn_in_trait)]
pub trait SettingsFlash {
    /// Keep `settings`; false if the write failed (the stored settings are then unchanged).
    async fn save(&mut self, settings: &Settings) -> bool;
}

/// No flash: nothing can be stored.
impl SettingsFlash for () {
    async fn save(&mut self, _: &Settings) -> bool {
        false
    }
}

impl<F: NorFlash> SettingsFlash for SettingsStore<F> {
    async fn save(&mut self, settings: &Settings) -> bool {
        SettingsStore::save(self, settings).await.is_ok()
    }
}

/// The settings record in a flash range.
pub struct SettingsStore<F: NorFlash> {
    map: Map<F>,
    /// Generation of the newest save seen (0: none).
    generation: u32,
    /// The flash could not be read: its generations are unknown, so the first save erases it.
    erase_first: bool,
    buf: [u8; BUFFER_BYTES],
}

impl<F: NorFlash> SettingsStore<F> {
    /// A store on `range` of `flash` (byte offsets, whole erase pages, at least two).
    pub fn new(flash: F, range: Range<u32>) -> Result<Self, BadRange> {
        let config = MapConfig::try_new(range).map_err(|_| BadRange)?;
        Ok(SettingsStore {
            map: MapStorage::new(flash, config, Cache::new_uncached()),
            generation: 0,
            erase_first: false,
            buf: [0; BUFFER_BYTES],
        })
    }

    /// The stored settings, or why there are none to use.
    pub async fn load(&mut self) -> Result<Settings, SettingsSource> {
        let read = self.read().await;
        // Unreadable: no generation is known, so a save starting from 0 could lose to an older
        // record with a higher one. The first save starts from an erased range instead.
        self.erase_first = read == Err(SettingsSource::DefaultsFlashError);
        read
    }

    async fn read(&mut self) -> Result<Settings, SettingsSource> {
        let generation = self
            .map
            .fetch_item::<u32>(&mut self.buf, &GENERATION_KEY)
            .await
            .map_err(|_| SettingsSource::DefaultsFlashError)?;
        self.generation = generation.unwrap_or(0);
        let bytes = self
            .map
            .fetch_item::<&[u8]>(&mut self.buf, &SETTINGS_KEY)
            .await
            .map_err(|_| SettingsSource::DefaultsFlashError)?;
        let Some(bytes) = bytes else {
            return Err(match generation {
                // A generation without settings: the settings record was lost.
                Some(_) => SettingsSource::DefaultsCorrupt,
                None => SettingsSource::DefaultsNoRecord,
            });
        };
        let (settings, saved_as) =
            Settings::decode(bytes).map_err(|_| SettingsSource::DefaultsInvalid)?;
        if saved_as < self.generation {
            return Err(SettingsSource::DefaultsCorrupt);
        }
        // The generation record itself may be the one lost (its CRC failed): the settings
        // are complete and no older than any generation seen.
        self.generation = saved_as;
        Ok(settings)
    }

    /// At boot, before the servo's first pulse: the stored settings into `rig`, or it keeps
    /// its built-in defaults; either way a `settings` record says which, and why (a warning
    /// too, on the board's log, for defaults). The first pulse is then the stored rest.
    /// Settings under which the over-force check could not trip are not used
    /// (`DefaultsInvalid`).
    pub async fn load_into(&mut self, rig: &mut Rig, sink: &mut impl LogSink) -> SettingsSource {
        let source = match self.load().await {
            Ok(s) => match rig.use_stored_settings(s) {
                Ok(()) => SettingsSource::Loaded,
                Err(_) => SettingsSource::DefaultsInvalid,
            },
            Err(why) => why,
        };
        rig.report_settings(source, sink);
        source
    }

    /// Keep `settings`: the settings first, then their generation (a reset in between leaves
    /// settings newer than the generation, which load accepts).
    pub async fn save(&mut self, settings: &Settings) -> Result<(), StoreFailed> {
        if self.erase_first {
            self.map.erase_all().await.map_err(|_| StoreFailed)?;
            self.generation = 0;
            self.erase_first = false;
        }
        let generation = self.generation.wrapping_add(1).max(1);
        let bytes = settings.encode(generation);
        self.map
            .store_item(&mut self.buf, &SETTINGS_KEY, &&bytes[..])
            .await
            .map_err(|_| StoreFailed)?;
        self.map
            .store_item(&mut self.buf, &GENERATION_KEY, &generation)
            .await
            .map_err(|_| StoreFailed)?;
        self.generation = generation;
        Ok(())
    }

    /// The flash back (for a test that damages it).
    pub fn into_flash(self) -> F {
        self.map.destroy().0
    }
}
