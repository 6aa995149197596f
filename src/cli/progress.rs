//! Stage progress for long commands: bars on a terminal, plain log lines otherwise, nothing with `--quiet`.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use prgenuav::campaign::run::Progress;

/// How progress is shown.
pub enum Reporter {
    /// A bar per stage on stderr.
    Bars(Mutex<Option<ProgressBar>>),
    /// A line per stage start, every tenth of it, and every note, on stderr.
    Lines(Mutex<(String, usize, Instant)>),
    /// Nothing.
    Quiet,
}

impl Reporter {
    /// Bars when stderr is a terminal, lines otherwise; nothing when `quiet`.
    pub fn new(quiet: bool) -> Self {
        if quiet {
            Self::Quiet
        } else if std::io::stderr().is_terminal() {
            Self::Bars(Mutex::new(None))
        } else {
            Self::Lines(Mutex::new((String::new(), 0, Instant::now())))
        }
    }
}

impl Progress for Reporter {
    fn stage(&self, name: &str, total: usize) {
        match self {
            Self::Bars(bar) => {
                let b = ProgressBar::new(total as u64);
                let style =
                    ProgressStyle::with_template("{prefix:>8} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
                        .map(|s| s.progress_chars("=> "));
                if let Ok(style) = style {
                    b.set_style(style);
                }
                b.set_prefix(name.to_string());
                if let Ok(mut slot) = bar.lock()
                    && let Some(old) = slot.replace(b)
                {
                    old.finish();
                }
            }
            Self::Lines(state) => {
                if let Ok(mut s) = state.lock() {
                    *s = (name.to_string(), total, Instant::now());
                }
                eprintln!("[{name}] 0/{total}");
            }
            Self::Quiet => {}
        }
    }

    fn tick(&self, done: usize) {
        match self {
            Self::Bars(bar) => {
                if let Ok(slot) = bar.lock()
                    && let Some(b) = slot.as_ref()
                {
                    b.set_position(done as u64);
                }
            }
            Self::Lines(state) => {
                if let Ok(s) = state.lock() {
                    let (name, total, start) = &*s;
                    let step = (*total / 10).max(1);
                    if done.is_multiple_of(step) || done == *total {
                        eprintln!("[{name}] {done}/{total} ({:.1} s)", start.elapsed().as_secs_f64());
                    }
                }
            }
            Self::Quiet => {}
        }
    }

    fn note(&self, message: &str) {
        match self {
            Self::Bars(bar) => match bar.lock().ok().and_then(|s| s.clone()) {
                Some(b) => b.println(message),
                None => eprintln!("{message}"),
            },
            Self::Lines(_) => eprintln!("{message}"),
            Self::Quiet => {}
        }
    }
}
