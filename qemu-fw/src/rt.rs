//! Startup without cortex-m-rt (see build.rs for why): the exception vector table and a reset
//! handler that zeroes `.bss`, copies `.data` from flash and calls `qemu_fw_main`. The symbols
//! come from `qemu-mps2-an385.x`.

core::arch::global_asm!(
    ".section .text.qemu_fw_reset,\"ax\",%progbits",
    ".global qemu_fw_reset",
    ".type qemu_fw_reset,%function",
    ".thumb_func",
    "qemu_fw_reset:",
    "    ldr r0, =__sbss",
    "    ldr r1, =__ebss",
    "    movs r2, #0",
    "0:  cmp r0, r1",
    "    bhs 1f",
    "    stm r0!, {{r2}}",
    "    b 0b",
    "1:  ldr r0, =__sdata",
    "    ldr r1, =__edata",
    "    ldr r2, =__sidata",
    "2:  cmp r0, r1",
    "    bhs 3f",
    "    ldm r2!, {{r3}}",
    "    stm r0!, {{r3}}",
    "    b 2b",
    "3:  bl qemu_fw_main",
    "    udf #0",
    "    .ltorg",
);

extern "C" {
    fn qemu_fw_reset();
}

/// One entry of the vector table: a handler or a reserved word.
#[repr(C)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}

/// Exceptions 1..=15 (entry 0, the initial stack pointer, is written by the linker script).
#[link_section = ".vector_table.exceptions"]
#[no_mangle]
#[used]
pub static QEMU_FW_VECTORS: [Vector; 15] = [
    Vector {
        handler: qemu_fw_reset,
    },
    Vector { handler: fault }, // NMI
    Vector { handler: fault }, // HardFault
    Vector { handler: fault }, // MemManage
    Vector { handler: fault }, // BusFault
    Vector { handler: fault }, // UsageFault
    Vector { reserved: 0 },
    Vector { reserved: 0 },
    Vector { reserved: 0 },
    Vector { reserved: 0 },
    Vector { handler: fault }, // SVCall
    Vector { handler: fault }, // DebugMonitor
    Vector { reserved: 0 },
    Vector { handler: fault }, // PendSV
    Vector {
        handler: crate::time_driver::on_systick,
    },
];

/// Any exception we do not expect: say so and make QEMU exit with a failure.
unsafe extern "C" fn fault() {
    defmt::error!("qemu-fw: unexpected exception");
    crate::exit(3);
}
