//! The linear encoder's quadrature signals into TIM2 (channels 1 and 2, the firmware's PA15 and
//! PB3 in encoder mode): the plant's motor position, in counts, becomes A/B transitions spread
//! evenly over the control period in which the motion happens, as a real scale's edges are.
//! Writing TIM2's `CNT` would not do: the timer answers from its own state, and the firmware's
//! input filter (8 samples at 84 MHz, ~95 ns) must see edges it can validate. Edges closer than
//! [`MIN_EDGE_SPACING_NS`] are not generated: a move that needs more edges in one period than
//! fit is carried into the next period and counted in [`QuadratureEncoder::deferred_counts`]
//! (the scale outran the input filter, as a real one would).

use rigless::device::Level;
use rigless::soc::st::tim::Channel;
use rigless::soc::stm32f427::Stm32f427;
use rigless::time::VirtualNanos;

/// Closest two edges are generated, ns: above the firmware's input filter (8 / 84 MHz = 95 ns).
pub const MIN_EDGE_SPACING_NS: u64 = 120;
/// TIM2's index in rigless's `TIMERS`.
const TIM2: usize = 0;

/// A quadrature encoder wired to TIM2's first two channels.
#[derive(Debug, Default)]
pub struct QuadratureEncoder {
    /// The count the edges generated so far amount to (x4 decoding).
    count: i64,
    /// Counts a period could not fit (see the module docs), summed over the run.
    pub deferred_counts: u64,
    /// Edges generated.
    pub edges: u64,
    /// The signals are inverted in direction (the scale mounted the other way round).
    pub reversed: bool,
}

/// (A, B) at each of the four phases of one cycle, forward order.
const PHASES: [(bool, bool); 4] = [(false, false), (true, false), (true, true), (false, true)];

impl QuadratureEncoder {
    /// The count the edges generated so far amount to.
    pub fn count(&self) -> i64 {
        self.count
    }

    /// Drive the edges that take the count to `target` over `[from, from + span_ns)`.
    pub fn move_to(&mut self, part: &mut Stm32f427, from: VirtualNanos, span_ns: u64, target: i64) {
        let wanted = target - self.count;
        if wanted == 0 {
            return;
        }
        let room = (span_ns / MIN_EDGE_SPACING_NS).max(1) as i64;
        let n = wanted.abs().min(room);
        self.deferred_counts += (wanted.abs() - n) as u64;
        let step = wanted.signum();
        let spacing = span_ns / n as u64;
        for k in 0..n {
            let before = self.phase();
            self.count += step;
            let after = self.phase();
            let at = VirtualNanos(from.0 + k as u64 * spacing);
            let (a0, b0) = PHASES[before];
            let (a1, b1) = PHASES[after];
            let level = |high: bool| if high { Level::High } else { Level::Low };
            if a0 != a1 {
                part.drive_timer(at, TIM2, |tim, regs, cx| {
                    tim.drive_input(Channel::new(1).expect("channel 1"), level(a1), regs, cx)
                });
            }
            if b0 != b1 {
                part.drive_timer(at, TIM2, |tim, regs, cx| {
                    tim.drive_input(Channel::new(2).expect("channel 2"), level(b1), regs, cx)
                });
            }
            self.edges += 1;
        }
    }

    fn phase(&self) -> usize {
        let c = if self.reversed {
            -self.count
        } else {
            self.count
        };
        c.rem_euclid(4) as usize
    }
}
