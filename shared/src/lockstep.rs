//! Lockstep hardware-in-the-loop as the core keeps it: one control tick per sensor frame from
//! the host, on every board alike.
//!
//! What both boards decide here rather than in their glue:
//! - **Entry.** The first sensor frame enters lockstep. On the rig the core has read its own
//!   encoder since boot; the host's simulated count starts elsewhere, and measured as a
//!   movement it would latch `EncoderFault`. Entering lockstep restarts the encoder extension
//!   (the next reading sets the count) and the velocity estimate.
//! - **Lost frames.** Gaps in the frame counter are counted.
//! - **Silence.** A board that keeps time (the rig's timer; the SIL rig's periods) reports each
//!   control period that brought no sensor frame; after `lockstep_timeout_ticks` such periods
//!   in a row the core latches `LinkLost` (frames that stop never leave the force on).

/// What a sensor frame's arrival means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameArrival {
    /// Frames missing between the previous frame and this one.
    pub lost: u32,
    /// This frame entered lockstep (the first one).
    pub entered: bool,
}

/// The lockstep link's state: entered or not, the last frame number, the silent periods.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LockstepLink {
    last_frame: Option<u32>,
    silent_periods: u32,
}

impl LockstepLink {
    /// Not in lockstep.
    pub const fn new() -> Self {
        Self {
            last_frame: None,
            silent_periods: 0,
        }
    }

    /// Lockstep has been entered (a sensor frame has arrived since start-up).
    pub fn is_active(&self) -> bool {
        self.last_frame.is_some()
    }

    /// A sensor frame numbered `frame` arrived.
    pub fn on_frame(&mut self, frame: u32) -> FrameArrival {
        let entered = self.last_frame.is_none();
        let lost = match self.last_frame {
            Some(last) => {
                let gap = frame.wrapping_sub(last.wrapping_add(1));
                // A frame number going backwards (a restarted host) counts as one loss.
                if gap < (1 << 31) { gap } else { 1 }
            }
            None => 0,
        };
        self.last_frame = Some(frame);
        self.silent_periods = 0;
        FrameArrival { lost, entered }
    }

    /// A control period passed in lockstep without a sensor frame. True exactly when this
    /// makes `timeout` silent periods in a row (the moment the link is lost). Before
    /// lockstep: false.
    pub fn on_silent_period(&mut self, timeout: u32) -> bool {
        if !self.is_active() {
            return false;
        }
        self.silent_periods = self.silent_periods.saturating_add(1);
        self.silent_periods == timeout.max(1)
    }

    /// Control periods in a row without a sensor frame.
    pub fn silent_periods(&self) -> u32 {
        self.silent_periods
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_frame_enters_and_gaps_are_counted() {
        let mut l = LockstepLink::new();
        assert!(!l.is_active());
        assert_eq!(
            l.on_frame(100),
            FrameArrival {
                lost: 0,
                entered: true
            }
        );
        assert_eq!(l.on_frame(101).lost, 0);
        assert_eq!(
            l.on_frame(105),
            FrameArrival {
                lost: 3,
                entered: false
            }
        );
        assert_eq!(l.on_frame(u32::MAX).lost, 1, "backwards counts as one");
        assert_eq!(l.on_frame(0).lost, 0, "the counter wraps");
    }

    #[test]
    fn silence_times_out_only_in_lockstep_and_a_frame_resets_it() {
        let mut l = LockstepLink::new();
        assert!(!l.on_silent_period(2), "not in lockstep: no clock to lose");
        l.on_frame(1);
        assert!(!l.on_silent_period(2));
        l.on_frame(2);
        assert!(!l.on_silent_period(2));
        assert!(l.on_silent_period(2), "lost at the second silent period");
        assert!(!l.on_silent_period(2), "reported once");
        assert_eq!(l.silent_periods(), 3);
    }
}
