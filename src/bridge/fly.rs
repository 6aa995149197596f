//! The bridge's entry points: open the link (retrying a refused TCP connection) and run one flight.

use std::sync::Arc;
use std::time::Duration;

use super::options::{BridgeError, FlyOptions};
use super::session::report::FlightReport;
use super::session::run;
use super::wire::cancel::CancelToken;
use super::wire::clock;
use super::wire::link::{self, Transport};
use super::wire::url::LinkAddress;
use crate::model::TestCase;

/// Flies `test` on the vehicle at `opts.connect` and reports; `cancel` lands it early (`aborted`).
///
/// Safe to call many times in parallel, each with its own address (one vehicle per link).
pub async fn fly(test: &TestCase, opts: &FlyOptions, cancel: CancelToken) -> Result<FlightReport, BridgeError> {
    opts.validate()?;
    let address = LinkAddress::parse(&opts.connect)?.to_mavlink();
    let transport = open_with_retry(&address, opts, &cancel).await?;
    fly_on(test, opts, Arc::new(transport), cancel).await
}

/// Opens the link. A refused TCP connection (the simulator is still starting) is tried again every 200 ms
/// within the heartbeat wait (as wall seconds) or until cancelled; any other error is final.
async fn open_with_retry(
    address: &str,
    opts: &FlyOptions,
    cancel: &CancelToken,
) -> Result<link::MavTransport, BridgeError> {
    let deadline = std::time::Instant::now() + clock::secs(opts.heartbeat_wait_s);
    loop {
        match link::MavTransport::open(address).await {
            Ok(t) => return Ok(t),
            Err(e)
                if e.kind() == std::io::ErrorKind::ConnectionRefused
                    && std::time::Instant::now() < deadline
                    && !cancel.is_cancelled() =>
            {
                tokio::time::sleep(Duration::from_millis(200)).await;
            }
            Err(source) => {
                return Err(BridgeError::Open {
                    url: address.to_string(),
                    source,
                });
            }
        }
    }
}

/// As [`fly`] on an already open transport (`opts.connect` only names it in messages).
pub async fn fly_on(
    test: &TestCase,
    opts: &FlyOptions,
    transport: Arc<dyn Transport>,
    cancel: CancelToken,
) -> Result<FlightReport, BridgeError> {
    opts.validate()?;
    run::run(test, opts, transport, cancel).await
}
