//! Progress display (indicatif) on stderr; it draws nothing when stderr is not a terminal, so logs and CI
//! output stay clean.

use indicatif::{ProgressBar, ProgressStyle};

/// A spinner with a message.
pub fn spinner(msg: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {prefix} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.set_prefix(msg.to_string());
    bar
}

/// A bar over `total` items.
pub fn bar(total: u64, msg: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_prefix(msg.to_string());
    bar
}
