//! The bridge's entry points: open the link (retrying a refused TCP connection, or a UDP port the last flight's
//! link is still letting go of) and run one flight.

use std::sync::Arc;
use std::time::Duration;

use super::options::{BridgeError, FlyOptions};
use super::session::report::FlightReport;
use super::session::run;
use super::wire::cancel::CancelToken;
use super::wire::clock;
use super::wire::link::{self, Transport};
use super::wire::tcp_in::TcpInTransport;
use super::wire::udp_in::UdpInTransport;
use super::wire::url::LinkAddress;
use crate::model::TestCase;

/// Flies `test` on the vehicle at `opts.connect` and reports; `cancel` lands it early (`aborted`).
///
/// Safe to call many times in parallel, each with its own address (one vehicle per link).
pub async fn fly(test: &TestCase, opts: &FlyOptions, cancel: CancelToken) -> Result<FlightReport, BridgeError> {
    opts.validate()?;
    let address = LinkAddress::parse(&opts.connect)?.to_mavlink();
    let transport = open_with_retry(&address, opts, &cancel).await?;
    fly_on(test, opts, transport, cancel).await
}

/// Opens the link. A refused TCP connection (the simulator is still starting) and a UDP port still in use are
/// tried again every 200 ms within the heartbeat wait (as wall seconds) or until cancelled; any other error is
/// final. The port: a campaign flies a vehicle's next test on the same `udpin` address as soon as the last one
/// ends. A finished flight closes its socket before returning (`Link::close`); a flight that ended early (no
/// heartbeat) or another process may still hold it for a moment; without the retry, a campaign on 2 PX4 SITL
/// instances loses its vehicles to `AddrInUse` within a few flights.
async fn open_with_retry(
    address: &str,
    opts: &FlyOptions,
    cancel: &CancelToken,
) -> Result<Arc<dyn Transport>, BridgeError> {
    let deadline = std::time::Instant::now() + clock::secs(opts.heartbeat_wait_s);
    loop {
        // A connect the network never answers (a `tcpout` to a silent host) ends with the wait or the stop.
        // Biased: an open that ends at once (a port in use) reports its own error, not the deadline's.
        let opened = tokio::select! {
            biased;
            opened = open(address) => opened,
            () = tokio::time::sleep_until(deadline.into()) => Err(std::io::Error::new(
                std::io::ErrorKind::TimedOut,
                format!("not open within {:.0} s (the heartbeat wait)", opts.heartbeat_wait_s),
            )),
            () = cancel.cancelled() => Err(std::io::Error::new(std::io::ErrorKind::Interrupted, "stopped")),
        };
        match opened {
            Ok(t) => return Ok(t),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::ConnectionRefused | std::io::ErrorKind::AddrInUse
                ) && std::time::Instant::now() < deadline
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

/// `udpin` on a socket that answers only the vehicle (a flood on the port cannot take its replies), `tcpin` on a
/// listener that settles on the client that is the vehicle (and never waits for one itself); any other address
/// through rust-mavlink.
async fn open(address: &str) -> std::io::Result<Arc<dyn Transport>> {
    if let Some(host_port) = address.strip_prefix("udpin:") {
        return Ok(Arc::new(UdpInTransport::bind(host_port).await?));
    }
    if let Some(host_port) = address.strip_prefix("tcpin:") {
        return Ok(Arc::new(TcpInTransport::bind(host_port).await?));
    }
    Ok(Arc::new(link::MavTransport::open(address).await?))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(wait_s: f64) -> FlyOptions {
        FlyOptions {
            heartbeat_wait_s: wait_s,
            ..FlyOptions::default()
        }
    }

    #[tokio::test]
    async fn a_udp_port_still_held_is_tried_again_until_it_is_free() {
        let held = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let address = format!("udpin:{}", held.local_addr().unwrap());
        let release = tokio::spawn(async move {
            tokio::time::sleep(Duration::from_millis(500)).await;
            drop(held);
        });
        let t = std::time::Instant::now();
        let opened = open_with_retry(&address, &opts(10.0), &CancelToken::new()).await;
        assert!(opened.is_ok(), "{:?}", opened.err());
        assert!(t.elapsed() >= Duration::from_millis(400), "it waited for the port");
        release.await.unwrap();
    }

    #[tokio::test]
    async fn a_udp_port_held_for_good_fails_after_the_wait_naming_the_address() {
        let held = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let address = format!("udpin:{}", held.local_addr().unwrap());
        let t = std::time::Instant::now();
        let e = match open_with_retry(&address, &opts(0.6), &CancelToken::new()).await {
            Ok(_) => panic!("the port is held"),
            Err(e) => e.to_string(),
        };
        assert!(t.elapsed() >= Duration::from_millis(500) && t.elapsed() < Duration::from_secs(5));
        assert!(e.contains(&address) && e.to_lowercase().contains("in use"), "{e}");
        drop(held);
    }
}
