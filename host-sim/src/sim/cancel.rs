//! Cooperative cancellation of long work: the closed loop polls
//! [`requested`] once per 1 kHz tick and ends with [`Cancelled`] when it is
//! set, so a command unwinds normally and its temporary output directories
//! are removed by their `Drop` (nothing half-written is left behind).
//!
//! Two sources: SIGINT and SIGTERM, after [`install_signal_handlers`] (the
//! CLI; a second signal ends the process at once, exit status 130), and a
//! caller's flag for the work run on the current thread ([`with_flag`]; the
//! Python package sets it when Ctrl-C arrives).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// The number of the last SIGINT or SIGTERM received (0: none).
fn signal_flag() -> &'static Arc<AtomicUsize> {
    static FLAG: OnceLock<Arc<AtomicUsize>> = OnceLock::new();
    FLAG.get_or_init(|| Arc::new(AtomicUsize::new(0)))
}

thread_local! {
    /// The flag of [`with_flag`] on this thread.
    static FLAG: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// The work ended early because cancellation was requested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled {
    /// The signal that asked for it (`SIGINT` = 2, `SIGTERM` = 15), or `None`
    /// for a caller's flag.
    pub signal: Option<i32>,
}

impl core::fmt::Display for Cancelled {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.signal {
            Some(signal_hook::consts::SIGINT) => f.write_str("interrupted (SIGINT)"),
            Some(signal_hook::consts::SIGTERM) => f.write_str("terminated (SIGTERM)"),
            Some(s) => write!(f, "stopped by signal {s}"),
            None => f.write_str("cancelled"),
        }
    }
}

impl std::error::Error for Cancelled {}

/// Makes SIGINT and SIGTERM request cancellation ([`requested`]) instead of
/// killing the process; a second one ends the process at once (status 130).
pub fn install_signal_handlers() -> std::io::Result<()> {
    let armed = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // The shutdown goes first: it acts only once `armed` is set, by the
        // first signal (signal_hook::flag::register_conditional_shutdown).
        signal_hook::flag::register_conditional_shutdown(sig, 130, Arc::clone(&armed))?;
        signal_hook::flag::register(sig, Arc::clone(&armed))?;
        signal_hook::flag::register_usize(sig, Arc::clone(signal_flag()), sig as usize)?;
    }
    Ok(())
}

/// Runs `f` on this thread with `flag` as an extra source of cancellation:
/// [`requested`] is true, on this thread, once `flag` is set.
pub fn with_flag<R>(flag: Arc<AtomicBool>, f: impl FnOnce() -> R) -> R {
    let old = FLAG.with(|c| c.replace(Some(flag)));
    let r = f();
    FLAG.with(|c| *c.borrow_mut() = old);
    r
}

/// `Err` when cancellation was requested: by a signal, or by the flag of
/// [`with_flag`] on this thread.
pub fn check() -> Result<(), Cancelled> {
    match signal_flag().load(Ordering::Relaxed) {
        0 => {}
        s => {
            return Err(Cancelled {
                signal: i32::try_from(s).ok(),
            });
        }
    }
    let flagged = FLAG.with(|c| {
        c.borrow()
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    });
    if flagged {
        Err(Cancelled { signal: None })
    } else {
        Ok(())
    }
}

/// Whether cancellation was requested ([`check`]).
pub fn requested() -> bool {
    check().is_err()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flag_cancels_only_its_own_thread_and_only_inside_with_flag() {
        let flag = Arc::new(AtomicBool::new(true));
        assert_eq!(
            with_flag(Arc::clone(&flag), check),
            Err(Cancelled { signal: None })
        );
        assert!(!requested(), "the flag is gone after with_flag");
        let other = std::thread::spawn(requested);
        assert!(!with_flag(flag, || other.join().unwrap()));
    }
}
