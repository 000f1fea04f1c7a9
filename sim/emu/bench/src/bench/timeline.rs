//! The bench's timeline: the operator's button, the case's chip fault and the end, and when
//! the harness must wake the bench for them.

use super::{Bench, WAKE_BUTTON, WAKE_DEBUGGER, WAKE_PANIC, WAKE_STACK_OVERFLOW, WAKE_STOP};
use crate::case::{CoreFault, Stop};
use capstan_plant::InjectionKind;

impl Bench {
    /// Is the operator holding the button down?
    pub fn button_pressed(&self) -> bool {
        self.button_pressed
    }

    /// The operator's presses, [start, end) in emulator ns, as far as they are known: held
    /// from power-up, the cord's start press, the aborts, and the one after the first reset.
    fn press_windows(&self) -> Vec<(f64, f64)> {
        let mut w = Vec::new();
        let held = self.case.held_from_power_up_us;
        if held > 0 {
            w.push((0.0, held as f64 * 1e3));
        }
        if let Some((from, len)) = self.case.held_us {
            w.push((from as f64 * 1e3, (from + len) as f64 * 1e3));
        }
        if let (Some(after), Some(r)) = (self.case.press_after_reset_us, self.resets.first()) {
            let at = r.t_ns + after as f64 * 1e3;
            w.push((at, at + crate::case::PRESS_US as f64 * 1e3));
        }
        let Some(p) = self.plant.as_ref() else {
            return w;
        };
        if let Some(at) = self.case.cord.press_at_us {
            w.push((self.ns(at), self.ns(at + self.case.cord.press_us)));
        }
        if let Some(rise) = p.trigger_rise_us(0) {
            let hold = self.case.plant.faults.abort_press_ms as u64 * 1_000;
            for inj in &self.case.injections {
                if inj.kind == InjectionKind::Abort {
                    let at = rise + inj.after_trigger_us;
                    w.push((self.ns(at), self.ns(at + hold)));
                }
            }
        }
        w
    }

    fn pressed_at(&self, t_ns: f64) -> bool {
        self.press_windows()
            .iter()
            .any(|&(a, b)| t_ns >= a && t_ns < b)
    }

    pub(super) fn core_fault_due(&self) -> Option<f64> {
        let fault = self.case.core_fault?;
        let rise = self.plant.as_ref()?.trigger_rise_us(0)?;
        Some(self.ns(rise + fault.after_trigger_us()))
    }

    fn stop_at(&self) -> Option<f64> {
        let p = self.plant.as_ref()?;
        match self.case.stop {
            Stop::At(us) => Some(self.ns(us)),
            Stop::AfterTrigger(us) => Some(self.ns(p.trigger_rise_us(0)? + us)),
            Stop::AfterReset(us) => Some(self.resets.first()?.t_ns + us as f64 * 1_000.0),
        }
    }

    /// When [`Bench::wake`] must be called next, ns (None: no deadline).
    pub fn deadline(&self) -> Option<f64> {
        let now = self.now_ns;
        let mut next: Option<f64> = None;
        let mut consider = |t: f64| {
            if t > now && next.is_none_or(|n| t < n) {
                next = Some(t);
            }
        };
        for (a, b) in self.press_windows() {
            consider(a);
            consider(b);
        }
        if !self.core_fault_done {
            if let Some(t) = self.core_fault_due() {
                consider(t);
            }
        }
        if let Some(t) = self.stop_at() {
            consider(t);
        }
        next
    }

    /// Time is `t_ns`: the operator, the chip fault and the end. Returns `WAKE_*` flags.
    pub fn wake(&mut self, t_ns: f64) -> u32 {
        self.settle(t_ns);
        let mut out = 0;
        let pressed = self.pressed_at(t_ns);
        if pressed != self.button_pressed {
            self.button_pressed = pressed;
            self.button.push((t_ns, pressed));
            let start_press = self.case.held_from_power_up_us == 0
                && self.case.held_us.is_none()
                && self.button.len() == 1;
            if pressed && self.run_since_ns.is_none() && start_press {
                // The start press: the run begins once it is debounced (10 samples).
                self.run_since_ns = Some(t_ns + 10e6);
            }
            out |= WAKE_BUTTON;
        }
        if !self.core_fault_done && self.core_fault_due().is_some_and(|due| t_ns >= due) {
            self.core_fault_done = true;
            match self.case.core_fault {
                // Struck at the first conversion that does not complete.
                Some(CoreFault::Hang { .. }) => self.hang = true,
                // Struck when the harness has diverted the core (`panicked`).
                Some(CoreFault::Panic { .. }) => out |= WAKE_PANIC,
                // Struck when the harness has moved the stack pointer (`panicked` too).
                Some(CoreFault::StackOverflow { .. }) => out |= WAKE_STACK_OVERFLOW,
                // The debugger's write now; the hang at the first conversion 5 ms later.
                Some(CoreFault::DebuggerThenHang { .. }) => {
                    out |= WAKE_DEBUGGER;
                    self.hang_from_ns = Some(t_ns + crate::case::DEBUGGER_TO_HANG_US as f64 * 1e3);
                }
                None => {}
            }
        }
        if self.stop_at().is_some_and(|s| t_ns >= s) {
            self.stopped = true;
            out |= WAKE_STOP;
        }
        out
    }

    /// Has the emulation reached its end?
    pub fn stopped(&self) -> bool {
        self.stopped
    }
}
