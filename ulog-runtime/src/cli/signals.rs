//! Ctrl-C (SIGINT) and SIGTERM for a process that is the `ulog` tool ([`handle_signals`]):
//! while a verb that can stop cleanly runs its work (`ulog parquet`, between logs), the
//! first signal asks it to stop and a second ends the process at once. Otherwise, and
//! without the call, the signals do what the process's own handlers do ([`main`](super::main)
//! sets none of its own).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Whether the process is the tool ([`handle_signals`]).
static AS_PROCESS: AtomicBool = AtomicBool::new(false);

/// The handlers' flags, once a stoppable verb set them up.
static FLAGS: OnceLock<Flags> = OnceLock::new();

struct Flags {
    /// A signal asked to stop.
    stop: Arc<AtomicBool>,
    /// The signal that asked.
    signal: Arc<AtomicUsize>,
    /// A signal now ends the process at once: outside a stoppable verb's work, or after
    /// the first signal.
    armed: Arc<AtomicBool>,
    /// Every handler was set: `armed` may be cleared.
    working: bool,
}

/// Says that the process is the tool (the `ulog` binary, the Python package's `ulog`
/// command): while `ulog parquet` converts, the first Ctrl-C (SIGINT) or SIGTERM then makes
/// it start no more logs, finish those under way and exit 128 + the signal, and a second
/// ends the process at once with that code. Once `ulog parquet` has set its handlers, a
/// signal at any other time also ends the process at once with that code (signal-hook
/// cannot give the signals' default actions back), so a program that calls
/// [`main`](super::main) among other work should not call this. Unix only; elsewhere the
/// signals end the tool as they always do.
pub fn handle_signals() {
    AS_PROCESS.store(true, Ordering::Relaxed);
}

/// A stoppable verb's work under way ([`stoppable`]): the signals stop it until dropped.
pub(crate) struct Stoppable {
    flags: Option<&'static Flags>,
}

/// For the work of a verb that can stop cleanly: where the process is the tool, the
/// handlers (set up once) let the first signal stop it.
pub(crate) fn stoppable() -> Stoppable {
    if !AS_PROCESS.load(Ordering::Relaxed) {
        return Stoppable { flags: None };
    }
    let flags = FLAGS.get_or_init(install);
    if !flags.working {
        return Stoppable { flags: None };
    }
    if !flags.stop.load(Ordering::Relaxed) {
        flags.armed.store(false, Ordering::Relaxed);
    }
    Stoppable { flags: Some(flags) }
}

impl Stoppable {
    /// Set when a signal asks to stop; never set where the process is not the tool.
    pub(crate) fn flag(&self) -> &AtomicBool {
        static NEVER: AtomicBool = AtomicBool::new(false);
        self.flags.map_or(&NEVER, |f| &*f.stop)
    }

    /// The signal that asked to stop, if one did.
    pub(crate) fn signal(&self) -> Option<usize> {
        let f = self.flags?;
        let signal = f.signal.load(Ordering::Relaxed);
        (f.stop.load(Ordering::Relaxed) && signal != 0).then_some(signal)
    }
}

impl Drop for Stoppable {
    fn drop(&mut self) {
        if let Some(f) = self.flags {
            f.armed.store(true, Ordering::Relaxed);
        }
    }
}

fn install() -> Flags {
    #[cfg_attr(not(unix), allow(unused_mut))]
    let mut flags = Flags {
        stop: Arc::new(AtomicBool::new(false)),
        signal: Arc::new(AtomicUsize::new(0)),
        armed: Arc::new(AtomicBool::new(true)),
        working: cfg!(unix),
    };
    #[cfg(unix)]
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        use signal_hook::flag;
        // The actions run in the order they are registered: the shutdown first, so that a
        // first signal during the work finds `armed` clear, and a second finds it set.
        if flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&flags.armed)).is_err() {
            // Nothing registered for `sig`: it ends the process as before, and cannot
            // stop the work.
            flags.working = false;
            continue;
        }
        // Failing after the shutdown (only if `sigaction` itself fails) would leave a
        // signal that does nothing: `armed` stays set, and every signal ends the process
        // at once.
        let registered = flag::register_usize(
            sig,
            Arc::clone(&flags.signal),
            usize::try_from(sig).unwrap_or(0),
        )
        .and_then(|_| flag::register(sig, Arc::clone(&flags.stop)))
        .and_then(|_| flag::register(sig, Arc::clone(&flags.armed)));
        if registered.is_err() {
            flags.working = false;
        }
    }
    flags
}
