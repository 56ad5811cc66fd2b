//! Progress on stderr for commands that run longer than a second: an `indicatif` spinner with
//! the current stage and its elapsed time when stderr is a terminal, plain lines otherwise (logs,
//! CI, tests), so the output stays readable either way.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Stage announcements on stderr: a spinner on a terminal, plain lines otherwise.
pub struct Progress {
    prefix: &'static str,
    spinner: Option<ProgressBar>,
}

impl Progress {
    /// Announcements prefixed with `prefix` (the command's name).
    pub fn new(prefix: &'static str) -> Self {
        let spinner = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new_spinner();
            if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {elapsed}") {
                bar.set_style(style);
            }
            bar.enable_steady_tick(Duration::from_millis(120));
            bar
        });
        Self { prefix, spinner }
    }

    /// A line that stays.
    pub fn line(&self, text: String) {
        match &self.spinner {
            Some(bar) => bar.println(text),
            None => eprintln!("{text}"),
        }
    }

    /// A stage begins.
    pub fn start(&self, stage: &str) {
        match &self.spinner {
            Some(bar) => {
                bar.reset_elapsed();
                bar.set_message(format!("{stage}…"));
            }
            None => eprintln!("{}: {stage}…", self.prefix),
        }
    }

    /// A stage ended after `seconds`.
    pub fn done(&self, stage: &str, seconds: f64) {
        self.line(format!(
            "{}: {stage}: done in {:.1} ms",
            self.prefix,
            seconds * 1e3
        ));
    }

    /// An indented note under the current stage.
    pub fn note(&self, text: &str) {
        self.line(format!("{}:   {text}", self.prefix));
    }

    /// Runs one stage, announced and timed.
    pub fn stage<T>(&self, name: &str, f: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
        self.start(name);
        let start = Instant::now();
        let value = f().with_context(|| format!("stage \"{name}\""))?;
        let seconds = start.elapsed().as_secs_f64();
        self.done(name, seconds);
        Ok((value, seconds))
    }

    /// Clears the spinner.
    pub fn finish(&self) {
        if let Some(bar) = &self.spinner {
            bar.finish_and_clear();
        }
    }
}

impl Drop for Progress {
    /// Clears the spinner also when a stage fails, before the error is printed.
    fn drop(&mut self) {
        self.finish();
    }
}
