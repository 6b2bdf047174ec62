//! Progress bars for long jobs: on stderr, and hidden when stderr is not a
//! terminal, when `CI` is set, or when `NLVID_NO_PROGRESS` is set — so logs
//! and piped output stay clean.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Whether progress bars should be drawn in this environment.
pub fn progress_enabled() -> bool {
    enabled(
        std::io::stderr().is_terminal(),
        std::env::var_os("CI").is_some(),
        std::env::var_os("NLVID_NO_PROGRESS").is_some(),
    )
}

/// Whether bars are drawn, given the environment's three facts.
pub fn enabled(stderr_is_terminal: bool, ci: bool, opted_out: bool) -> bool {
    stderr_is_terminal && !ci && !opted_out
}

/// A progress bar over `len` steps labelled `what` (e.g. "runs"). Hidden
/// (all calls are no-ops) where [`progress_enabled`] is false.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !progress_enabled() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} {msg} (eta {eta})",
    ) {
        pb.set_style(style);
    }
    pb.set_message(what.to_string());
    pb
}
