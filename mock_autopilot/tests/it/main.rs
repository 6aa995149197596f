//! Integration tests: the mock on ephemeral UDP ports, flown by rust-mavlink and pymavlink clients.

mod client;
mod collision_prevention;
mod faults;
mod garbage;
mod python;
mod rust_client;

/// Every numeric flag of the binary beyond its documented range (docs/cli.md) is refused at once, naming it,
/// before anything listens.
#[test]
fn numbers_beyond_their_range_are_refused_at_once_naming_the_flag() {
    let cases: [(&[&str], &str); 9] = [
        (&["--speed-factor", "1e300"], "speed factor"),
        (&["--latency", "1e300"], "--latency"),
        (&["--estimator-settle", "1e300"], "--estimator-settle"),
        (&["--lockstep", "--lockstep-wait", "1e9"], "--lockstep-wait"),
        (&["--reboot-after", "1e300"], "--reboot-after"),
        (&["--silence-after=-1"], "--silence-after"),
        (&["--loss", "2"], "--loss"),
        (&["--duplicate=-0.5"], "--duplicate"),
        (&["--instance", "51000"], "--instance"),
    ];
    for (args, needle) in cases {
        let t0 = std::time::Instant::now();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mock-autopilot"))
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(t0.elapsed() < std::time::Duration::from_secs(5), "{args:?}");
    }
}
