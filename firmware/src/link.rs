//! The board-independent half of the host link, used by both boards: what a decoded frame does
//! to the core's [`Rig`], and how the rig's sample records and faults leave as messages.
//! Encoding, decoding and the rig itself are `sandjumper-core`; this only routes.

use sandjumper_core::protocol::{FaultReport, SAMPLE_BATCH};
use sandjumper_core::{Command, FaultCode, Rejection, Rig, RigMessage, SampleRecord};

/// Handles one host command and returns the reply to send (same `id`). Feeds the rig's
/// host-link watchdog and frame counters.
pub fn reply_to<const Q: usize>(rig: &mut Rig<Q>, id: u16, command: &Command) -> RigMessage {
    rig.note_frame_ok();
    let result = rig.handle(command).map_err(|e| Rejection::from(&e));
    RigMessage::Reply { id, result }
}

/// The fault report to send if a fault was latched since `before` was read.
pub fn newly_latched<const Q: usize>(
    rig: &Rig<Q>,
    before: Option<FaultCode>,
) -> Option<RigMessage> {
    match (before, rig.fault()) {
        (None, Some(code)) => Some(RigMessage::Fault(FaultReport {
            code,
            tick: rig.status().fault_tick,
        })),
        _ => None,
    }
}

/// Moves sample records into [`RigMessage::Samples`] batches of [`SAMPLE_BATCH`] and hands
/// each to `send`; a partial batch is sent only if `flush`. Returns the batches sent.
pub fn send_sample_batches(
    mut next: impl FnMut() -> Option<SampleRecord>,
    waiting: usize,
    flush: bool,
    mut send: impl FnMut(RigMessage),
) -> usize {
    let mut batches = 0;
    let mut left = waiting;
    while left >= SAMPLE_BATCH || (flush && left > 0) {
        let mut batch = heapless::Vec::new();
        while !batch.is_full() {
            let Some(record) = next() else { break };
            // Cannot fail: checked `is_full`.
            let _ = batch.push(record);
        }
        if batch.is_empty() {
            break;
        }
        left = left.saturating_sub(batch.len());
        send(RigMessage::Samples(batch));
        batches += 1;
    }
    batches
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_core::{RigConfig, RigState, TickInput, TickTiming};

    fn rig() -> Rig<64> {
        Rig::new(RigConfig::default()).expect("default rig configuration is valid")
    }

    fn tick(rig: &mut Rig<64>, raw: u32) {
        rig.tick(&TickInput {
            encoder_raw: raw,
            current_a: None,
            timing: TickTiming::Unknown,
        });
    }

    #[test]
    fn an_illegal_command_is_rejected_with_its_id_and_changes_nothing() {
        let mut rig = rig();
        let reply = reply_to(&mut rig, 7, &Command::Start);
        assert!(matches!(
            reply,
            RigMessage::Reply {
                id: 7,
                result: Err(Rejection::IllegalInState { .. })
            }
        ));
        assert_eq!(rig.state(), RigState::Idle);
        assert_eq!(rig.status().counters.frames_ok, 1);
    }

    #[test]
    fn a_fault_is_reported_once_with_its_tick() {
        let mut rig = rig();
        tick(&mut rig, 0);
        let before = rig.fault();
        tick(&mut rig, 1 << 30); // far more than max_counts_per_tick: encoder fault
        let report = newly_latched(&rig, before);
        assert_eq!(
            report,
            Some(RigMessage::Fault(FaultReport {
                code: FaultCode::EncoderFault,
                tick: 1
            }))
        );
        assert_eq!(newly_latched(&rig, rig.fault()), None);
    }

    #[test]
    fn samples_leave_in_full_batches_in_sequence_and_the_rest_on_flush() {
        let mut rig = rig();
        for t in 0..40 {
            tick(&mut rig, t);
        }
        let mut seqs = Vec::new();
        let mut collect = |m: RigMessage| match m {
            RigMessage::Samples(batch) => {
                seqs.push(batch.iter().map(|r| r.seq).collect::<Vec<_>>())
            }
            other => panic!("unexpected {other:?}"),
        };
        let waiting = rig.samples().len();
        assert_eq!(
            send_sample_batches(|| rig.samples().pop(), waiting, false, &mut collect),
            2
        );
        let waiting = rig.samples().len();
        assert_eq!(waiting, 40 - 2 * SAMPLE_BATCH);
        assert_eq!(
            send_sample_batches(|| rig.samples().pop(), waiting, true, &mut collect),
            1
        );
        let all: Vec<u32> = seqs.concat();
        assert_eq!(all, (0..40).collect::<Vec<_>>());
        assert_eq!(seqs[0].len(), SAMPLE_BATCH);
    }
}
