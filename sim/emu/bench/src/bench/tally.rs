//! What the bench saw, gathered at the end of the emulation into its [`Report`].

use super::Bench;
use crate::report::{
    Budget, CoreFaultOut, InjectionOut, PlantServoEvent, Report, Stats, CYCLES_PER_SAMPLE,
};
use capstan_plant::ServoEvent;

impl Bench {
    /// Everything seen, at the end of the emulation (`t_ns`).
    pub fn report(&mut self, t_ns: f64) -> Report {
        self.settle(t_ns);
        if let Some(p) = self.plant.as_mut() {
            let us = ((t_ns - self.origin_ns) / 1_000.0).round().max(0.0) as u64;
            p.advance_to(us);
        }
        let rise = self.trigger_rise_ns;
        let origin = self.origin_ns;
        let (injections, plant_servo) = self.plant_records();
        Report {
            case: self.case.name.to_string(),
            origin_ns: self.plant.as_ref().map(|_| origin),
            end_ns: t_ns,
            servo: self.servo.segments.clone(),
            servo_pulses: self.servo.rises,
            pwm_off_grid: self.pwm_off_grid,
            amp: self.amp.segments.clone(),
            amp_periods: self.amp.rises,
            trigger: self.trigger.clone(),
            led_edges: self.led_edges,
            button: self.button.clone(),
            button_mismatches: self.button_mismatches,
            conversions: self.conversions,
            rounding_mismatches: self.rounding_mismatches,
            mismatch_examples: self.mismatch_examples.clone(),
            t1_phase_ns: self.t1_phase_ns,
            late_t1: self.late_t1.clone(),
            trigger_rise_ns: rise,
            injections,
            core_fault: self.case.core_fault.map(|f| CoreFaultOut {
                kind: f.name(),
                due_ns: self.core_fault_due(),
                struck_ns: self.core_fault_struck_ns,
            }),
            resets: self.resets.clone(),
            budget: self.budget(),
            plant_servo,
            samples: self.samples.clone(),
            after_reset: self.after_reset.clone(),
            drive_v_at_reset: self.drive_v_at_reset,
        }
    }

    /// The loop budget: busy cycles per sample in runs and idle, the worst of the run's.
    fn budget(&self) -> Budget {
        let rise = self.trigger_rise_ns;
        let mut run = self.run_bursts.clone();
        let mut idle = self.idle_bursts.clone();
        let mut worst = run.clone();
        worst.sort_by_key(|b| std::cmp::Reverse(b.1));
        worst.truncate(5);
        let run_worst = worst
            .iter()
            .map(|&(t, c)| (t - rise.unwrap_or(0.0), c))
            .collect();
        // Every stretch that ended before the case's chip fault struck (a hung loop, the
        // panic path, a lockup: the harness's doing, not a sample's work).
        let ns_per_cycle = 1e6 / CYCLES_PER_SAMPLE as f64;
        let mut working: Vec<(f64, u32)> = run
            .iter()
            .chain(&idle)
            .copied()
            .filter(|&(t, c)| {
                self.core_fault_struck_ns
                    .is_none_or(|s| t + c as f64 * ns_per_cycle < s)
            })
            .collect();
        Budget {
            available_per_sample: CYCLES_PER_SAMPLE,
            run: Stats::of(&mut run),
            idle: Stats::of(&mut idle),
            working: Stats::of(&mut working),
            run_worst,
            cycles: self.cycles,
        }
    }

    /// The plant's own records, in emulator ns: its injections and its servo's moves.
    fn plant_records(&self) -> (Vec<InjectionOut>, Vec<PlantServoEvent>) {
        let origin = self.origin_ns;
        let Some(p) = self.plant.as_ref() else {
            return (Vec::new(), Vec::new());
        };
        let injections = p
            .injections()
            .iter()
            .map(|r| InjectionOut {
                kind: r.injection.kind.name(),
                at_ns: r.at_us.map(|us| origin + us as f64 * 1e3),
                plant_safe_at_ns: r.safe_at_us.map(|us| origin + us as f64 * 1e3),
            })
            .collect();
        let servo = p
            .servo_events(0)
            .0
            .iter()
            .map(|e: &ServoEvent| PlantServoEvent {
                t_ns: origin + e.t_us as f64 * 1e3,
                pulse_us: e.pulse_us,
                angle_deg: e.angle_deg,
            })
            .collect();
        (injections, servo)
    }
}
