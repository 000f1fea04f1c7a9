//! Startup without cortex-m-rt (see build.rs for why): the exception vector table and a reset
//! handler that paints the stack, zeroes `.bss`, copies `.data` from flash and calls
//! `qemu_fw_main`; and [`ram_usage`], the stack's high-water mark read back from the paint. The
//! symbols come from `qemu-lm3s6965evb.x`.

/// What the reset handler fills the stack with (must match the `ldr r2` below).
const PAINT: u32 = 0x5A5A_C3C3;

core::arch::global_asm!(
    ".section .text.qemu_fw_reset,\"ax\",%progbits",
    ".global qemu_fw_reset",
    ".type qemu_fw_reset,%function",
    ".thumb_func",
    "qemu_fw_reset:",
    // Paint the stack up to the initial stack pointer (nothing has been pushed yet).
    "    ldr r0, =_stack_bottom",
    "    mov r1, sp",
    "    ldr r2, =0x5A5AC3C3",
    "4:  cmp r0, r1",
    "    bhs 5f",
    "    stm r0!, {{r2}}",
    "    b 4b",
    "5:  ldr r0, =__sbss",
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
    static _stack_bottom: u32;
    static _stack_top: u32;
    static __sdata: u32;
    static __euninit: u32;
}

/// RAM use, bytes.
pub struct RamUsage {
    /// Deepest the stack has been since reset (the painted words it overwrote).
    pub stack_used: usize,
    /// The stack's size (`_stack_size` in the linker script).
    pub stack_size: usize,
    /// `.data`, `.bss` and `.uninit`: the executor's task (with the plant and the rig in its
    /// future), the time driver's queue, ...
    pub statics: usize,
}

/// The stack's high-water mark so far (scanning up from the bottom for the first word that is
/// not the paint) and the size of the statics.
pub fn ram_usage() -> RamUsage {
    // SAFETY: only the addresses of the linker's symbols are taken; the words between
    // `_stack_bottom` and the current stack pointer are plain RAM that nothing else uses, and
    // the scan stops at the first overwritten word, which is below the live stack.
    unsafe {
        let bottom = core::ptr::addr_of!(_stack_bottom);
        let top = core::ptr::addr_of!(_stack_top);
        let mut p = bottom;
        while p < top && core::ptr::read_volatile(p) == PAINT {
            p = p.add(1);
        }
        RamUsage {
            stack_used: top as usize - p as usize,
            stack_size: top as usize - bottom as usize,
            statics: core::ptr::addr_of!(__euninit) as usize
                - core::ptr::addr_of!(__sdata) as usize,
        }
    }
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
