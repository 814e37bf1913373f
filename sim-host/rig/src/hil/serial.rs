//! Hardware in the loop on the real board: the F407 firmware in its lockstep HIL mode, frames
//! over its USB CDC port (`--link serial:/dev/ttyACM0`). The session protocol, the frames and
//! all host code are the ones PIL uses ([`super::framed::FramedLink`]); only the byte stream
//! differs. USB CDC ignores the baud rate; the port is opened raw (8N1, no flow control).
//!
//! Not testable without a board: it compiles and is exercised by the same `FramedLink` as PIL.

use std::time::Duration;

use super::framed::FramedLink;
use super::link::LinkError;

/// Open the board's serial port at `path` and wait for its hello (`Status`).
pub fn start(path: &str, answer_timeout: Duration) -> Result<FramedLink, LinkError> {
    let io = |what: &str| {
        let what = format!("{what} {path}");
        move |e: serialport::Error| LinkError::Io {
            what: what.clone(),
            message: e.to_string(),
        }
    };
    let port = serialport::new(path, 12_000_000)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        // The board writes only while the host holds DTR (docs/firmware.md); Windows opens
        // ports without it.
        .dtr_on_open(true)
        .timeout(Duration::from_millis(100))
        .open()
        .map_err(io("opening serial port"))?;
    let reader = port.try_clone().map_err(io("cloning serial port"))?;
    FramedLink::start(
        format!("serial:{path}"),
        Box::new(reader),
        Box::new(port),
        None,
        answer_timeout,
    )
}
