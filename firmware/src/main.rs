//! RP2040 (Raspberry Pi Pico) board binary: wires pins to the rig core. Placeholder until the
//! board wiring lands; on the host this compiles to a stub.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("this is the RP2040 firmware; build it with --target thumbv6m-none-eabi");
}
