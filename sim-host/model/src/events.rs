//! The events a run locates: mode switches (touchdown, lift-off, ...) and apexes.

use serde::Serialize;

/// Kinds of located events.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum EventKind {
    /// Foot reaches the stored ground level moving down.
    Touchdown,
    /// Spring pulls the foot off the ground (`-F_s - m_f g > 0`).
    LiftOff,
    /// An intruding foot comes to rest and the sand holds it.
    Static,
    /// A static foot starts moving down again (a new intrusion episode).
    Intrusion,
    /// The rod's apex (`x_r'` crosses zero downward).
    Apex,
}

impl EventKind {
    /// Name as written in outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Touchdown => "Touchdown",
            Self::LiftOff => "LiftOff",
            Self::Static => "Static",
            Self::Intrusion => "Intrusion",
            Self::Apex => "Apex",
        }
    }
}

impl core::fmt::Display for EventKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A located event.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Event {
    /// Time, s.
    pub t_s: f64,
    /// What happened.
    pub kind: EventKind,
}
