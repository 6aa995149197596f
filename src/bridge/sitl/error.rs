//! Why a PX4 instance did not start, with PX4's own last words.

/// Why an instance did not start.
#[derive(Debug, thiserror::Error)]
pub enum SitlError {
    /// The binary is not `BUILD/bin/px4` with a `BUILD/etc` beside `bin`.
    #[error("{bin}: not BUILD/bin/px4 of a PX4 SITL build ({etc} is missing)")]
    NoEtc {
        /// The binary given.
        bin: String,
        /// Where `etc` was looked for.
        etc: String,
    },
    /// The process could not be started.
    #[error("starting {bin}: {source}")]
    Spawn {
        /// The binary given.
        bin: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The startup script did not finish in time.
    #[error(
        "PX4 instance {instance} did not finish its startup script within {secs} s{}",
        last_words(tail)
    )]
    Boot {
        /// The instance number.
        instance: u8,
        /// The bound waited.
        secs: u64,
        /// The console's last lines.
        tail: Vec<String>,
    },
    /// The process ended before its startup script finished.
    #[error("PX4 instance {instance} exited during its startup ({status}){}", last_words(tail))]
    Died {
        /// The instance number.
        instance: u8,
        /// Its exit status, in words.
        status: String,
        /// The console's last lines.
        tail: Vec<String>,
    },
    /// The caller's stop flag was raised while it booted.
    #[error("PX4 instance {instance}: stopped while booting")]
    Cancelled {
        /// The instance number.
        instance: u8,
    },
}

/// `; PX4 said: "a" | "b"` for the last three console lines, or nothing.
fn last_words(tail: &[String]) -> String {
    let last: Vec<&str> = tail.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).collect();
    if last.is_empty() {
        return String::new();
    }
    format!("; PX4 said: {}", last[last.len().saturating_sub(3)..].join(" | "))
}
