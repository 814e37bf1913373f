//! The STM32F407's reset-status flags (RCC_CSR, RM0090 section 7.3.21) as a [`ResetCause`].
//! Register access stays in `board/f407.rs`; the decoding is plain logic, tested on the host.
//!
//! A power-on reset also sets the pin and brown-out flags (the supply rises through the
//! brown-out level and NRST is held low meanwhile), so the flags are read in order of how
//! much they say: a watchdog, software or low-power reset first, then power-on, then
//! brown-out alone (a dip that did not reach power-off), then the pin alone.

use sandjumper_core::ResetCause;

/// RCC_CSR bit: low-power reset.
pub const LPWRRSTF: u32 = 1 << 31;
/// RCC_CSR bit: window watchdog reset.
pub const WWDGRSTF: u32 = 1 << 30;
/// RCC_CSR bit: independent watchdog reset.
pub const IWDGRSTF: u32 = 1 << 29;
/// RCC_CSR bit: software reset.
pub const SFTRSTF: u32 = 1 << 28;
/// RCC_CSR bit: power-on / power-down reset.
pub const PORRSTF: u32 = 1 << 27;
/// RCC_CSR bit: reset pin (NRST).
pub const PINRSTF: u32 = 1 << 26;
/// RCC_CSR bit: brown-out reset.
pub const BORRSTF: u32 = 1 << 25;

/// The cause of the last reset from RCC_CSR's flags.
pub fn reset_cause(csr: u32) -> ResetCause {
    let set = |bit: u32| csr & bit != 0;
    if set(IWDGRSTF) || set(WWDGRSTF) {
        ResetCause::Watchdog
    } else if set(SFTRSTF) {
        ResetCause::Software
    } else if set(LPWRRSTF) {
        ResetCause::LowPower
    } else if set(PORRSTF) {
        ResetCause::PowerOn
    } else if set(BORRSTF) {
        ResetCause::BrownOut
    } else if set(PINRSTF) {
        ResetCause::Pin
    } else {
        ResetCause::Unknown
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_on_sets_three_flags_and_is_power_on() {
        assert_eq!(
            reset_cause(PORRSTF | PINRSTF | BORRSTF),
            ResetCause::PowerOn
        );
    }

    #[test]
    fn a_watchdog_or_software_reset_wins_over_the_pin_flag_it_also_sets() {
        assert_eq!(reset_cause(IWDGRSTF | PINRSTF), ResetCause::Watchdog);
        assert_eq!(reset_cause(WWDGRSTF | PINRSTF), ResetCause::Watchdog);
        assert_eq!(reset_cause(SFTRSTF | PINRSTF), ResetCause::Software);
        assert_eq!(reset_cause(LPWRRSTF | PINRSTF), ResetCause::LowPower);
        assert_eq!(reset_cause(BORRSTF | PINRSTF), ResetCause::BrownOut);
        assert_eq!(reset_cause(PINRSTF), ResetCause::Pin);
        assert_eq!(reset_cause(0), ResetCause::Unknown);
    }

    #[test]
    fn only_power_on_allows_arm_without_an_acknowledgement() {
        for bit in [LPWRRSTF, WWDGRSTF, IWDGRSTF, SFTRSTF, BORRSTF, PINRSTF, 0] {
            assert!(!reset_cause(bit).is_power_on(), "{bit:#x}");
        }
        assert!(reset_cause(PORRSTF).is_power_on());
    }
}
