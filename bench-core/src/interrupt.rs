//! Stopping a sweep cleanly on SIGINT (Ctrl-C) or SIGTERM (`timeout`, Slurm, the device tool):
//! the first signal only sets a flag, which the runner reads between rows, so the row being
//! measured is finished and written, `run.json` records `interrupted`, and the process exits.
//! The first signal also arms the default action: a second SIGINT or SIGTERM terminates the
//! process at once, as if no handler were installed (for a row that will not finish) — unless it
//! comes within [`REPEAT_GRACE`] of the first: that is one request delivered twice, not a second
//! one. coreutils `timeout` signals its command and then its whole process group, so the command
//! can receive SIGTERM twice within microseconds (seen on the H200: an `aa` sweep killed by the
//! second copy with no summary and no manifest update).
//!
//! The handler stores three atomics and reads the monotonic clock (`clock_gettime`, which is
//! async-signal-safe); the default action is `signal-hook`'s emulation.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use signal_hook::consts::{SIGINT, SIGTERM};

/// A repeat of a stop signal sooner than this after the first is the same request delivered
/// twice and is ignored; a later one terminates the process.
pub const REPEAT_GRACE: Duration = Duration::from_millis(250);

use crate::{CoreError, Result};

struct Flags {
    /// Any handled signal arrived; also the condition that makes the next one act as default.
    any: Arc<AtomicBool>,
    /// Number of the last handled signal (0: none).
    which: Arc<AtomicUsize>,
    /// Nanoseconds after `base` at which the first signal arrived (0: none yet).
    first_ns: Arc<AtomicU64>,
}

static FLAGS: OnceLock<Flags> = OnceLock::new();

/// Installs the handlers for SIGINT and SIGTERM; further calls do nothing.
pub fn install() -> Result<()> {
    static INSTALLING: Mutex<()> = Mutex::new(());
    let _one_at_a_time = INSTALLING.lock().unwrap_or_else(|p| p.into_inner());
    if FLAGS.get().is_some() {
        return Ok(());
    }
    let flags = Flags {
        any: Arc::new(AtomicBool::new(false)),
        which: Arc::new(AtomicUsize::new(0)),
        first_ns: Arc::new(AtomicU64::new(0)),
    };
    let err = |e: std::io::Error| CoreError::Io(format!("installing signal handlers: {e}"));
    let base = Instant::now();
    for sig in [SIGINT, SIGTERM] {
        let (any, which, first_ns) = (
            Arc::clone(&flags.any),
            Arc::clone(&flags.which),
            Arc::clone(&flags.first_ns),
        );
        let action = move || {
            let now = (base.elapsed().as_nanos() as u64).max(1);
            match first_ns.compare_exchange(0, now, Ordering::SeqCst, Ordering::SeqCst) {
                Ok(_) => {
                    which.store(sig as usize, Ordering::SeqCst);
                    any.store(true, Ordering::SeqCst);
                }
                Err(first) if now.saturating_sub(first) >= REPEAT_GRACE.as_nanos() as u64 => {
                    let _ = signal_hook::low_level::emulate_default_handler(sig);
                }
                Err(_) => {} // the first request, delivered again
            }
        };
        // SAFETY: the action only touches atomics and the monotonic clock (clock_gettime is
        // async-signal-safe), and emulate_default_handler is documented async-signal-safe.
        unsafe { signal_hook::low_level::register(sig, action) }.map_err(err)?;
    }
    let _ = FLAGS.set(flags); // cannot fail: checked empty under the lock

    Ok(())
}

/// The signal asking the run to stop (`"SIGINT"` or `"SIGTERM"`, the last one received), or
/// `None` if none arrived or [`install`] was never called.
pub fn requested() -> Option<&'static str> {
    let flags = FLAGS.get()?;
    if !flags.any.load(Ordering::SeqCst) {
        return None;
    }
    match flags.which.load(Ordering::SeqCst) as i32 {
        SIGINT => Some("SIGINT"),
        SIGTERM => Some("SIGTERM"),
        _ => None,
    }
}
