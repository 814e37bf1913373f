//! The rig tool's programs through the other simulated controllers, measured against sil: the
//! real firmware in QEMU (`LinkArg::Pil`, skipped without QEMU and the firmware toolchain
//! except under CI) and the F407 release binary on the virtual board (`LinkArg::F407`,
//! skipped without `sim-host/virtual-f407/build.sh`'s program and the F407 build except under
//! CI). Called as the library's typed requests; the command line's `--link pil` contract is in
//! `sim-host/cli/tests/integration/rig_tool.rs`.

use sandjumper_core::RigState;
use sandjumper_core::reset::ResetCause;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::params::ModelName;
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil_command::{self, HilRequest};
use sandjumper_rig::tool::intrude::{self, IntrudeRequest};
use sandjumper_rig::tool::jump::{self, JumpOutcome, JumpRequest};
use sandjumper_rig::tool::replay;
use sandjumper_rig::tool::status::status;
use sandjumper_rig::tool::target::Target;

use crate::common;
use common::{qemu_firmware, replay_error, replay_of_log, virtual_board};

/// `rig jump` of `kind` at 10 Hz (delay `tau_s`) on `target`, completed.
fn jump_on(target: Target, kind: JumpKind, tau_s: Option<f64>) -> JumpOutcome {
    let request = JumpRequest {
        tau_s,
        ..JumpRequest::new(target, kind, 10.0)
    };
    let outcome = jump::run(&request, &Silent).expect("the jump runs");
    assert!(outcome.completed, "{}: {:?}", outcome.link, outcome.faults);
    outcome
}

/// The firmware in QEMU reports an idle controller, and runs the 10 Hz single jump to the same
/// number of samples and a simulated jump height within 0.5 % of sil's.
#[test]
fn status_and_jump_through_pil_match_sil() {
    let Some(elf) = qemu_firmware() else { return };
    let pil = Target {
        firmware: Some(elf),
        ..Target::on(LinkArg::Pil)
    };
    let report = status(&pil, &Silent).unwrap();
    assert_eq!(report.link, "pil");
    assert_eq!(report.status.state, RigState::Idle);
    let p = jump_on(pil, JumpKind::Single, None);
    let q = jump_on(Target::on(LinkArg::Sil), JumpKind::Single, None);
    assert_eq!(p.samples, q.samples);
    let (hp, hq) = (
        p.simulated_jump_height_m.expect("a simulated rig"),
        q.simulated_jump_height_m.expect("a simulated rig"),
    );
    assert!((hp / hq - 1.0).abs() < 0.005, "PIL {hp} m vs SIL {hq} m");
}

/// The F407 binary on the virtual board reports an idle controller after a power-on reset,
/// and runs the paper's delayed stutter (10 Hz, 0.1 s) to within 1 mm of sil's simulated jump
/// height (measured 62.69 mm against 62.82 mm); `hil` on the board runs the same program the
/// same way (within 1 mm: the virtual time of the Start varies from run to run, seen 0.45 mm
/// apart, since the host polls the board's ticks every 50 ms of wall time).
#[test]
fn status_and_jump_through_the_f407_binary_match_sil() {
    if virtual_board().is_none() {
        return;
    }
    let board = Target::on(LinkArg::F407);
    let report = status(&board, &Silent).unwrap();
    assert_eq!(report.status.state, RigState::Idle);
    assert_eq!(report.status.reset_cause, ResetCause::PowerOn);
    let delayed = |target| {
        jump_on(target, JumpKind::DelayedStutter, Some(0.1))
            .simulated_jump_height_m
            .expect("a height")
    };
    let (f407, sil) = (delayed(board), delayed(Target::on(LinkArg::Sil)));
    let hil = hil_command::run(
        &HilRequest {
            link: LinkArg::F407,
            kind: JumpKind::DelayedStutter,
            freq_hz: 10.0,
            tau_s: Some(0.1),
            ..HilRequest::default()
        },
        &Silent,
    )
    .expect("hil runs on the board");
    let json: serde_json::Value = serde_json::from_str(&hil.json().unwrap()).unwrap();
    assert_eq!(json["link"], "f407");
    let h407 = hil.jump_height_m().expect("a height");
    assert!(
        (h407 - f407).abs() < 1e-3,
        "hil {h407} m, rig jump {f407} m"
    );
    // The bound: within 1 mm of sil.
    assert!((f407 - sil).abs() < 1e-3, "f407 {f407} m, sil {sil} m");
}

/// The slow intrusion into `eq1` sand through the F407 binary measures the force at its 20 mm
/// depth within 0.5 N of sil's; a sil jump replayed on the board follows it within 1.5 mm,
/// 0.5 mm RMS (measured max 0.91 mm, rms 0.21 mm). A shorter program than the command's
/// defaults (20 mm/s, 0.1 s holds; `sandjumper rig intrude --link f407 --model eq1 --out DIR`
/// runs the defaults' 10 mm/s and 0.5 s holds, measured 29.29 N against sil's 29.34 N).
#[test]
fn intrusion_and_replay_through_the_f407_binary_match_sil() {
    if virtual_board().is_none() {
        return;
    }
    let force_at_20_mm = |link: LinkArg| -> f64 {
        let request = IntrudeRequest {
            target: Target::on(link),
            model: ModelName::Eq1,
            speed_m_s: 0.02,
            hold_s: 0.1,
            ..IntrudeRequest::default()
        };
        let outcome = intrude::run(&request, &Silent).expect("the intrusion runs");
        assert!(outcome.completed, "{}: {:?}", outcome.link, outcome.faults);
        assert!((outcome.depth_m - 0.02).abs() < 1e-9);
        outcome.force_at_depth_n.expect("the force at the depth")
    };
    let (f407, sil) = (force_at_20_mm(LinkArg::F407), force_at_20_mm(LinkArg::Sil));
    assert!(
        (f407 - sil).abs() < 0.5,
        "force at 20 mm: f407 {f407} N, sil {sil} N"
    );
    let original = jump_on(Target::on(LinkArg::Sil), JumpKind::Single, None);
    let request = replay_of_log(Target::on(LinkArg::F407), &original.log, "jump.csv");
    let outcome = replay::run(&request, &Silent).expect("the replay runs");
    assert!(outcome.completed, "{:?}", outcome.fault_names());
    let (max, rms) = replay_error(&original.log, &outcome.log);
    assert!(max < 1.5e-3 && rms < 0.5e-3, "max {max} m, rms {rms} m");
}
