//! Wall time of each phase of a scene build, so that the `scale` benchmark can say where a
//! build's time goes (`cargo bench --bench scale -- --phases`). Reading the clock a dozen
//! times a build costs nothing measurable.

use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub struct BuildTimes {
    /// Each phase's name and wall time, in the order they ran.
    pub phases: Vec<(&'static str, Duration)>,
    last: Instant,
}

impl Default for BuildTimes {
    fn default() -> Self {
        Self::start()
    }
}

impl BuildTimes {
    /// Starts the clock of the first phase.
    pub fn start() -> Self {
        BuildTimes {
            phases: Vec::new(),
            last: Instant::now(),
        }
    }

    /// Ends the phase running now, called `name`, and starts the next.
    pub fn mark(&mut self, name: &'static str) {
        let now = Instant::now();
        self.phases.push((name, now - self.last));
        self.last = now;
    }

    /// The phases as `name 0.123 s, …`.
    pub fn summary(&self) -> String {
        let parts: Vec<String> = self
            .phases
            .iter()
            .map(|(n, d)| format!("{n} {:.3} s", d.as_secs_f64()))
            .collect();
        parts.join(", ")
    }
}
