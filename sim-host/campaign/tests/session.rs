//! A campaign session called as a library: one point through sil, stopped, resumed and
//! finished, its status read between; and the refusals a session gives.

use std::path::{Path, PathBuf};

use sandjumper_campaign::session::{self, point_line};
use sandjumper_campaign::{
    CampaignError, Hooks, ResumeRequest, RunRequest, SessionOutcome, StatusRequest,
};
use sandjumper_output::{Blame, Blamed, Silent};

/// The repository's small campaign cut to one point, without camera and analyses.
fn one_point(dir: &Path) -> PathBuf {
    let small = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/campaign-small.toml"
    );
    let text = std::fs::read_to_string(small)
        .unwrap()
        .replace(r#"kinds = ["single", "delayed"]"#, r#"kinds = ["single"]"#)
        .replace("frequencies_hz = [10.0, 14.0]", "frequencies_hz = [10.0]")
        .replace("phis = [0.58, 0.61]", "phis = [0.58]")
        .replace("fps = 200", "fps = 0")
        .replace("track = true", "track = false")
        .replace("replay = true", "replay = false");
    let p = dir.join("one.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn a_one_point_campaign_stops_resumes_and_finishes_with_typed_outcomes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("one");
    let request = RunRequest {
        file: one_point(tmp.path()),
        link: Some("sil".into()),
        out: out.clone(),
        stop_after: Some(0),
        ..RunRequest::default()
    };
    let stopped = session::run(&request, Hooks::default(), &Silent).unwrap();
    assert_eq!(
        stopped,
        SessionOutcome::Stopped {
            this_session: 0,
            done: 0,
            total: 1,
            out: out.clone()
        }
    );
    let status = session::status(&StatusRequest { dir: out.clone() }).unwrap();
    assert_eq!(
        (status.state.as_str(), status.points),
        ("stopped (resumable)", 1)
    );
    assert_eq!((status.link.as_str(), status.sessions), ("sil", 1));

    // One session at a time: while another process holds the journal, the status says it is
    // running and a resume is refused, naming the holder.
    let journal = tmp.path().join("one.incomplete/journal.jsonl");
    let held = sandjumper_output::WriterLock::take(&journal).unwrap();
    let status = session::status(&StatusRequest { dir: out.clone() }).unwrap();
    assert_eq!(status.state, "running");
    let busy = ResumeRequest {
        dir: out.clone(),
        ..ResumeRequest::default()
    };
    let e = session::resume(&busy, Hooks::default(), &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string().contains("is being run by another session"),
        "{e}"
    );
    if Path::new("/proc/locks").exists() {
        let holder = format!("process {} on ", std::process::id());
        assert!(e.to_string().contains(&holder), "{e}");
    }
    drop(held);

    let mut lines = Vec::new();
    let hooks = Hooks {
        live: None,
        on_point: Some(Box::new(|row, line| {
            assert_eq!(line, point_line(row, 1));
            lines.push(line.to_string());
        })),
    };
    let resume = ResumeRequest {
        dir: out.clone(),
        ..ResumeRequest::default()
    };
    let finished = session::resume(&resume, hooks, &Silent).unwrap();
    let SessionOutcome::Finished {
        done,
        failed,
        sessions,
        ..
    } = &finished
    else {
        panic!("{finished:?}");
    };
    assert_eq!((*done, *failed, *sessions), (1, 0, 2));
    assert_eq!(lines.len(), 1);
    assert!(lines[0].starts_with("point    1/1  single"), "{}", lines[0]);
    assert!(out.join("results.csv").is_file());
    assert!(
        finished
            .to_string()
            .contains("1 points done (0 failed or faulted) over 2 session(s)")
    );
    let status = session::status(&StatusRequest { dir: out.clone() }).unwrap();
    assert_eq!((status.state.as_str(), status.done), ("finished", 1));

    // A finished campaign is not resumed, nor run over.
    let e = session::resume(&resume, Hooks::default(), &Silent).unwrap_err();
    assert!(
        e.to_string()
            .ends_with("the campaign is finished; nothing to resume"),
        "{e}"
    );
    let e = session::run(&request, Hooks::default(), &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string().contains("exists (allowed: a new folder"),
        "{e}"
    );
}

#[test]
fn a_link_other_than_sil_and_pil_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let request = RunRequest {
        file: one_point(tmp.path()),
        link: Some("f407".into()),
        out: tmp.path().join("x"),
        ..RunRequest::default()
    };
    assert_eq!(
        request.validate(),
        Err(CampaignError::Input(
            "--link f407 (allowed: sil, pil; a board is --port PATH)".into()
        ))
    );
    assert!(session::run(&request, Hooks::default(), &Silent).is_err());
    assert!(!tmp.path().join("x.incomplete").exists());
    let e = session::status(&StatusRequest {
        dir: tmp.path().join("x"),
    })
    .unwrap_err();
    assert!(e.to_string().contains("no campaign here"), "{e}");
}

#[test]
fn a_live_views_pace_is_refused_with_the_command_lines_words() {
    assert!(session::check_pace(None).is_ok());
    let e = session::check_pace(Some(2.0)).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert_eq!(
        e.to_string(),
        "--pace 2: a campaign's points are not paced, each is shown when it is done (allowed: --live and --linger only)"
    );
    assert!(matches!(
        session::stop_event(1, "why".into()),
        sandjumper_live::Event::Campaign(sandjumper_live::CampaignRecord::Stop {
            exit_status: 1,
            ..
        })
    ));
}

/// A caller that stops the session as soon as it is asked (Ctrl-C in a face).
struct StopNow;

impl sandjumper_output::Progress for StopNow {
    fn cancelled(&self) -> bool {
        true
    }
}

/// A session its caller stops ends as `stop_after` does, before its next point (the journal
/// holds every point done; `resume` goes on). Tried: without the session's check, the point
/// ran and the session finished.
#[test]
fn a_session_stopped_by_its_caller_is_resumable() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("one");
    let request = RunRequest {
        file: one_point(tmp.path()),
        link: Some("sil".into()),
        out: out.clone(),
        ..RunRequest::default()
    };
    let stopped = session::run(&request, Hooks::default(), &StopNow).unwrap();
    assert_eq!(
        stopped,
        SessionOutcome::Stopped {
            this_session: 0,
            done: 0,
            total: 1,
            out: out.clone()
        }
    );
    let finished = session::resume(
        &ResumeRequest {
            dir: out.clone(),
            ..ResumeRequest::default()
        },
        Hooks::default(),
        &Silent,
    )
    .unwrap();
    assert!(
        matches!(finished, SessionOutcome::Finished { done: 1, .. }),
        "{finished:?}"
    );
}
