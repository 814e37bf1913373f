//! The protocol layer both the loop runs ([`crate::hil`]) and the rig tool ([`crate::tool`])
//! stand on: [`link`] ([`RigLink`], the one interface to a controller, and its errors), the
//! controller's status and bringing it to Idle.

pub mod link;

use link::{LinkError, RigLink};
use sandjumper_core::{Command, Reply, RigState, Status};

fn status_of(reply: Reply) -> Result<Status, LinkError> {
    match reply {
        Reply::Status(s) => Ok(s),
        Reply::Ack => Err(LinkError::Protocol(
            "a status query was answered with a plain Ack".into(),
        )),
    }
}

/// Ask for the controller's status.
pub fn query_status(link: &mut dyn RigLink) -> Result<Status, LinkError> {
    status_of(link.command(&Command::StatusQuery)?)
}

/// Bring a controller left Armed, Running, Done or Faulted by an earlier session to Idle.
pub fn bring_to_idle(link: &mut dyn RigLink) -> Result<(), LinkError> {
    match query_status(link)?.state {
        RigState::Faulted => {
            link.command(&Command::ClearFault)?;
        }
        RigState::Armed | RigState::Running | RigState::Done => {
            link.command(&Command::Abort)?;
        }
        RigState::Idle => {}
    }
    Ok(())
}
