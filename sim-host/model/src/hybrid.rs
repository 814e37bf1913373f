//! Ground modes and their guards (docs/model.md section 3).

use serde::Serialize;

/// Where the foot is with respect to the ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum GroundMode {
    /// In the air: `F_GM = 0`.
    Aerial,
    /// At rest, held by the sand (or the floor): `F_GM = L`.
    Static,
    /// Moving into the sand: `F_GM` follows the force law.
    Intruding,
}

impl GroundMode {
    /// Name as written in outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Aerial => "Aerial",
            Self::Static => "Static",
            Self::Intruding => "Intruding",
        }
    }
}

impl core::fmt::Display for GroundMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

use crate::events::EventKind;
use crate::ground::{IntrusionEpisode, Sand};
use crate::robot::Robot;

/// What the ground does to the foot at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootForces {
    /// Foot acceleration x_f'', m/s^2.
    pub accel_m_s2: f64,
    /// Ground force on the foot F_GM, N (upward).
    pub ground_force_n: f64,
    /// Added mass m_a, kg.
    pub added_mass_kg: f64,
}

/// A switching condition of the current mode: the mode switches when `value` turns positive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guard {
    /// What happens when it fires.
    pub transition: Transition,
    /// Guard function, positive once the switch is due.
    pub value: f64,
}

/// The mode switches of docs/model.md section 3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transition {
    /// Aerial foot reaches the stored ground level moving down: `x_level - x_f > 0`.
    Touchdown,
    /// Static foot pulled up by the spring: `-F_s - m_f g > 0` (rule 5, Zeno-free).
    LiftOff,
    /// Intruding foot's velocity reaches 0: `v > 0` (it becomes static if the sand holds it).
    Stop,
    /// Static foot's load exceeds the holding capacity: `L - F_p_re(z) > 0`.
    Restart,
}

/// The hybrid state of the foot-ground contact (docs/model.md section 3, rules 1-6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Current mode.
    pub mode: GroundMode,
    /// Height of the ground under the foot, m: follows the foot while grounded, frozen in
    /// flight where the foot left it (rule 1).
    pub ground_level_m: f64,
    /// The current (or last) intrusion episode: where it began, the overshoot's anchor, its
    /// laws (rebuilt at each touchdown and restart, so never out of date).
    episode: IntrusionEpisode,
    /// The foot has left the ground at least once (the sand under it is disturbed).
    pub airborne_once: bool,
    /// Deepest point reached so far, z_max, m.
    pub max_depth_m: f64,
}

/// Force margin of the load guards (restart, lift-off), N: a load must exceed the capacity
/// by more than this (a micronewton) before the mode switches, so rounding noise of a foot
/// at rest cannot trigger switches. Physically negligible.
pub const LOAD_GUARD_MARGIN_N: f64 = 1e-6;

/// Depth below the undisturbed surface of a foot at height `x_f`, m.
#[inline]
pub fn depth_of(x_f: f64) -> f64 {
    -x_f
}

impl Contact {
    /// A static foot at height `x_f` on `sand` (after the initial sink; no overshoot).
    pub fn at_rest(sand: &Sand, x_f: f64) -> Self {
        let z = depth_of(x_f);
        Self {
            mode: GroundMode::Static,
            ground_level_m: x_f,
            episode: sand.episode(z, None),
            airborne_once: false,
            max_depth_m: z.max(0.0),
        }
    }

    /// A foot in the air over `sand` that has been airborne before (the sand is disturbed),
    /// the ground level at `ground_level_m`, no intrusion so far.
    pub fn in_flight(sand: &Sand, ground_level_m: f64) -> Self {
        Self {
            mode: GroundMode::Aerial,
            ground_level_m,
            episode: sand.episode(0.0, None),
            airborne_once: true,
            max_depth_m: 0.0,
        }
    }

    /// Depth z_start where the current intrusion episode began, m.
    pub fn episode_start_m(&self) -> f64 {
        self.episode.start_m()
    }

    /// Depth the re-intrusion overshoot is anchored at; `None` until the foot has been airborne.
    pub fn overshoot_anchor_m(&self) -> Option<f64> {
        self.episode.anchor_m()
    }

    /// Holding capacity of the sand at depth `z` in the current episode, N (`F_p_re` once
    /// airborne, plain `F_p` before; infinite for the rigid floor).
    #[inline]
    pub fn holding_force(&self, sand: &Sand, z_m: f64) -> f64 {
        sand.resisting_force(z_m, self.overshoot_anchor_m())
    }

    /// Foot acceleration and ground force for spring force `f_s` and foot state `(x_f, v_f)`.
    #[inline]
    pub fn foot(&self, robot: &Robot, sand: &Sand, x_f: f64, v_f: f64, f_s: f64) -> FootForces {
        let m_f = robot.foot_mass_kg();
        let weight = m_f * robot.gravity_m_s2();
        match self.mode {
            GroundMode::Aerial => FootForces {
                accel_m_s2: robot.foot_accel_aerial(f_s),
                ground_force_n: 0.0,
                added_mass_kg: 0.0,
            },
            GroundMode::Static => FootForces {
                accel_m_s2: 0.0,
                ground_force_n: f_s + weight,
                added_mass_kg: 0.0,
            },
            GroundMode::Intruding => {
                let (resist, m_a) = sand.intrusion(&self.episode, depth_of(x_f), v_f);
                // eq4, implicit in the foot's own acceleration: (m_f + m_a) a = -m_f g - F_s + F_p + alpha v^2.
                // The reciprocal depends on the depth only: it is ready before F_s.
                let per_kg = 1.0 / (m_f + m_a);
                let accel = ((resist - weight) - f_s) * per_kg;
                FootForces {
                    accel_m_s2: accel,
                    ground_force_n: resist - m_a * accel,
                    added_mass_kg: m_a,
                }
            }
        }
    }

    /// Added mass m_a of a foot at height `x_f`, kg (the `added_mass_kg` of
    /// [`foot`](Self::foot); 0 unless intruding).
    #[inline]
    pub fn added_mass(&self, sand: &Sand, x_f: f64) -> f64 {
        match self.mode {
            GroundMode::Intruding => sand.episode_added_mass(&self.episode, depth_of(x_f)),
            GroundMode::Aerial | GroundMode::Static => 0.0,
        }
    }

    /// The guards of the current mode (at most two; unused slots have value `-inf`).
    #[inline]
    pub fn guards(&self, robot: &Robot, sand: &Sand, x_f: f64, v_f: f64, f_s: f64) -> [Guard; 2] {
        let values = self.guard_values_with(robot, sand, x_f, v_f, || f_s);
        let transitions = self.guard_transitions();
        [0, 1].map(|i| Guard {
            transition: transitions[i],
            value: values[i],
        })
    }

    /// What each of the current mode's guards does when it fires (slot by slot as in
    /// [`guard_values_with`](Self::guard_values_with)).
    #[inline]
    pub fn guard_transitions(&self) -> [Transition; 2] {
        match self.mode {
            GroundMode::Aerial => [Transition::Touchdown; 2],
            GroundMode::Static => [Transition::LiftOff, Transition::Restart],
            GroundMode::Intruding => [Transition::Stop; 2],
        }
    }

    /// The values of the current mode's guards (unused slots `-inf`), with the spring force
    /// `f_s()`, N, computed only by the modes whose guards depend on it. The run loop keeps
    /// these plain numbers from step to step; the transitions are looked up only when one
    /// fires.
    #[inline]
    pub fn guard_values_with(
        &self,
        robot: &Robot,
        sand: &Sand,
        x_f: f64,
        v_f: f64,
        f_s: impl FnOnce() -> f64,
    ) -> [f64; 2] {
        match self.mode {
            GroundMode::Aerial => [self.ground_level_m - x_f, f64::NEG_INFINITY],
            GroundMode::Static => {
                let load = robot.foot_load(f_s());
                let restart = if sand.law.is_rigid() {
                    f64::NEG_INFINITY
                } else {
                    load - self.holding_force(sand, depth_of(x_f)) - LOAD_GUARD_MARGIN_N
                };
                [-load - LOAD_GUARD_MARGIN_N, restart]
            }
            GroundMode::Intruding => [v_f, f64::NEG_INFINITY],
        }
    }

    /// Apply `transition` at foot state `(x_f, v_f)` (velocity possibly reset). Returns the
    /// event to record when the mode changed.
    pub fn apply(
        &mut self,
        transition: Transition,
        robot: &Robot,
        sand: &Sand,
        x_f: f64,
        v_f: &mut f64,
        f_s: f64,
    ) -> Option<EventKind> {
        let z = depth_of(x_f);
        match transition {
            Transition::Touchdown => {
                self.ground_level_m = x_f;
                let rigid = sand.law.is_rigid();
                let anchor = if self.airborne_once && !rigid {
                    Some(z)
                } else {
                    self.overshoot_anchor_m()
                };
                self.episode = sand.episode(z, anchor);
                if rigid {
                    // Perfectly plastic impact on the rigid floor.
                    *v_f = 0.0;
                    self.mode = GroundMode::Static;
                } else {
                    // No velocity jump: the foot enters the sand with the active law (the
                    // overshoot anchored here once the foot has been airborne).
                    self.mode = GroundMode::Intruding;
                }
                Some(EventKind::Touchdown)
            }
            Transition::LiftOff => {
                self.ground_level_m = x_f;
                self.airborne_once = true;
                self.mode = GroundMode::Aerial;
                Some(EventKind::LiftOff)
            }
            Transition::Stop => {
                *v_f = 0.0;
                self.ground_level_m = x_f;
                if robot.foot_load(f_s) <= self.holding_force(sand, z) {
                    self.mode = GroundMode::Static;
                    Some(EventKind::Static)
                } else {
                    None
                }
            }
            Transition::Restart => {
                // A new intrusion episode starts here.
                let anchor = match self.overshoot_anchor_m() {
                    Some(_) if sand.law.anchor == crate::params::ReintrusionAnchor::Episode => {
                        Some(z)
                    }
                    kept => kept,
                };
                self.episode = sand.episode(z, anchor);
                if robot.foot_load(f_s) > self.holding_force(sand, z) {
                    self.mode = GroundMode::Intruding;
                    Some(EventKind::Intrusion)
                } else {
                    None
                }
            }
        }
    }

    /// Follow the foot while grounded (rule 6): ground level and z_max.
    #[inline]
    pub fn track(&mut self, x_f: f64) {
        if self.mode != GroundMode::Aerial {
            self.ground_level_m = x_f;
            self.max_depth_m = self.max_depth_m.max(depth_of(x_f));
        }
    }
}
