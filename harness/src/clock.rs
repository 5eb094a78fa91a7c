//! Wall-clock time that can be paused, so that what a report does between passes (resolving,
//! measuring, writing) is not charged to rendering.

use std::time::Instant;

/// A stopwatch that starts running and can be paused and resumed.
#[derive(Debug)]
pub struct Stopwatch {
    running_since: Option<Instant>,
    banked: f64,
}

impl Stopwatch {
    /// A running stopwatch at zero.
    pub fn start() -> Self {
        Self {
            running_since: Some(Instant::now()),
            banked: 0.0,
        }
    }

    /// Stops counting until [`Stopwatch::resume`].
    pub fn pause(&mut self) {
        if let Some(t) = self.running_since.take() {
            self.banked += t.elapsed().as_secs_f64();
        }
    }

    /// Counts again (no effect while running).
    pub fn resume(&mut self) {
        self.running_since.get_or_insert_with(Instant::now);
    }

    /// Seconds counted so far.
    pub fn seconds(&self) -> f64 {
        self.banked
            + self
                .running_since
                .map_or(0.0, |t| t.elapsed().as_secs_f64())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paused_time_is_not_counted() {
        let mut clock = Stopwatch::start();
        clock.pause();
        let before = clock.seconds();
        std::thread::sleep(std::time::Duration::from_millis(30));
        assert_eq!(clock.seconds(), before);
        clock.resume();
        std::thread::sleep(std::time::Duration::from_millis(5));
        assert!(clock.seconds() > before);
    }
}
