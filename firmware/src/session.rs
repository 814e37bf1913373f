//! How the emulated board is told what to do, and how it says how it ended.
//!
//! The semihosting command line (QEMU `-semihosting-config enable=on,arg=...`, or the
//! arguments after the ELF in `firmware/qemu-run.sh`) selects the session:
//!
//! | command line | session |
//! |---|---|
//! | (empty) or `selftest [ticks=N] [inject=encoder-jump]` | synthetic sensor feed, tick-cost report |
//! | `fifo IN_PATH OUT_PATH` | lockstep over two host FIFOs via semihosting |
//! | `uart` | lockstep over the CMSDK UART0 |
//! | `hang` | never ends (to test the runner's timeout) |
//!
//! Exit status (QEMU's own, via semihosting `SYS_EXIT_EXTENDED`): see [`ExitStatus`].

/// QEMU's exit status at the end of a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExitStatus {
    /// 0: the session ended cleanly (host closed the link with no fault latched; self-test
    /// passed).
    Clean,
    /// 1: the firmware panicked (force was zeroed first).
    Panic,
    /// 2: a HardFault (force was zeroed first).
    HardFault,
    /// 3: the command line was not understood.
    Usage,
    /// 4: the host link could not be opened, or a write failed.
    LinkError,
    /// 5: the self-test found the core misbehaving (message on the console).
    SelfTestFailed,
    /// 16 + code: the session ended with this core fault latched (codes 1..=8, see the core's
    /// fault table), e.g. 19 = encoder fault, 24 = link lost (EOF while armed or running).
    Fault(u8),
}

impl ExitStatus {
    /// Offset added to a core fault code.
    pub const FAULT_BASE: u32 = 16;

    /// The process exit status QEMU returns.
    pub fn code(self) -> u32 {
        match self {
            Self::Clean => 0,
            Self::Panic => 1,
            Self::HardFault => 2,
            Self::Usage => 3,
            Self::LinkError => 4,
            Self::SelfTestFailed => 5,
            Self::Fault(code) => Self::FAULT_BASE + u32::from(code),
        }
    }
}

/// A fault the self-test injects into its synthetic sensor feed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Injection {
    /// The encoder count jumps by far more than is physically possible in one tick, halfway.
    EncoderJump,
}

/// What the command line asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Session<'a> {
    /// Synthetic sensor feed for `ticks` control ticks (0 = the whole default jump).
    SelfTest {
        ticks: u32,
        inject: Option<Injection>,
    },
    /// Lockstep over the semihosting FIFOs.
    Fifo { input: &'a str, output: &'a str },
    /// Lockstep over the CMSDK UART0.
    Uart,
    /// Spin forever.
    Hang,
}

/// A command line that could not be understood: the offending word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UsageError<'a>(pub &'a str);

impl<'a> Session<'a> {
    /// Parses the semihosting command line (words separated by spaces).
    pub fn parse(command_line: &'a str) -> Result<Self, UsageError<'a>> {
        let mut words = command_line.split_ascii_whitespace();
        let session = match words.next() {
            None => {
                return Ok(Self::SelfTest {
                    ticks: 0,
                    inject: None,
                });
            }
            Some("selftest") => {
                let mut ticks = 0;
                let mut inject = None;
                for word in words.by_ref() {
                    if let Some(n) = word.strip_prefix("ticks=") {
                        ticks = n.parse().map_err(|_| UsageError(word))?;
                    } else if word == "inject=encoder-jump" {
                        inject = Some(Injection::EncoderJump);
                    } else {
                        return Err(UsageError(word));
                    }
                }
                Self::SelfTest { ticks, inject }
            }
            Some("fifo") => {
                let input = words
                    .next()
                    .ok_or(UsageError("fifo needs IN_PATH OUT_PATH"))?;
                let output = words
                    .next()
                    .ok_or(UsageError("fifo needs IN_PATH OUT_PATH"))?;
                Self::Fifo { input, output }
            }
            Some("uart") => Self::Uart,
            Some("hang") => Self::Hang,
            Some(other) => return Err(UsageError(other)),
        };
        match words.next() {
            Some(extra) => Err(UsageError(extra)),
            None => Ok(session),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_command_line_is_the_self_test() {
        assert_eq!(
            Session::parse(""),
            Ok(Session::SelfTest {
                ticks: 0,
                inject: None
            })
        );
        assert_eq!(
            Session::parse("  "),
            Ok(Session::SelfTest {
                ticks: 0,
                inject: None
            })
        );
    }

    #[test]
    fn sessions_parse_with_their_arguments() {
        assert_eq!(
            Session::parse("selftest ticks=500 inject=encoder-jump"),
            Ok(Session::SelfTest {
                ticks: 500,
                inject: Some(Injection::EncoderJump)
            })
        );
        assert_eq!(
            Session::parse("fifo /tmp/a.in /tmp/a.out"),
            Ok(Session::Fifo {
                input: "/tmp/a.in",
                output: "/tmp/a.out"
            })
        );
        assert_eq!(Session::parse("uart"), Ok(Session::Uart));
        assert_eq!(Session::parse("hang"), Ok(Session::Hang));
    }

    #[test]
    fn bad_words_are_named() {
        assert_eq!(
            Session::parse("selftest ticks=many"),
            Err(UsageError("ticks=many"))
        );
        assert_eq!(Session::parse("fly"), Err(UsageError("fly")));
        assert_eq!(Session::parse("uart extra"), Err(UsageError("extra")));
        assert_eq!(
            Session::parse("fifo /only/one"),
            Err(UsageError("fifo needs IN_PATH OUT_PATH"))
        );
    }

    #[test]
    fn fault_exit_status_is_offset_and_distinct_from_the_others() {
        assert_eq!(ExitStatus::Clean.code(), 0);
        assert_eq!(ExitStatus::Fault(3).code(), 19);
        for code in 1..=8 {
            let status = ExitStatus::Fault(code).code();
            assert!(
                status > ExitStatus::LinkError.code() && status != 124,
                "{status}"
            );
        }
    }
}
