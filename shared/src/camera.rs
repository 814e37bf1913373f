//! Camera trigger: a pulse train at a frame rate derived from the control tick.
//!
//! Integer arithmetic only (a Bresenham accumulator): frame `k` starts on tick
//! `ceil(k * tick_hz / fps)` after the train starts, so the train never drifts; at 200 fps and
//! a 10 kHz tick that is exactly one frame every 50 ticks (5 ms). Frame 0 starts on the tick
//! the trajectory starts. The line is high for `pulse_ticks` ticks from each frame start
//! (clamped so it always goes low again before the next frame).

/// Camera trigger generator.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CameraTrigger {
    fps: u32,
    tick_hz: u32,
    pulse_ticks: u32,
    acc: u32,
    high_left: u32,
    next_frame: u32,
    running: bool,
}

/// What the trigger does on one tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TriggerTick {
    /// Trigger line level for this tick.
    pub level: bool,
    /// `Some(k)` on the tick frame `k` starts (rising edge).
    pub frame: Option<u32>,
}

impl CameraTrigger {
    /// `fps` must be `1..=tick_hz/2` (checked by the configuration); `pulse_ticks >= 1`.
    pub fn new(fps: u32, tick_hz: u32, pulse_ticks: u32) -> Self {
        // Longest pulse that still leaves one low tick in the shortest frame.
        let min_frame_ticks = tick_hz.checked_div(fps.max(1)).unwrap_or(1);
        let pulse_ticks = pulse_ticks.clamp(1, min_frame_ticks.saturating_sub(1).max(1));
        Self {
            fps,
            tick_hz,
            pulse_ticks,
            acc: 0,
            high_left: 0,
            next_frame: 0,
            running: false,
        }
    }

    /// Start the train: the next [`tick`](Self::tick) begins frame 0.
    pub fn start(&mut self) {
        self.running = self.fps > 0;
        self.acc = self.tick_hz; // pre-charged: frame 0 on the first tick
        self.high_left = 0;
        self.next_frame = 0;
    }

    /// Stop the train; the line goes low.
    pub fn stop(&mut self) {
        self.running = false;
        self.high_left = 0;
    }

    /// Frames started so far.
    pub fn frames(&self) -> u32 {
        self.next_frame
    }

    /// Advance one control tick.
    pub fn tick(&mut self) -> TriggerTick {
        if !self.running {
            return TriggerTick {
                level: false,
                frame: None,
            };
        }
        let mut frame = None;
        if self.acc >= self.tick_hz {
            self.acc -= self.tick_hz;
            frame = Some(self.next_frame);
            self.next_frame = self.next_frame.wrapping_add(1);
            self.high_left = self.pulse_ticks;
        }
        self.acc += self.fps;
        let level = self.high_left > 0;
        self.high_left = self.high_left.saturating_sub(1);
        TriggerTick { level, frame }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_ticks(fps: u32, tick_hz: u32, ticks: u32) -> heapless::Vec<u32, 2048> {
        let mut c = CameraTrigger::new(fps, tick_hz, 5);
        c.start();
        let mut v = heapless::Vec::new();
        for n in 0..ticks {
            if let Some(k) = c.tick().frame {
                assert_eq!(k as usize, v.len());
                v.push(n).unwrap();
            }
        }
        v
    }

    #[test]
    fn exactly_one_frame_per_5_ms_at_200_fps() {
        let v = frame_ticks(200, 10_000, 100_000);
        assert_eq!(v.len(), 2000);
        for (k, n) in v.iter().enumerate() {
            assert_eq!(*n, 50 * k as u32);
        }
    }

    #[test]
    fn non_integer_period_never_drifts() {
        // 10 kHz / 300 fps = 33.33 ticks: frame k at ceil(k * 100 / 3).
        let v = frame_ticks(300, 10_000, 60_000);
        assert_eq!(v.len(), 1800);
        for (k, n) in v.iter().enumerate() {
            assert_eq!(*n, (k as u32 * 10_000).div_ceil(300));
        }
        let v = frame_ticks(500, 10_000, 10_000);
        assert_eq!(v.len(), 500);
        assert!(v.iter().enumerate().all(|(k, n)| *n == 20 * k as u32));
    }

    #[test]
    fn pulse_is_high_then_low_each_frame() {
        let mut c = CameraTrigger::new(500, 10_000, 5);
        c.start();
        let levels: heapless::Vec<bool, 40> = (0..40).map(|_| c.tick().level).collect();
        for (n, l) in levels.iter().enumerate() {
            assert_eq!(*l, n % 20 < 5, "tick {n}");
        }
        c.stop();
        assert_eq!(
            c.tick(),
            TriggerTick {
                level: false,
                frame: None
            }
        );
    }
}
