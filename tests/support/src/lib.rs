//! Test binaries whose tests need what a machine may lack: a wgpu adapter, a display, a Slurm
//! cluster. libtest can only pass or fail a test, so a test that could not run here used to
//! pass after a banner the summary hid. These binaries run on [libtest-mimic] instead
//! (`harness = false`), where a [`Need`] that is missing marks the test *ignored*, with its
//! reason, in the summary and in the count; after the summary the binary says what it did not
//! test and what to install. Where the need's variable is set (`PPM_REQUIRE_WGPU=1`, as CI
//! sets it) the same test fails instead.
//!
//! ```no_run
//! use test_support::{Need, Suite};
//!
//! fn main() -> std::process::ExitCode {
//!     let adapter = Need::wgpu(|| Err("no adapter in this example".into()));
//!     Suite::new()
//!         .test("adds_up", || assert_eq!(1 + 1, 2))
//!         .test_needing(&[&adapter], "renders_on_the_gpu", || { /* ... */ })
//!         .run()
//! }
//! ```
//!
//! libtest-mimic captures no output, so a test's figures go through [`figure!`]: kept with
//! the test and shown where it fails, or always with `--nocapture` / `--show-output`, as
//! libtest shows a test's prints.

#![warn(missing_docs)]

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use std::cell::RefCell;
use std::panic::{self, AssertUnwindSafe};
use std::process::{Command, ExitCode, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Something a test needs beyond a CPU and the workspace's code. Cloning shares it: its
/// probe runs once per binary, however many tests need it.
#[derive(Clone)]
pub struct Need(Arc<NeedState>);

struct NeedState {
    what: String,
    variable: String,
    install: String,
    probe: Box<dyn Fn() -> Result<(), String> + Send + Sync>,
    found: OnceLock<Result<(), String>>,
    skipped: AtomicUsize,
}

impl Need {
    /// A need called `what` ("a wgpu adapter"), which `variable=1` makes required, met where
    /// `probe` returns `Ok` (else `Err` says why not); `install` tells a reader what would meet
    /// it.
    pub fn new(
        what: impl Into<String>,
        variable: impl Into<String>,
        install: impl Into<String>,
        probe: impl Fn() -> Result<(), String> + Send + Sync + 'static,
    ) -> Self {
        Self(Arc::new(NeedState {
            what: what.into(),
            variable: variable.into(),
            install: install.into(),
            probe: Box::new(probe),
            found: OnceLock::new(),
            skipped: AtomicUsize::new(0),
        }))
    }

    /// A wgpu adapter, found by `probe` (which opens one); `PPM_REQUIRE_WGPU=1` requires it.
    pub fn wgpu(probe: impl Fn() -> Result<(), String> + Send + Sync + 'static) -> Self {
        Self::new(
            "a wgpu adapter",
            "PPM_REQUIRE_WGPU",
            "a Vulkan driver (on Debian without a GPU, Mesa's lavapipe, which runs wgpu on the \
             CPU: `apt-get install mesa-vulkan-drivers`)",
            probe,
        )
    }

    /// A virtual X server to open windows on: Xvfb installed. `PPM_REQUIRE_WGPU=1` requires
    /// it, since the windows it serves draw with wgpu.
    pub fn display() -> Self {
        Self::new(
            "a virtual display (Xvfb)",
            "PPM_REQUIRE_WGPU",
            "Xvfb (`apt-get install xvfb`)",
            || {
                let runs = Command::new("Xvfb")
                    .arg("-help")
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .status()
                    .is_ok();
                runs.then_some(())
                    .ok_or_else(|| "Xvfb is not installed".into())
            },
        )
    }

    /// A single-node Slurm cluster this process can start: root, with Slurm's controller and
    /// munge installed. `PPM_REQUIRE_SLURM=1` requires it.
    pub fn slurm() -> Self {
        Self::new(
            "a Slurm cluster",
            "PPM_REQUIRE_SLURM",
            "Slurm and munge, and run as root (`scripts/slurm/cluster.sh install`)",
            || {
                let root = Command::new("id")
                    .arg("-u")
                    .output()
                    .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
                let installed = Command::new("sh")
                    .args(["-c", "command -v slurmctld && command -v munged"])
                    .stdout(Stdio::null())
                    .status()
                    .is_ok_and(|s| s.success());
                match (root, installed) {
                    (false, _) => Err("not root".into()),
                    (true, false) => Err("Slurm is not installed".into()),
                    (true, true) => Ok(()),
                }
            },
        )
    }

    /// Whether the need is met here (probed once), else why not.
    pub fn met(&self) -> Result<(), String> {
        self.0.found.get_or_init(|| (self.0.probe)()).clone()
    }

    /// Whether this run requires the need: its variable is set to 1.
    pub fn required(&self) -> bool {
        std::env::var(&self.0.variable).as_deref() == Ok("1")
    }

    /// The outcome of a test that needs this where it is missing (`why`): a failure where it
    /// is `required`, else ignored (and counted for the binary's closing lines, which give
    /// `why` once rather than on every ignored test's line).
    fn missing(&self, why: &str, required: bool) -> Result<Completion, Failed> {
        let state = &self.0;
        if required {
            return Err(format!(
                "{}=1, but this test needs {}: {why}",
                state.variable, state.what
            )
            .into());
        }
        state.skipped.fetch_add(1, Ordering::Relaxed);
        Ok(Completion::ignored_with(format!("needs {}", state.what)))
    }
}

/// The tests of one binary, run by libtest-mimic with libtest's command line.
#[derive(Default)]
pub struct Suite {
    trials: Vec<Trial>,
    needs: Vec<Need>,
}

impl Suite {
    /// An empty suite.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a test that needs nothing the machine may lack. A panic fails it.
    pub fn test(self, name: impl Into<String>, test: impl FnOnce() + Send + 'static) -> Self {
        self.test_needing(&[], name, test)
    }

    /// Adds a test that runs where every one of `needs` is met; where one is not, the test is
    /// ignored with the reason, or fails where that need is required.
    pub fn test_needing(
        mut self,
        needs: &[&Need],
        name: impl Into<String>,
        test: impl FnOnce() + Send + 'static,
    ) -> Self {
        let needs: Vec<Need> = needs.iter().map(|&n| n.clone()).collect();
        for need in &needs {
            if !self.needs.iter().any(|n| Arc::ptr_eq(&n.0, &need.0)) {
                self.needs.push(need.clone());
            }
        }
        self.trials.push(Trial::ignorable_test(name, move || {
            let missing: Vec<(&Need, String)> = needs
                .iter()
                .filter_map(|need| need.met().err().map(|why| (need, why)))
                .collect();
            if let Some(&(need, ref why)) = missing.iter().find(|(need, _)| need.required()) {
                return need.missing(why, true);
            }
            // Counted against each need it lacks, so the closing lines name them all.
            let mut ignored = Ok(Completion::Completed);
            for (need, why) in &missing {
                ignored = need.missing(why, false);
            }
            match missing.len() {
                0 => run_keeping_figures(test),
                1 => ignored,
                _ => Ok(Completion::ignored_with(format!(
                    "needs {}",
                    missing
                        .iter()
                        .map(|(need, _)| need.0.what.as_str())
                        .collect::<Vec<_>>()
                        .join(" and ")
                ))),
            }
        }));
        self
    }

    /// Runs the tests the command line selects (the usual filters, `--list`,
    /// `--test-threads`), then names what was ignored for want of a need and what would
    /// meet it; the exit code is libtest's.
    pub fn run(self) -> ExitCode {
        let args = Arguments::from_args();
        SHOW_FIGURES.store(args.nocapture || args.show_output, Ordering::Relaxed);
        let conclusion = libtest_mimic::run(&args, self.trials);
        for need in &self.needs {
            let skipped = need.0.skipped.load(Ordering::Relaxed);
            if skipped == 0 {
                continue;
            }
            let why = need.met().err().unwrap_or_default();
            let (tests, them) = match skipped {
                1 => ("1 test of this binary needs".to_owned(), "it"),
                n => (format!("{n} tests of this binary need"), "them"),
            };
            println!(
                "NOT TESTED HERE: {tests} {}: {why}. To run {them}, install {}; {}=1 makes {them} \
                 fail instead.\n",
                need.0.what, need.0.install, need.0.variable,
            );
        }
        conclusion.exit_code()
    }
}

/// Whether figures are printed as they are made (`--nocapture`, `--show-output`).
static SHOW_FIGURES: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// The figures of the test running on this thread.
    static FIGURES: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Keeps a line of a test's figures (what it measured): printed at once with `--nocapture` or
/// `--show-output`, otherwise shown only where the test fails. Write it from the test's own
/// thread, as `println!`.
#[macro_export]
macro_rules! figure {
    ($($arg:tt)*) => {
        $crate::keep_figure(::std::format!($($arg)*))
    };
}

/// What [`figure!`] calls.
#[doc(hidden)]
pub fn keep_figure(line: String) {
    if SHOW_FIGURES.load(Ordering::Relaxed) {
        println!("{line}");
    } else {
        FIGURES.with(|f| {
            let mut f = f.borrow_mut();
            f.push_str(&line);
            f.push('\n');
        });
    }
}

/// Runs `test`, turning a panic into a failure that carries the test's figures.
fn run_keeping_figures(test: impl FnOnce()) -> Result<Completion, Failed> {
    FIGURES.with(|f| f.borrow_mut().clear());
    let outcome = panic::catch_unwind(AssertUnwindSafe(test));
    let figures = FIGURES.with(|f| std::mem::take(&mut *f.borrow_mut()));
    outcome.map(|()| Completion::Completed).map_err(|payload| {
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("(a panic without a message)");
        let figures = if figures.is_empty() {
            String::new()
        } else {
            format!("\nits figures:\n{figures}")
        };
        format!("test panicked: {message}{figures}").into()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn absent() -> Need {
        Need::new("a thing", "PPM_TEST_SUPPORT_NEVER_SET", "nothing", || {
            Err("absent".into())
        })
    }

    /// A test whose need is missing is ignored with the reason and counted, or fails where
    /// the need is required; one whose need is met runs.
    #[test]
    fn a_missing_need_ignores_the_test_or_fails_it_where_required() {
        let need = absent();
        let why = need.met().unwrap_err();
        let outcome = need.missing(&why, false).unwrap();
        assert!(matches!(outcome, Completion::Ignored { reason: Some(r) } if r == "needs a thing"));
        assert_eq!(need.0.skipped.load(Ordering::Relaxed), 1);
        let Err(failed) = need.missing(&why, true) else {
            panic!("a required need that is missing must fail the test");
        };
        assert_eq!(
            failed.message(),
            Some("PPM_TEST_SUPPORT_NEVER_SET=1, but this test needs a thing: absent")
        );
        assert_eq!(
            need.0.skipped.load(Ordering::Relaxed),
            1,
            "a failure is no skip"
        );
        let ran = Arc::new(AtomicBool::new(false));
        let flag = ran.clone();
        let met = Need::new("x", "PPM_TEST_SUPPORT_NEVER_SET", "", || Ok(()));
        assert_eq!(met.met(), Ok(()));
        let done = run_keeping_figures(move || flag.store(true, Ordering::Relaxed)).unwrap();
        assert!(matches!(done, Completion::Completed));
        assert!(ran.load(Ordering::Relaxed));
    }

    /// A panicking test fails with its message and the figures it kept.
    #[test]
    fn a_failure_carries_the_test_s_figures() {
        let Err(failed) = run_keeping_figures(|| {
            figure!("measured {}", 42);
            panic!("too far");
        }) else {
            panic!("a panic must fail the test");
        };
        let message = failed.message().unwrap();
        assert!(
            message.contains("too far") && message.contains("measured 42"),
            "{message}"
        );
    }
}
