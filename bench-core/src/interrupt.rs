//! Stopping a sweep cleanly on SIGINT (Ctrl-C) or SIGTERM (`timeout`, Slurm, the device tool):
//! the first signal only sets a flag, which the runner reads between rows, so the row being
//! measured is finished and written, `run.json` records `interrupted`, and the process exits.
//! The first signal also arms the default action: a second SIGINT or SIGTERM terminates the
//! process at once, as if no handler were installed (for a row that will not finish).
//!
//! Flag-based through `signal-hook`: the handler stores two atomics and does nothing else.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use signal_hook::consts::{SIGINT, SIGTERM};

use crate::{CoreError, Result};

struct Flags {
    /// Any handled signal arrived; also the condition that makes the next one act as default.
    any: Arc<AtomicBool>,
    /// Number of the last handled signal (0: none).
    which: Arc<AtomicUsize>,
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
    };
    let err = |e: std::io::Error| CoreError::Io(format!("installing signal handlers: {e}"));
    for sig in [SIGINT, SIGTERM] {
        // Order matters: the default action is checked before the flag is set, so it runs only
        // from the second signal on.
        signal_hook::flag::register_conditional_default(sig, Arc::clone(&flags.any))
            .map_err(err)?;
        signal_hook::flag::register_usize(sig, Arc::clone(&flags.which), sig as usize)
            .map_err(err)?;
        signal_hook::flag::register(sig, Arc::clone(&flags.any)).map_err(err)?;
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
