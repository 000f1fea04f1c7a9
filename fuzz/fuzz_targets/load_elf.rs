//! Any bytes as the firmware ELF (a wrong file, a damaged build): refused with a message or
//! loaded, never a panic.
#![no_main]

use capstan_link::Firmware;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = Firmware::from_elf_bytes(data, "fuzz.elf");
});
