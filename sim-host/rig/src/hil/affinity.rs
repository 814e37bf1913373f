//! One core for a processor-in-the-loop session: QEMU and the host's lockstep threads pinned
//! together.
//!
//! A lockstep tick is three hand-offs between processes and threads (the host writes a sensor
//! frame, QEMU's vCPU answers, the host's reader thread passes the answer on). When those
//! threads sit on different cores, every hand-off is a cross-core wake-up: on a virtual
//! machine an inter-processor interrupt, which costs far more than the tick itself. Measured
//! on a 2-core VM for the delayed stutter (10 Hz, tau 0.3 s, eq4, phi 0.57; 8,523 ticks): about
//! 60 us a tick unpinned (1.6-1.8x real time, 26 k context switches, 6 k migrations), about
//! 23 us pinned to one core (4.3-4.4x). See `docs/performance.md`.
//!
//! [`PinnedThread::pin`] pins the calling thread to one allowed core; a process it spawns
//! and the threads it creates inherit that mask, so QEMU and the reader thread share the
//! core. The guard restores the thread's previous mask when dropped. Several sessions at once
//! (parallel tests) are spread over the allowed cores in turn. Linux only; elsewhere a no-op.

/// The calling thread pinned to one core until this guard is dropped.
#[derive(Debug)]
pub struct PinnedThread {
    #[cfg(target_os = "linux")]
    previous: Option<libc::cpu_set_t>,
}

#[cfg(target_os = "linux")]
impl PinnedThread {
    /// Pin the calling thread to one of the cores it may run on (the next in turn). When the
    /// mask cannot be read or set, nothing is pinned and the session runs unpinned.
    pub fn pin() -> Self {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        // SAFETY: cpu_set_t is plain data; the calls get a valid pointer and its size.
        unsafe {
            let mut previous: libc::cpu_set_t = std::mem::zeroed();
            let size = std::mem::size_of::<libc::cpu_set_t>();
            if libc::sched_getaffinity(0, size, &mut previous) != 0 {
                return Self { previous: None };
            }
            let allowed: Vec<usize> = (0..libc::CPU_SETSIZE as usize)
                .filter(|&c| libc::CPU_ISSET(c, &previous))
                .collect();
            if allowed.len() < 2 {
                return Self { previous: None };
            }
            let core = allowed[NEXT.fetch_add(1, Ordering::Relaxed) % allowed.len()];
            let mut one: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(core, &mut one);
            if libc::sched_setaffinity(0, size, &one) != 0 {
                return Self { previous: None };
            }
            Self {
                previous: Some(previous),
            }
        }
    }

    /// The thread is pinned (false: it could not be, or it had one core to begin with).
    pub fn is_pinned(&self) -> bool {
        self.previous.is_some()
    }
}

#[cfg(target_os = "linux")]
impl Drop for PinnedThread {
    fn drop(&mut self) {
        if let Some(previous) = &self.previous {
            // SAFETY: as in `pin`; restoring a mask the thread had is always allowed.
            unsafe {
                libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), previous);
            }
        }
    }
}

#[cfg(not(target_os = "linux"))]
impl PinnedThread {
    /// No pinning on this platform.
    pub fn pin() -> Self {
        Self {}
    }

    /// Always false here.
    pub fn is_pinned(&self) -> bool {
        false
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    fn allowed_cores() -> usize {
        // SAFETY: as in `pin`.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            assert_eq!(
                libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set),
                0
            );
            libc::CPU_COUNT(&set) as usize
        }
    }

    #[test]
    fn pinning_holds_one_core_and_dropping_restores_the_mask() {
        std::thread::spawn(|| {
            let before = allowed_cores();
            let pin = PinnedThread::pin();
            if before >= 2 {
                assert!(pin.is_pinned());
                assert_eq!(allowed_cores(), 1);
                // A thread spawned now inherits the one core.
                let inner = std::thread::spawn(allowed_cores).join().unwrap();
                assert_eq!(inner, 1);
            }
            drop(pin);
            assert_eq!(allowed_cores(), before);
        })
        .join()
        .unwrap();
    }
}
