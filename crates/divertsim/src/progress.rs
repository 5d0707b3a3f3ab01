//! The command line's progress: a bar on a terminal, plain lines at most every
//! [`PLAIN_PROGRESS_EVERY`] seconds in a log or a pipe, counts grouped by thousands.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// Seconds between the plain progress lines written when stderr is not a terminal.
pub const PLAIN_PROGRESS_EVERY: f64 = 10.0;

/// The plain-line interval: [`PLAIN_PROGRESS_EVERY`], or DIVERTSIM_PROGRESS_SECONDS.
fn plain_interval() -> f64 {
    std::env::var("DIVERTSIM_PROGRESS_SECONDS")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .unwrap_or(PLAIN_PROGRESS_EVERY)
}

/// A progress display for a log file or a pipe: the bar's line, printed as a plain line at
/// most every [`PLAIN_PROGRESS_EVERY`] seconds (none for a run shorter than that).
#[derive(Debug)]
struct PlainLines {
    state: std::sync::Mutex<(std::time::Instant, String)>,
}

impl indicatif::TermLike for PlainLines {
    fn width(&self) -> u16 {
        100
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.write_str(s)
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        if !s.trim().is_empty() {
            if let Ok(mut st) = self.state.lock() {
                st.1 = s.trim_end().to_string();
            }
        }
        Ok(())
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        if let Ok(mut st) = self.state.lock() {
            if st.0.elapsed().as_secs_f64() >= plain_interval() && !st.1.is_empty() {
                eprintln!("{}", st.1.trim());
                st.0 = std::time::Instant::now();
            }
        }
        Ok(())
    }
}

/// A progress bar on stderr counting runs: drawn in a terminal, written as a plain line every
/// [`PLAIN_PROGRESS_EVERY`] s into a log or a pipe, hidden with `--quiet`.
pub fn progress_bar(len: u64, what: &str, quiet: bool) -> ProgressBar {
    progress_bar_of(len, what, "runs", quiet)
}

/// A progress line for work whose total is not known before it runs: the count so far and
/// the time, no bar, no total (never "38934/0 runs").
pub fn progress_counter(what: &str, unit: &str, quiet: bool) -> ProgressBar {
    let bar = progress_bar_of(0, what, unit, quiet);
    if let Ok(style) = ProgressStyle::with_template(&counter_template(unit)) {
        bar.set_style(style);
    }
    bar
}

/// The line of [`progress_counter`]: the count and the time, no total.
fn counter_template(unit: &str) -> String {
    format!("{{msg:>12}} {{pos}} {unit} so far, {{elapsed}} elapsed")
}

/// [`progress_bar`] counting `unit` ("runs", "pieces", "speeds").
pub fn progress_bar_of(len: u64, what: &str, unit: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(len)
    } else {
        let plain = PlainLines {
            state: std::sync::Mutex::new((std::time::Instant::now(), String::new())),
        };
        ProgressBar::with_draw_target(
            Some(len),
            indicatif::ProgressDrawTarget::term_like_with_hz(Box::new(plain), 1),
        )
    };
    if let Ok(style) = ProgressStyle::with_template(&format!(
        "{{msg:>12}} [{{bar:40}}] {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, eta {{eta}}"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    // Redrawn every second even between ticks (a long piece, a worst-case search), so the
    // elapsed time moves and a log still gets its plain lines.
    bar.enable_steady_tick(std::time::Duration::from_secs(1));
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 50, item 6: replicate's progress read "38934/0 runs"; a count without a known
    /// total shows no total and no bar.
    #[test]
    fn a_progress_count_without_a_total_shows_none() {
        let t = counter_template("runs");
        assert!(!t.contains("{len}") && !t.contains("{bar"), "{t}");
        let bar = progress_counter("replicate", "runs", false);
        bar.set_position(38934);
        assert_eq!(bar.length(), Some(0));
        bar.finish_and_clear();
    }
}
