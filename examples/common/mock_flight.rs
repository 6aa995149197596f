//! One flight of a test on an embedded lockstep mock in `avoidance` mode, as `generate` flies it: shared by
//! the examples that compare the mock with PX4.

use std::time::Duration;

use anyhow::Context;
use mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT;
use mock_autopilot::{Builder, LinkSpec, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, fly};
use prgenuav::campaign::fly::mock_mavlink::mock_builder_with;
use prgenuav::campaign::settings::mock_profile::MockProfile;
use prgenuav::model::TestCase;

/// The mock's simulated time runs this many times faster than the wall clock.
const SPEED: f64 = 100.0;

/// (status, min distance, flight time) of one flight.
pub type Flown = (String, Option<f64>, f64);

/// Flies `test` on a fresh mock with the campaign's mock profile (env `MOCK_PROFILE=NAME`: that profile;
/// `MOCK_SETTING=...`: a setting as `mock_fit` takes them, e.g. `MPC_XY_VEL_MAX=2.0,MOCK_VEL_GAIN=1.0`;
/// `MOCK_PX4_DEFAULTS=1`: PX4's own defaults), its gusts (if the setting has any) drawn from `seed`. Needs
/// `mod setting` (`common/setting.rs`) beside it.
pub async fn fly_mock(test: TestCase, seed: u64) -> anyhow::Result<Flown> {
    let builder = if std::env::var_os("MOCK_PX4_DEFAULTS").is_some() {
        mock_autopilot::MockAutopilot::builder()
    } else {
        let profile = match (std::env::var("MOCK_SETTING"), std::env::var("MOCK_PROFILE")) {
            (Ok(setting), _) => crate::setting::parse_setting(&setting).context("MOCK_SETTING")?,
            (_, Ok(name)) => MockProfile::named(&name).map_err(|e| anyhow::anyhow!("MOCK_PROFILE: {e}"))?,
            _ => MockProfile::default(),
        };
        mock_builder_with(&profile, FlyMode::Avoidance)
    };
    let r = fly_on_mock(&test, builder.seed(seed), FlyOptions::default()).await?;
    Ok((r.status.as_str().to_string(), r.min_distance, r.flight_time_s))
}

/// Flies `test` on a fresh lockstep mock made by `builder`, in `avoidance` mode with `opts`' other options.
pub async fn fly_on_mock(test: &TestCase, builder: Builder, opts: FlyOptions) -> anyhow::Result<FlightReport> {
    let mock = builder
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse()?))
        .speed_factor(SpeedFactor::Times(SPEED))
        .lockstep(Some(DEFAULT_LOCKSTEP_WAIT))
        .spawn()
        .await?;
    let port = mock.local_addr().map(|a| a.port()).context("mock has no port")?;
    let opts = FlyOptions {
        connect: format!("udpout:127.0.0.1:{port}"),
        mode: FlyMode::Avoidance,
        time_scale: SPEED,
        lockstep: Some(Duration::ZERO),
        ..opts
    };
    let r = fly(test, &opts, CancelToken::new()).await;
    let _ = mock.shutdown().await;
    Ok(r?)
}
