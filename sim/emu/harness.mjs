// The RP2040 board image on rp2040js, in the rig: the plant (sim/emu/bench, WebAssembly) on its
// pins. Usage: node sim/emu/harness.mjs JOB.json (written by tests/emu_rp2040/setup.rs; see sim/emu/README.md).
//
// The emulated chip runs in its own virtual time (8 ns per cycle at 125 MHz, idle time skipped).
// Everything the rig sees goes through the bench, at the emulator's time in ns:
//   output pins (GP16 servo PWM, GP18 amplifier PWM, GP20 trigger, GP25 LED: job.pins, the
//   wire schema's pin map) -> bench_pin,
//   each ADC conversion -> bench_adc, whose code the ADC returns 2 us later,
//   the operator's button (GP21), the case's chip fault and the end <- bench_deadline/bench_wake,
//   every busy stretch of the core (wake to sleep) -> bench_burst (the loop budget).
// The defmt stream is read from the RTT up-buffer every 1 ms, as a debug probe does, and the
// job's host command lines are written into the RTT down-buffer when due.
// What rp2040js lacks, the harness does, as the hardware would: a UDF (or BKPT) raises a
// HardFault, a watchdog bite or trigger resets the chip (a fresh chip, with the watchdog's
// REASON and SCRATCH registers carried over), and an access just below SRAM (a stack run off
// its bottom, where memory.x puts it) locks the core up, as a Cortex-M0+ whose HardFault cannot
// stack its frame does.
import { RP2040 } from 'rp2040js';
import fs from 'node:fs';
import path from 'node:path';

const job = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
const elf = fs.readFileSync(job.elf);
fs.mkdirSync(job.out, { recursive: true });

// The bench.
const wasm = await WebAssembly.instantiate(fs.readFileSync(job.wasm), {
  env: { bench_log: (ptr, len) => process.stderr.write(text(ptr, len) + '\n') },
});
const B = wasm.instance.exports;
function text(ptr, len) {
  return Buffer.from(B.memory.buffer, ptr, len).toString('utf8');
}
{
  const name = Buffer.from(job.case, 'utf8');
  const at = B.bench_buffer(name.length); // may grow the memory: take its buffer after
  new Uint8Array(B.memory.buffer, at, name.length).set(name);
  if (!B.bench_new()) throw new Error(`emu-bench has no case ${job.case}`);
}
// With a debug probe attached, probe-rs halts the core on HardFault entry (vector catch); the
// clock, the peripherals and the watchdog go on.
const probeAttached = B.bench_probe_attached() !== 0;
const WAKE_BUTTON = 1, WAKE_PANIC = 2, WAKE_STOP = 4, WAKE_STACK_OVERFLOW = 8, WAKE_DEBUGGER = 16;
// Below SRAM nothing is mapped: an access there is a bus fault, and one made by a stack that
// ran off the bottom of SRAM leaves the HardFault no room to stack its frame: lockup.
const BELOW_RAM = 0x1fff0000;
// The board's pins: the wire schema's pin map (capstan-wire), written into the job by the test.
const { servo: SERVO, amp: AMP, trigger: TRIGGER, button: BUTTON, led: LED } = job.pins;
for (const [name, gpio] of Object.entries({ SERVO, AMP, TRIGGER, BUTTON, LED })) {
  if (!Number.isInteger(gpio)) throw new Error(`job.json: no pin ${name.toLowerCase()} in its pins`);
}
// The PWM slices of the servo and the amplifier (the RP2040's: GPIO / 2 mod 8).
const SLICES = [SERVO, AMP].map((gpio) => (gpio >> 1) & 7);
const FUNCSEL_PWM = 4, LOW = 0, HIGH = 1, HARDFAULT = 3;
const WATCHDOG_BASE = 0x40058000, RAM = 0x20000000;
// VREG_AND_CHIP_RESET: rp2040js leaves it unimplemented (every read 0xffffffff: every reset
// flag set). The harness answers its CHIP_RESET register as the chip does: HAD_POR (bit 8)
// from the power-on, kept through the watchdog's resets, which are not chip-level.
const VREG_BASE = 0x40064000, CHIP_RESET = 0x8, HAD_POR = 1 << 8;

// rp2040js's own logger prints every SEV and throws on errors: keep them, quietly.
const warnings = new Map();
const errors = [];
let badAccesses = 0;
const logger = {
  debug() {},
  info() {},
  warn(who, msg) {
    const bad = /(?:undefined|invalid memory) address: ([0-9a-f]+)/i.exec(msg);
    if (bad && parseInt(bad[1], 16) >= BELOW_RAM && parseInt(bad[1], 16) < RAM) {
      if (!lockup) lockup = { t_ns: now(), pc: core.PC, address: parseInt(bad[1], 16), ipsr: core.IPSR };
      halted = true;
      return;
    }
    const key = warnings.size < 100 ? `${who}: ${msg}` : 'other warnings';
    warnings.set(key, (warnings.get(key) ?? 0) + 1);
    if (/invalid|undefined address|not implemented/i.test(msg) && badAccesses++ < 10) errors.push({ t_ns: now(), pc: core.PC, msg: `${who}: ${msg}` });
  },
  error(who, msg) {
    errors.push({ t_ns: now(), msg: `${who}: ${msg}` });
  },
};

const SimulationClock = new RP2040().clock.constructor; // rp2040js's clock, not exported by name
let mcu, core, clock, benchAlarm, benchAlarmAt = -1;
let epoch = 0; // emulator time at which the present chip's clock started (each reset restarts it)
const now = () => epoch + clock.nanos;
const stream = [];
let streamBytes = 0, lastReadBytes = 0;
// Each poll that read bytes: [emulated ns, bytes read so far] (when a record reached the host).
const rttReads = [];
const commands = (job.commands ?? []).map((c) => ({
  at_s: c.at_s,
  line: c.line,
  at_ns: Math.round(c.at_s * 1e9),
  bytes: Buffer.from(c.line + '\n', 'utf8'),
  sent: 0,
  written_ns: null,
}));
let nextCommand = 0;
const resets = [], breaks = [];
// Writes that changed a PWM compare (the servo's slice, the amplifier's): when the firmware
// commanded a pulse width or duty, as opposed to when the pin shows it.
const pwmWrites = [];
let panicInjected = null, stackInjected = null, lockup = null;
let pendingPanic = false, pendingStack = false, pendingBreak = null, pendingReset = false, stop = false;
let halted = false;
// The host's stall of the log (job.rtt_stall): [from, to) ns, and when the firmware put the up
// channel back to non-blocking after the harness set it to block.
const stall = job.rtt_stall ? { from_ns: job.rtt_stall[0] * 1e3, to_ns: job.rtt_stall[1] * 1e3, blocking_set_ns: null, mode_restored_ns: null } : null;
let instructions = 0, cycles = 0;
// The lowest the stack pointer went (before an injected stack overflow): the stack's use.
let minSp = 0xffffffff;

function pwmTickNs(gpio) {
  if (mcu.gpio[gpio].functionSelect !== FUNCSEL_PWM) return 0;
  const div = mcu.pwm.channels[(gpio >> 1) & 7].div;
  return (((div >> 4) & 0xff || 256) + (div & 0xf) / 16) * 1e9 / mcu.clkSys;
}

function syncBench() {
  const t = B.bench_deadline();
  if (t === benchAlarmAt) return;
  benchAlarmAt = t;
  if (t < 0) benchAlarm.cancel();
  else benchAlarm.schedule(Math.max(0, t - now()));
}

function wake() {
  benchAlarmAt = -1;
  const flags = B.bench_wake(now());
  if (flags & WAKE_BUTTON) mcu.gpio[BUTTON].setInputValue(!B.bench_button()); // pull-up; pressed = low
  if (flags & WAKE_PANIC) pendingPanic = true;
  if (flags & WAKE_STACK_OVERFLOW) pendingStack = true;
  if (flags & WAKE_DEBUGGER) debuggerWritesWatchdog();
  if (flags & WAKE_STOP) stop = true;
  syncBench();
}

// The RTT control block (rtt-target sets it up at the start of main, the header after the
// channels and the id's first byte last): its max_up, or 0 while it is not set up.
function rttUpChannels() {
  const base = job.rtt - RAM;
  if (mcu.sram[base] !== 0x53) return 0; // "SEGGER RTT" not written yet (boot)
  return mcu.sramView.getUint32(base + 16, true);
}

// Read the defmt up channel 0 like a probe: bytes from the read to the write offset. During the
// job's stall the host reads nothing, and sets the channel to block when full at its start
// (mode bits of its flags: 2), as `probe-rs run` may.
function pollRtt(final = false) {
  if (rttUpChannels() === 0) return;
  const base = job.rtt - RAM;
  const sv = mcu.sramView;
  const up = base + 24;
  if (stall && !final && now() >= stall.from_ns && now() < stall.to_ns) {
    const flags = sv.getUint32(up + 20, true);
    if (stall.blocking_set_ns === null) {
      sv.setUint32(up + 20, (flags & ~3) | 2, true);
      stall.blocking_set_ns = now();
    } else if (stall.mode_restored_ns === null && (flags & 3) !== 2) {
      stall.mode_restored_ns = now();
    }
    return;
  }
  const buf = sv.getUint32(up + 4, true) - RAM;
  const size = sv.getUint32(up + 8, true);
  const wr = sv.getUint32(up + 12, true);
  let rd = sv.getUint32(up + 16, true);
  if (wr >= size || rd >= size) throw new Error(`bad RTT offsets ${rd} ${wr} of ${size}`);
  while (rd !== wr) {
    const end = wr > rd ? wr : size;
    stream.push(Buffer.from(mcu.sram.subarray(buf + rd, buf + end)));
    streamBytes += end - rd;
    rd = end === size ? 0 : end;
  }
  sv.setUint32(up + 16, rd, true);
  if (streamBytes !== lastReadBytes) {
    rttReads.push([now(), streamBytes]);
    lastReadBytes = streamBytes;
  }
}

// The host's command lines (job.commands), written into RTT down channel 0 like a debug probe
// does once each is due: after the up channels' descriptors, from the write offset, at most
// the free space (one byte stays empty), wrapping at the buffer's size, the write offset
// stored last. What does not fit waits for the next poll.
function writeCommands() {
  const maxUp = rttUpChannels();
  if (maxUp === 0 || nextCommand >= commands.length || commands[nextCommand].at_ns > now()) return;
  const base = job.rtt - RAM;
  const sv = mcu.sramView;
  if (sv.getUint32(base + 20, true) === 0) throw new Error('the RTT control block has no down channel');
  const down = base + 24 + 24 * maxUp;
  const buf = sv.getUint32(down + 4, true) - RAM;
  const size = sv.getUint32(down + 8, true);
  let wr = sv.getUint32(down + 12, true);
  const rd = sv.getUint32(down + 16, true);
  if (wr >= size || rd >= size) throw new Error(`bad RTT down offsets ${rd} ${wr} of ${size}`);
  let free = (rd - wr - 1 + size) % size;
  while (nextCommand < commands.length && commands[nextCommand].at_ns <= now() && free > 0) {
    const c = commands[nextCommand];
    for (; c.sent < c.bytes.length && free > 0; c.sent++, free--) {
      mcu.sram[buf + wr] = c.bytes[c.sent];
      wr = (wr + 1) % size;
    }
    if (c.sent < c.bytes.length) break;
    c.written_ns = now();
    nextCommand++;
  }
  sv.setUint32(down + 12, wr, true);
}

function boot(carried) {
  clock = new SimulationClock();
  mcu = new RP2040(clock);
  core = mcu.core;
  mcu.logger = logger;
  for (const s of job.segments) mcu.flash.set(elf.subarray(s.offset, s.offset + s.size), s.paddr - 0x10000000);
  // No boot ROM: start at boot2, with the stack the ROM would have set.
  core.PC = job.boot.pc;
  core.SP = job.boot.sp;
  const vreg = mcu.findPeripheral(VREG_BASE);
  const readVreg = vreg.readUint32.bind(vreg);
  vreg.readUint32 = (offset) => (offset === CHIP_RESET ? HAD_POR : readVreg(offset));
  const dog = mcu.findPeripheral(WATCHDOG_BASE);
  if (carried) {
    dog.reason = carried.reason;
    dog.scratchData.set(carried.scratch);
  }
  // rp2040js's watchdog sets REASON but does not reset the chip (and its alarm would fire
  // again at the same instant forever): stop it and reset here.
  dog.onWatchdogTrigger = () => {
    dog.alarm.enable = false;
    dog.timer.enable = false;
    pendingReset = true;
  };
  // A UDF or BKPT: rp2040js only reports it; the core takes a HardFault (after this instruction).
  mcu.onBreak = (code) => (pendingBreak = code);
  // The pin's level for the bench: 0 driven low, 1 high, 2 not driven (an input: the board's
  // pull-downs hold it low, and the amplifier's filter discharges through its pull-down).
  for (const gpio of [SERVO, AMP, TRIGGER, LED]) {
    mcu.gpio[gpio].addListener((state) => B.bench_pin(gpio, state === HIGH ? 1 : state === LOW ? 0 : 2, now(), pwmTickNs(gpio)));
  }
  mcu.gpio[BUTTON].setInputValue(!B.bench_button());
  for (const slice of SLICES) {
    const ch = mcu.pwm.channels[slice];
    const write = ch.writeRegister.bind(ch);
    ch.writeRegister = (offset, value) => {
      const before = ch.cc & 0xffff;
      write(offset, value);
      if (offset === 0x0c && (ch.cc & 0xffff) !== before) pwmWrites.push({ t_ns: now(), slice, cc_a: ch.cc & 0xffff });
    };
  }
  let phased = false;
  mcu.adc.onADCRead = (channel) => {
    if (!phased) {
      // The board's first conversion: its sample grid starts here. The host's polls go half a
      // millisecond off it from now on.
      phased = true;
      rtt.schedule(0.5e6);
    }
    const code = B.bench_adc(channel, now());
    syncBench();
    if (code < 0) return; // the case's hang: this conversion never completes
    mcu.adc.channelValues[channel] = code;
    mcu.adc.currentChannel = channel;
    mcu.adc.sampleAlarm.schedule(mcu.adc.sampleTime * 1000);
  };
  const rtt = clock.createAlarm(() => {
    pollRtt();
    writeCommands();
    rtt.schedule(1e6);
  });
  // The host polls every 1 ms, from 1.5 ms after the boot until the board's first
  // conversion, then half a millisecond off the board's sample grid (which starts when the
  // boot is done, ~0.5-1.0 ms), so a line written at a poll is never taken at the edge of a
  // sample (tests/emu_rp2040 maps each line to the sample that took it).
  rtt.schedule(1.5e6);
  benchAlarm = clock.createAlarm(wake);
  benchAlarmAt = -1;
  syncBench();
}

function reset() {
  pendingReset = false;
  pollRtt(true);
  const dog = mcu.findPeripheral(WATCHDOG_BASE);
  const carried = { reason: dog.reason, scratch: Uint32Array.from(dog.scratchData) };
  const t = now();
  // The outputs' registers as the old chip left them (what a panic handler wrote).
  const pins = Object.fromEntries(
    [SERVO, AMP, TRIGGER].map((g) => [g, { funcsel: mcu.gpio[g].functionSelect, out: mcu.gpio[g].outputValue, oe: mcu.gpio[g].outputEnable }]),
  );
  const cc = SLICES.map((slice) => mcu.pwm.channels[slice].cc & 0xffff);
  resets.push({ t_ns: t, reason: carried.reason, scratch0: carried.scratch[0], scratch1: carried.scratch[1], halted, pins, pwm_cc_a: cc });
  halted = false;
  B.bench_reset(t, carried.reason);
  epoch = t;
  boot(carried);
}

// A `panic!("...")` in thread mode, now: the image's core::panicking::panic(msg, &Location),
// with the message and location written into RAM the firmware does not use.
function injectPanic() {
  pendingPanic = false;
  const p = job.panic;
  const enc = (s) => Buffer.from(s, 'utf8');
  const file = enc(p.file), msg = enc(p.message);
  const fileAt = p.ram, msgAt = p.ram + file.length, locAt = (msgAt + msg.length + 3) & ~3;
  mcu.sram.set(file, fileAt - RAM);
  mcu.sram.set(msg, msgAt - RAM);
  const sv = mcu.sramView;
  [fileAt, file.length, p.line, p.col].forEach((v, i) => sv.setUint32(locAt - RAM + 4 * i, v, true));
  panicInjected = { t_ns: now(), interrupted_pc: core.PC, was_waiting: core.waiting };
  core.registers[0] = msgAt;
  core.registers[1] = msg.length;
  core.registers[2] = locAt;
  core.LR = core.PC | 1;
  core.PC = p.fn & ~1;
  core.waiting = false;
  B.bench_panicked(now());
}

// A debugger (probe-rs, an IDE) writes the watchdog's control, now: disabled, and paused while
// the core is halted (CTRL bits 24-26), as a probe may leave it after a session.
let debuggerWrote = null;
function debuggerWritesWatchdog() {
  const dog = mcu.findPeripheral(WATCHDOG_BASE);
  const before = dog.readUint32(0);
  dog.writeUint32(0, (before & ~(1 << 30)) | (7 << 24));
  debuggerWrote = { t_ns: now(), ctrl_before: before >>> 0, ctrl_after: dog.readUint32(0) >>> 0 };
}

// The stack run off the bottom of SRAM, now: SP 16 bytes above it, where memory.x ends the
// image's stack. The core's next pushes (the timer interrupt's frame, a call) fall below it.
function injectStackOverflow() {
  pendingStack = false;
  stackInjected = { t_ns: now(), sp_before: core.SP, pc: core.PC, was_waiting: core.waiting };
  core.SP = RAM + 16;
  B.bench_panicked(now());
}

boot(null);
const wall0 = Date.now();
const wallLimitMs = job.wall_limit_s * 1000;
const emulatedLimitNs = job.emulated_limit_s * 1e9;
let burst = 0, burstStart = 0;
while (!stop) {
  for (let i = 0; i < 200000 && !stop; i++) {
    if (pendingPanic && core.IPSR === 0) injectPanic();
    if (pendingStack && core.IPSR === 0) injectStackOverflow();
    if (core.waiting || halted) {
      if (burst) {
        B.bench_burst(burstStart, burst);
        burst = 0;
      }
      const n = clock.nanosToNextAlarm;
      clock.tick(n > 0 ? n : 8);
    } else {
      if (!burst) burstStart = now();
      const c = core.executeInstruction();
      if (core.SP < minSp && !stackInjected) minSp = core.SP;
      instructions++;
      burst += c;
      cycles += c;
      if (pendingBreak !== null) {
        const pc = core.PC - core.breakRewind;
        breaks.push({ t_ns: now(), pc, code: pendingBreak, ipsr: core.IPSR });
        pendingBreak = null;
        if (core.IPSR === HARDFAULT) throw new Error(`lockup: UDF/BKPT in the HardFault handler at ${pc.toString(16)}`);
        core.PC = pc;
        core.exceptionEntry(HARDFAULT);
        if (probeAttached) halted = true;
      }
      clock.tick(c * 8);
    }
    if (pendingReset) reset();
  }
  if (process.env.EMU_DEBUG) process.stderr.write(`t=${now() / 1e9} instr=${instructions} waiting=${core.waiting} deadline=${benchAlarmAt}\n`);
  if (errors.length) throw new Error(`the emulated chip went wrong: ${JSON.stringify(errors.slice(0, 5))}`);
  if (Date.now() - wall0 > wallLimitMs) throw new Error(`wall-clock limit of ${job.wall_limit_s} s reached at ${now() / 1e9} s emulated`);
  if (now() > emulatedLimitNs) throw new Error(`emulated-time limit of ${job.emulated_limit_s} s reached without the case's end`);
}
pollRtt(true);
const wallS = (Date.now() - wall0) / 1000;
const end = now();
const reportLen = B.bench_report(end);
const report = JSON.parse(text(B.bench_buffer_ptr(), reportLen));
fs.writeFileSync(path.join(job.out, 'stream.defmt'), Buffer.concat(stream));
const summary = {
  case: job.case,
  rp2040js: JSON.parse(fs.readFileSync(new URL('./node_modules/rp2040js/package.json', import.meta.url))).version,
  wall_s: wallS,
  emulated_s: end / 1e9,
  realtime_factor: end / 1e9 / wallS,
  instructions,
  cycles,
  mips: instructions / wallS / 1e6,
  rtt_bytes: streamBytes,
  rtt_reads: rttReads,
  commands: commands.map(({ at_s, line, written_ns }) => ({ at_s, line, written_ns })),
  resets,
  breaks,
  pwm_writes: pwmWrites,
  panic: panicInjected,
  stack_overflow: stackInjected,
  debugger_watchdog: debuggerWrote,
  min_sp: minSp,
  lockup,
  rtt_stall: stall,
  probe_attached: probeAttached,
  warnings: Object.fromEntries(warnings),
  errors,
  bench: report,
};
fs.writeFileSync(path.join(job.out, 'emulation.json'), JSON.stringify(summary, null, 1));
process.stderr.write(
  `emu: ${job.case}: ${(end / 1e9).toFixed(3)} s emulated in ${wallS.toFixed(1)} s (${(end / 1e9 / wallS).toFixed(2)}x real time, ` +
    `${(instructions / wallS / 1e6).toFixed(1)} MIPS), ${streamBytes} bytes of defmt, ${resets.length} reset(s); ` +
    `loop budget during runs: mean ${report.budget.run.mean.toFixed(0)}, max ${report.budget.run.max} of ` +
    `${report.budget.available_per_sample} cycles per sample\n`,
);
