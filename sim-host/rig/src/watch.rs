//! What a run shows while it goes on: a [`RunWatch`] is told the run's title, every control
//! period of a jump through the loop ([`PeriodView`]) and every step of a rig program
//! ([`ProgramView`]). The command line connects it to its live view; the library knows
//! nothing of a page or a server. A run given no watch builds nothing for one.

use crate::hil::run::PeriodView;
use crate::tool::session::ProgramView;

/// The sink a watched run reports its steps to. Every method has a do-nothing default.
pub trait RunWatch {
    /// The run begins: `title` in words, at rig time `t_s`, s (negative while settling).
    fn started(&mut self, title: &str, t_s: f64) {
        let _ = (title, t_s);
    }
    /// One control period of a jump through the loop (`hil` on a lockstep link).
    fn period(&mut self, view: &PeriodView) {
        let _ = view;
    }
    /// One step of a rig program (a lockstep period or a free-running board's status poll);
    /// `p_cmd_m`: the commanded motor position at the step, m, when the host knows it;
    /// `metres_per_count`: the encoder's scale, m.
    fn program(&mut self, view: &ProgramView<'_>, p_cmd_m: Option<f64>, metres_per_count: f64) {
        let _ = (view, p_cmd_m, metres_per_count);
    }
}
