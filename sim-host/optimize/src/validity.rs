//! Where an answer stands against what the paper measured: its landings, its pushes while the
//! grains still move, the re-intrusion overshoot it re-arms ([`Regime`]), and the height it
//! keeps when the model's rule for each is swapped for the model's alternative
//! ([`Rescore`]). The paper measured single jumps, stutters and delayed stutters; a stroke
//! that lands faster than those do, or pushes into grains still moving from a landing, is
//! scored by rules (the overshoot after a landing, the drag law, the overshoot re-armed at
//! every restart of a static foot) fitted elsewhere. [`Validity::relies_on`] names, in
//! words, each rule the answer's advantage rests on.

use serde::Serialize;

use sandjumper_model::events::EventKind;
use sandjumper_model::ground::{DragLaw, GroundLaw};
use sandjumper_model::params::{DragChoice, ReintrusionAnchor, ReintrusionChoice};
use sandjumper_model::record::JumpSummary;

use crate::evaluate::Problem;
use crate::family::MoveChain;

/// The landings of `jump` (time, s; downward speed, m/s) before `until_s`: the ones a stroke
/// lasting `until_s` still acts on (the landing after its last hop ends the run and is not).
pub fn landings_before(jump: &JumpSummary, until_s: f64) -> Vec<(f64, f64)> {
    jump.events
        .iter()
        .filter(|e| e.kind == EventKind::Touchdown)
        .zip(&jump.touchdown_speeds_m_s)
        .filter(|(e, _)| e.t_s < until_s)
        .map(|(e, v)| (e.t_s, *v))
        .collect()
}

/// What a stroke's kinematic jump does outside the paper's measured regime.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Regime {
    /// Landings (touchdowns after a hop) while the stroke still runs (the landing that ends
    /// the run is not one).
    pub touchdowns: usize,
    /// The fastest of those landings (the centre of mass's downward speed), m/s (0 without
    /// one).
    pub max_landing_speed_m_s: f64,
    /// Pushes (moves that raise `p`, driving the foot down through the spring) that begin
    /// after a touchdown while the foot still intrudes (the grains under it still move: it has
    /// neither come to rest nor left again).
    pub pushes_during_grain_motion: usize,
    /// The shortest delay from a touchdown to the next push, s (None: no push follows a
    /// landing).
    pub earliest_push_after_touchdown_s: Option<f64>,
    /// Intrusion episodes that carry the re-intrusion overshoot (0 when the ground law has
    /// none): each touchdown, and, with the overshoot re-anchored at every episode, each
    /// restart of a static foot after the first flight.
    pub reintrusion_episodes: usize,
}

/// The pushes of `chain` after a landing in its kinematic jump `jump`: the earliest delay from
/// a touchdown to the start of the next push (a move that raises `p`, driving the foot down
/// through the spring), s, and how many pushes begin while the foot still intrudes after a
/// touchdown (it has neither come to rest nor left again: the grains under it still move).
pub fn pushes_after_landings(jump: &JumpSummary, chain: &MoveChain) -> (Option<f64>, usize) {
    let events = &jump.events;
    // Each touchdown and the end of its grains' motion (rest, lift-off or the run's end).
    let landings: Vec<(f64, f64)> = events
        .iter()
        .enumerate()
        .filter(|(_, e)| e.kind == EventKind::Touchdown)
        .map(|(i, e)| {
            let end = events[i + 1..]
                .iter()
                .find(|n| matches!(n.kind, EventKind::Static | EventKind::LiftOff))
                .map_or(jump.end_time_s, |n| n.t_s);
            (e.t_s, end)
        })
        .collect();
    let (mut earliest, mut during) = (None::<f64>, 0);
    let (mut t, mut p) = (0.0, chain.start_m);
    for m in &chain.moves {
        if m.to_m > p
            && let Some(&(td, still)) = landings.iter().rev().find(|&&(a, _)| a < t)
        {
            earliest = Some(earliest.map_or(t - td, |e: f64| e.min(t - td)));
            during += usize::from(t < still);
        }
        if m.to_m != p {
            t += m.duration_s;
        }
        t += m.hold_s;
        p = m.to_m;
    }
    (earliest, during)
}

impl Regime {
    /// The regime of `chain`'s kinematic jump `jump` on ground `law`.
    pub fn of(jump: &JumpSummary, chain: &MoveChain, law: &GroundLaw) -> Self {
        let events = &jump.events;
        let (earliest, pushes) = pushes_after_landings(jump, chain);
        // A rigid floor has no grains to move (its foot stays in contact at rest).
        let pushes = if law.is_rigid() { 0 } else { pushes };
        let first_flight = events.iter().position(|e| e.kind == EventKind::LiftOff);
        let reintrusion_episodes = if !law.reintrusion {
            0
        } else {
            events
                .iter()
                .enumerate()
                .filter(|&(i, e)| match e.kind {
                    EventKind::Touchdown => true,
                    EventKind::Intrusion => {
                        law.anchor == ReintrusionAnchor::Episode
                            && first_flight.is_some_and(|f| i > f)
                    }
                    _ => false,
                })
                .count()
        };
        let landings = landings_before(jump, chain.duration_s());
        Self {
            touchdowns: landings.len(),
            max_landing_speed_m_s: landings.iter().map(|l| l.1).fold(0.0, f64::max),
            pushes_during_grain_motion: pushes,
            earliest_push_after_touchdown_s: earliest,
            reintrusion_episodes,
        }
    }
}

/// One of the model's rules swapped for its alternative, and what the answer and the paper's
/// best keep under it (kinematic model, the stroke tables the rig replays).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rescore {
    /// The rule, in a word or two (`overshoot`, `re-armed overshoot`, `drag law`).
    pub tag: String,
    /// The rule, in words.
    pub rule: String,
    /// Its alternative, in words.
    pub alternative: String,
    /// The answer's objective value under the model's rule (the search's).
    pub answer_value: f64,
    /// The answer's value under the alternative (NaN when it breaks a limit there).
    pub answer_value_alternative: f64,
    /// The paper's best's value under the model's rule.
    pub paper_value: f64,
    /// The paper's best's value under the alternative (NaN when it breaks a limit there).
    pub paper_value_alternative: f64,
    /// The answer's rod apex under the alternative, m (the height it keeps, whatever the
    /// objective; NaN when it breaks a limit there).
    pub answer_height_alternative_m: f64,
    /// The paper's best's rod apex under the alternative, m.
    pub paper_height_alternative_m: f64,
    /// The limit a stroke breaks under the alternative, in words (empty: none).
    pub violation: String,
}

impl Rescore {
    /// The fraction of its value the answer keeps under the alternative.
    pub fn answer_kept(&self) -> f64 {
        self.answer_value_alternative / self.answer_value
    }

    /// The answer's value over the paper's best's under the model's rule.
    pub fn lead(&self) -> f64 {
        self.answer_value / self.paper_value
    }

    /// The answer's value over the paper's best's under the alternative.
    pub fn lead_alternative(&self) -> f64 {
        self.answer_value_alternative / self.paper_value_alternative
    }

    /// Whether the answer's advantage over the paper's best rests on the rule: under the
    /// alternative its lead shrinks to less than [`RELIANCE_KEPT`] of what it was, or a lead
    /// it had is gone (or it breaks a limit there). The paper's strokes lean on the model's
    /// rules too (their heights were fitted with them); what is asked here is whether the
    /// answer's gain over them does.
    pub fn relied_on(&self) -> bool {
        let (lead, alt) = (self.lead(), self.lead_alternative());
        // NaN (a limit broken under the alternative) neither keeps nor leads.
        let kept = alt >= RELIANCE_KEPT * lead;
        let leads = alt > 1.0;
        !kept || (lead > 1.0 && !leads)
    }
}

/// An answer relies on a rule when its lead over the paper's best keeps less than this fraction
/// of itself without the rule.
pub const RELIANCE_KEPT: f64 = 0.9;

/// The answer against the paper's measured regime and the model's alternatives.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Validity {
    /// The answer's regime.
    pub answer: Regime,
    /// The paper's best's regime.
    pub paper: Regime,
    /// The fastest landing while the stroke still runs among the paper's strokes this run
    /// swept at the robot's amplitude (feasible ones, the same ground and limits; a
    /// stutter's preliminary hop), m/s: the paper's regime as this model renders it.
    pub paper_sweep_max_landing_speed_m_s: f64,
    /// The shortest delay from a landing to the next push among the same paper strokes, s
    /// (None: none of them pushes after a landing).
    pub paper_sweep_earliest_push_after_landing_s: Option<f64>,
    /// The answer under each alternative rule (none on hard ground).
    pub rescored: Vec<Rescore>,
    /// Each rule outside the paper's measured regime the answer relies on, in words (empty:
    /// none found).
    pub relies_on: Vec<String>,
    /// The same, in a word or two each (the figure's title names them).
    pub relies_on_tags: Vec<String>,
}

impl Validity {
    /// The validity of `answer` against `paper` on `problem`; `paper_sweep_max_landing` is
    /// the fastest landing of the paper's swept strokes, m/s, and `paper_sweep_earliest_push`
    /// their shortest delay from a landing to a push, s. `jump` gives a chain's kinematic
    /// jump on the problem's ground (its table's, as the search evaluates it).
    pub fn assess(
        problem: &Problem,
        answer: &MoveChain,
        paper: &MoveChain,
        paper_sweep_max_landing: f64,
        paper_sweep_earliest_push: Option<f64>,
        jump: &dyn Fn(&Problem, &MoveChain) -> Result<JumpSummary, String>,
    ) -> Result<Self, String> {
        let law = GroundLaw::resolve(problem.model, &problem.params.model);
        let answer_regime = Regime::of(&jump(problem, answer)?, answer, &law);
        let paper_regime = Regime::of(&jump(problem, paper)?, paper, &law);
        let (a, p) = (problem.evaluate(answer), problem.evaluate(paper));
        let rescored: Vec<Rescore> = alternatives(&law)
            .into_iter()
            .map(|alt| {
                let mut swapped = problem.clone();
                (alt.apply)(&mut swapped.params.model);
                for bed in &mut swapped.beds {
                    (alt.apply)(&mut bed.model);
                }
                let (ea, ep) = (swapped.evaluate(answer), swapped.evaluate(paper));
                Rescore {
                    tag: alt.tag.into(),
                    rule: alt.rule.into(),
                    alternative: alt.alternative.into(),
                    answer_value: a.value,
                    answer_value_alternative: ea.value,
                    paper_value: p.value,
                    paper_value_alternative: ep.value,
                    answer_height_alternative_m: ea.jump_height_m,
                    paper_height_alternative_m: ep.jump_height_m,
                    violation: [
                        ea.violation.map(|v| format!("answer: {v}")),
                        ep.violation.map(|v| format!("paper: {v}")),
                    ]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join("; "),
                }
            })
            .collect();
        let (mut relies_on, mut relies_on_tags) = (Vec::new(), Vec::<String>::new());
        if answer_regime.max_landing_speed_m_s > paper_sweep_max_landing {
            relies_on.push(format!(
                "lands at {:.2} m/s, faster than any of the paper's strokes at the robot's \
                 amplitude ({:.2} m/s)",
                answer_regime.max_landing_speed_m_s, paper_sweep_max_landing
            ));
            relies_on_tags.push("landing speed".into());
        }
        if let Some(dt) = answer_regime.earliest_push_after_touchdown_s
            && paper_sweep_earliest_push.is_none_or(|p| dt < p)
        {
            relies_on.push(format!(
                "pushes {:.1} ms after a landing, sooner than any of the paper's strokes at the \
                 robot's amplitude ({})",
                1e3 * dt,
                paper_sweep_earliest_push.map_or("none pushes after a landing".into(), |p| {
                    format!("{:.1} ms", 1e3 * p)
                })
            ));
            relies_on_tags.push("push timing".into());
        }
        if answer_regime.pushes_during_grain_motion > paper_regime.pushes_during_grain_motion {
            relies_on.push(format!(
                "{} push(es) while the foot still intrudes after a landing (the grains under it \
                 still moving; the paper's best: {})",
                answer_regime.pushes_during_grain_motion, paper_regime.pushes_during_grain_motion
            ));
            relies_on_tags.push("push into moving grains".into());
        }
        for r in rescored.iter().filter(|r| r.relied_on()) {
            relies_on.push(format!(
                "{}: with {} the answer keeps {:.0} % of its value and {:.2} times the paper's \
                 best (against {:.2} times with the rule)",
                r.rule,
                r.alternative,
                100.0 * r.answer_kept(),
                r.lead_alternative(),
                r.lead()
            ));
            relies_on_tags.push(r.tag.clone());
        }
        Ok(Self {
            answer: answer_regime,
            paper: paper_regime,
            paper_sweep_max_landing_speed_m_s: paper_sweep_max_landing,
            paper_sweep_earliest_push_after_landing_s: paper_sweep_earliest_push,
            rescored,
            relies_on,
            relies_on_tags,
        })
    }
}

/// A rule of the ground model and its alternative.
struct Alternative {
    tag: &'static str,
    rule: &'static str,
    alternative: &'static str,
    apply: fn(&mut sandjumper_model::params::ModelOverrides),
}

/// The alternatives that apply to `law` (none on the rigid floor).
fn alternatives(law: &GroundLaw) -> Vec<Alternative> {
    let mut v = Vec::new();
    if law.is_rigid() {
        return v;
    }
    if law.reintrusion {
        v.push(Alternative {
            tag: "overshoot",
            rule: "re-intrusion overshoot after a landing",
            alternative: "no overshoot",
            apply: |o| o.reintrusion = ReintrusionChoice::Off,
        });
        if law.anchor == ReintrusionAnchor::Episode {
            v.push(Alternative {
                tag: "re-armed overshoot",
                rule: "overshoot re-armed at every restart of a static foot",
                alternative: "the overshoot anchored at touchdowns only",
                apply: |o| o.reintrusion_anchor = ReintrusionAnchor::Touchdown,
            });
        }
    }
    v.push(match law.drag {
        DragLaw::AddedMass => Alternative {
            tag: "drag law",
            rule: "added-mass drag (eq. 4) at these speeds",
            alternative: "constant-alpha drag (eq. 1)",
            apply: |o| o.drag = DragChoice::ConstantAlpha,
        },
        DragLaw::ConstantAlpha => Alternative {
            tag: "drag law",
            rule: "constant-alpha drag (eq. 1) at these speeds",
            alternative: "added-mass drag (eq. 4)",
            apply: |o| o.drag = DragChoice::AddedMass,
        },
    });
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::family::Move;
    use sandjumper_model::events::Event;
    use sandjumper_model::params::{ModelName, ModelOverrides};

    /// A hop landing at 0.2 s at 1.2 m/s, intruding until it rests at 0.25 s, a restart of
    /// the static foot at 0.3 s, a lift-off at 0.35 s and the landing that ends the run, at
    /// 2.5 m/s after the stroke (not one the stroke acts on).
    fn jump() -> JumpSummary {
        let ev = |t_s, kind| Event { t_s, kind };
        JumpSummary {
            events: vec![
                ev(0.05, EventKind::LiftOff),
                ev(0.1, EventKind::Apex),
                ev(0.2, EventKind::Touchdown),
                ev(0.25, EventKind::Static),
                ev(0.3, EventKind::Intrusion),
                ev(0.35, EventKind::LiftOff),
                ev(0.6, EventKind::Touchdown),
            ],
            touchdown_speeds_m_s: vec![1.2, 2.5],
            end_time_s: 0.6,
            ..JumpSummary::default()
        }
    }

    /// From 10 mm: down to -10 mm by 0.1 s, held to 0.21 s; a push to 10 mm (0.21-0.23 s,
    /// 10 ms after the landing, grains moving); down again by 0.24 s; a push from 0.26 s
    /// (the foot at rest).
    fn chain() -> MoveChain {
        let mv = |to_m, duration_s, hold_s| Move {
            to_m,
            duration_s,
            hold_s,
        };
        MoveChain {
            start_m: 0.01,
            moves: vec![
                mv(-0.01, 0.1, 0.11),
                mv(0.01, 0.02, 0.0),
                mv(-0.01, 0.01, 0.02),
                mv(0.01, 0.02, 0.0),
            ],
        }
    }

    #[test]
    fn a_push_into_moving_grains_and_each_overshoot_episode_are_counted() {
        let eq4 = GroundLaw::resolve(ModelName::Eq4, &ModelOverrides::default());
        let r = Regime::of(&jump(), &chain(), &eq4);
        assert_eq!(r.touchdowns, 1);
        assert_eq!(r.max_landing_speed_m_s, 1.2);
        assert_eq!(r.pushes_during_grain_motion, 1);
        let dt = r.earliest_push_after_touchdown_s.unwrap();
        assert!((dt - 0.01).abs() < 1e-12, "{dt}");
        // The touchdowns' episodes and the static foot's restart.
        assert_eq!(r.reintrusion_episodes, 3);
        let touchdown_anchor = GroundLaw::resolve(
            ModelName::Eq4,
            &ModelOverrides {
                reintrusion_anchor: ReintrusionAnchor::Touchdown,
                ..ModelOverrides::default()
            },
        );
        assert_eq!(
            Regime::of(&jump(), &chain(), &touchdown_anchor).reintrusion_episodes,
            2
        );
        let none = GroundLaw::resolve(ModelName::Eq1Linear, &ModelOverrides::default());
        assert_eq!(Regime::of(&jump(), &chain(), &none).reintrusion_episodes, 0);
        let hard = Regime::of(
            &jump(),
            &chain(),
            &GroundLaw::resolve(ModelName::Hard, &ModelOverrides::default()),
        );
        assert_eq!(
            (
                hard.pushes_during_grain_motion,
                hard.earliest_push_after_touchdown_s
            ),
            (0, r.earliest_push_after_touchdown_s)
        );
    }

    #[test]
    fn a_stroke_that_keeps_its_lead_under_an_alternative_does_not_rely_on_it() {
        let row = |answer_alt: f64, paper_alt: f64| Rescore {
            tag: "t".into(),
            rule: "r".into(),
            alternative: "a".into(),
            answer_value: 0.4,
            answer_value_alternative: answer_alt,
            paper_value: 0.2,
            paper_value_alternative: paper_alt,
            answer_height_alternative_m: answer_alt,
            paper_height_alternative_m: paper_alt,
            violation: String::new(),
        };
        // Both lose a quarter: the lead (2x) is the same.
        assert!(!row(0.3, 0.15).relied_on());
        // The answer loses more than the paper's best: its lead shrinks to 1.5x.
        assert!(row(0.3, 0.2).relied_on());
        // Its lead is gone.
        assert!(row(0.19, 0.2).relied_on());
        // It breaks a limit under the alternative.
        assert!(row(f64::NAN, 0.2).relied_on());
        // The answer is the paper's best: no lead to lose.
        let same = Rescore {
            answer_value: 0.2,
            answer_value_alternative: 0.07,
            paper_value_alternative: 0.07,
            ..row(0.0, 0.0)
        };
        assert!(!same.relied_on());
    }
}
