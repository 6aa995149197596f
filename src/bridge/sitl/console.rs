//! The console of a running PX4: drained by a thread so PX4 never blocks on a full pipe, its last lines kept
//! (PX4's own account of a flight that went wrong), and the boot line signalled.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader};
use std::process::Child;
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex, PoisonError};

/// Console lines kept for [`Px4Sitl::console_tail`]: enough for a flight's failsafe, landing and disarm
/// messages, small enough to keep for every instance of a fleet.
pub(super) const CONSOLE_LINES: usize = 400;

/// The console line PX4's POSIX main prints once its startup script ran.
const BOOTED: &str = "Startup script returned";

/// The last [`CONSOLE_LINES`] lines of one PX4's console, shared with the thread that reads it.
#[derive(Debug, Clone, Default)]
pub(super) struct Console {
    lines: Arc<Mutex<VecDeque<String>>>,
}

impl Console {
    /// Follows `child`'s stdout on a thread that ends when PX4 closes it; the receiver gets one message when
    /// the startup script ran and disconnects when the console closes.
    pub(super) fn follow(child: &mut Child) -> (Console, Receiver<()>) {
        let (tx, rx) = channel();
        let console = Console::default();
        if let Some(out) = child.stdout.take() {
            let kept = console.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines().map_while(Result::ok) {
                    if line.contains(BOOTED) {
                        let _ = tx.send(());
                    }
                    keep_line(&kept.lines, line);
                }
            });
        }
        (console, rx)
    }

    /// The last `n` lines, oldest first.
    pub(super) fn tail(&self, n: usize) -> Vec<String> {
        let lines = self.lines.lock().unwrap_or_else(PoisonError::into_inner);
        lines.iter().skip(lines.len().saturating_sub(n)).cloned().collect()
    }
}

/// Appends `line` without its ANSI colour codes, dropping the oldest line beyond [`CONSOLE_LINES`].
fn keep_line(console: &Mutex<VecDeque<String>>, line: String) {
    let plain = strip_ansi(&line);
    let mut lines = console.lock().unwrap_or_else(PoisonError::into_inner);
    if lines.len() == CONSOLE_LINES {
        lines.pop_front();
    }
    lines.push_back(plain);
}

/// `line` without `ESC [ ... letter` sequences (PX4 colours its console's INFO/WARN tags).
fn strip_ansi(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            if chars.next() == Some('[') {
                for c in chars.by_ref() {
                    if c.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_are_removed_from_console_lines() {
        assert_eq!(
            strip_ansi("INFO  [commander] \u{1b}[32mReady for takeoff!\u{1b}[0m"),
            "INFO  [commander] Ready for takeoff!"
        );
        assert_eq!(
            strip_ansi("WARN  [failsafe] Failsafe activated\t"),
            "WARN  [failsafe] Failsafe activated\t"
        );
    }

    #[test]
    fn the_console_keeps_its_last_lines() {
        let console = Mutex::new(VecDeque::new());
        for i in 0..CONSOLE_LINES + 5 {
            keep_line(&console, format!("line {i}"));
        }
        let lines = console.lock().unwrap();
        assert_eq!(lines.len(), CONSOLE_LINES);
        assert_eq!(lines.front().map(String::as_str), Some("line 5"));
        assert_eq!(lines.back(), Some(&format!("line {}", CONSOLE_LINES + 4)));
    }
}
