//! Boards in the loop (`--hitl serial:/dev/ttyACM0:921600,...`): each board is a vehicle whose simulator
//! (prgenuav's iris, on the board's serial port on the wall clock) starts with its first flight at the
//! test's home and runs for the campaign, so the board's estimator never sees the world jump; each flight
//! starts where the last one landed, as on any vehicle flown again (the bridge flies in the test's frame).
//! The bridge flies the board through the simulator's gateway and refuses it unless `SYS_HITL` is 1. A
//! board whose serial device disappears is dropped, its flight given to another vehicle, never charged.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use tokio::runtime::Handle;

use super::mock_mavlink::{flight_seed, flown, fly_blocking};
use super::vehicle::{Flown, Vehicle, VehicleError};
use crate::bridge::hil::board::{Board, BoardPort};
use crate::bridge::{FlyMode, FlyOptions};
use crate::judge::Judge;
use crate::model::TestCase;

/// How the boards' flights are flown and judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitlSettings {
    /// Obstacle mode.
    pub mode: FlyMode,
    /// Judge edition.
    pub judge: Judge,
    /// A flight is given up (LAND) after this many seconds.
    pub timeout_s: f64,
    /// The campaign's seed (the simulator's sensor noise).
    pub seed: u64,
}

/// One board on one serial port.
pub struct HitlVehicle {
    handle: Handle,
    url: String,
    port: BoardPort,
    settings: HitlSettings,
    board: Option<Board>,
}

impl HitlVehicle {
    /// The board at `url` (`serial:DEVICE:BAUD`), checked.
    pub fn new(handle: Handle, url: &str, settings: HitlSettings) -> Result<Self, String> {
        Ok(Self {
            handle,
            url: url.to_string(),
            port: BoardPort::parse(url)?,
            settings,
            board: None,
        })
    }

    fn unreachable(&self, reason: String) -> VehicleError {
        VehicleError::Unreachable {
            vehicle: self.name(),
            reason,
        }
    }

    /// The board's simulator, started at `test`'s home with the flight's seed if it is not running.
    fn board(&mut self, test: &TestCase, csv: &Path) -> Result<&Board, VehicleError> {
        if self.board.is_none() {
            let seed = flight_seed(self.settings.seed, csv);
            let started = self.handle.block_on(Board::start(&self.port, test.home, seed));
            self.board = Some(started.map_err(|e| self.unreachable(e.to_string()))?);
        }
        self.board
            .as_ref()
            .ok_or_else(|| self.unreachable("no simulator".into()))
    }
}

impl Vehicle for HitlVehicle {
    fn name(&self) -> String {
        self.url.clone()
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Flown, VehicleError> {
        let s = self.settings;
        let url = self.board(test, csv)?.url().to_string();
        let opts = FlyOptions {
            connect: url,
            mode: s.mode,
            judge: s.judge,
            timeout_s: s.timeout_s,
            trajectory_csv: Some(csv.to_path_buf()),
            heartbeat_wait_s: 30.0,
            require_hitl: true,
            ..FlyOptions::default()
        };
        let result = fly_blocking(&self.handle, test, &opts, stop);
        if let Some(why) = self.board.as_ref().and_then(Board::failure) {
            // The device went away (unplugged, rebooted): this board flies no more flights.
            if let Some(board) = self.board.take() {
                let _ = self.handle.block_on(board.stop());
            }
            return Err(self.unreachable(format!("the board's serial link ended: {why}")));
        }
        result.map(flown).map_err(|e| self.unreachable(e.to_string()))
    }
}
