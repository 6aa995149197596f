//! The gateway of a board in the loop: every non-HIL frame from the board goes out to a UDP endpoint (a
//! ground station, the product's bridge) untouched, and every datagram arriving on that socket goes to the
//! board, so the board's mission and parameters can be flown through the simulator's serial link.

use std::net::SocketAddr;

use tokio::net::UdpSocket;

use crate::error::SimError;

/// Where the gateway sends and listens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GatewayConfig {
    /// The local address the socket binds (port 0: any free one).
    pub bind: SocketAddr,
    /// Where the board's traffic goes (e.g. 127.0.0.1:14550, QGroundControl's).
    pub remote: SocketAddr,
}

/// An open gateway socket.
#[derive(Debug)]
pub struct Gateway {
    socket: UdpSocket,
    remote: SocketAddr,
    /// Frames sent to the endpoint.
    pub to_endpoint: u64,
    /// Datagrams passed to the board.
    pub to_board: u64,
}

impl Gateway {
    /// Binds the socket.
    pub async fn open(config: GatewayConfig) -> Result<Self, SimError> {
        let socket = UdpSocket::bind(config.bind).await.map_err(|e| SimError::Gateway {
            addr: config.bind.to_string(),
            source: e,
        })?;
        Ok(Self::from_socket(socket, config.remote))
    }

    /// A gateway on a socket the host made.
    pub fn from_socket(socket: UdpSocket, remote: SocketAddr) -> Self {
        Self {
            socket,
            remote,
            to_endpoint: 0,
            to_board: 0,
        }
    }

    /// The local address.
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.socket.local_addr().ok()
    }

    /// Sends a frame from the board to the endpoint (dropped if the socket's buffer is full: UDP).
    pub fn forward(&mut self, frame: &[u8]) {
        if self.socket.try_send_to(frame, self.remote).is_ok() {
            self.to_endpoint += 1;
        }
    }

    /// Waits for a datagram for the board.
    pub async fn recv(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let (n, _) = self.socket.recv_from(buf).await?;
        self.to_board += 1;
        Ok(n)
    }
}
