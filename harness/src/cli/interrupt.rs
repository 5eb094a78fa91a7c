//! Ctrl-C, SIGTERM and SIGHUP: the first asks the command to stop after the iteration in
//! progress and write what it completed; the second ends the process at once. Hours of
//! rendering are not lost to a key pressed once.

use anyhow::{Context, Result};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use thiserror::Error;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Exit status of a command stopped by a signal: 128 + SIGINT, as shells report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Installs the handler; commands that honour [`requested`] call it before they start.
pub fn install() -> Result<()> {
    ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            eprintln!("\ninterrupted again: stopping now");
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        eprintln!(
            "\ninterrupted: finishing the current iteration and writing what is done \
             (interrupt again to stop at once)"
        );
    })
    .context("cannot install the interrupt handler")
}

/// Whether an interrupt asked the command to stop.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// [`requested`] as a progress callback's answer.
pub fn flow() -> ControlFlow<()> {
    if requested() {
        ControlFlow::Break(())
    } else {
        ControlFlow::Continue(())
    }
}

/// What a command returns once it has written what an interruption left it: `main` exits
/// with [`EXIT_INTERRUPTED`].
#[derive(Debug, Error)]
#[error("interrupted: {0}")]
pub struct Interrupted(pub String);
