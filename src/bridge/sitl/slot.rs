//! Instance slots: which PX4 instance numbers this process may start on this machine. Instance `i` owns a set
//! of UDP ports (the bridge listens on `14540 + i`; PX4 binds `14580 + i` and `18570 + i`), so two instances
//! with one number break each other's flights. Parallel flights on one machine (a campaign's `--px4` fleet,
//! `fly --px4` jobs of a Slurm node or of `xargs -P`) each claim a free slot: an exclusive lock on
//! `TMPDIR/prgenuav-px4-slot-<i>.lock`, held until the flight ends (the OS drops it if the process dies), and
//! ports nobody else (a PX4 started by hand) has bound; with prgenuav's simulator, also TCP `4560 + i`, where
//! PX4 connects to its simulator.

use std::fs::{File, OpenOptions, TryLockError};
use std::net::{TcpListener, UdpSocket};
use std::path::PathBuf;

use crate::bridge::options::VehicleSim;

/// Instances on one machine: instance 10's bridge port would be 14550, where every instance's GCS link sends
/// (QGroundControl's port).
pub const SLOTS: u8 = 10;

/// UDP ports of instance `i`: the bridge's, and PX4's own two.
fn ports(instance: u8) -> [u16; 3] {
    let i = u16::from(instance);
    [14540 + i, 14580 + i, 18570 + i]
}

/// A claimed instance number; the claim ends when this is dropped.
#[derive(Debug)]
pub struct Slot {
    instance: u8,
    _lock: File,
}

impl Slot {
    /// The instance number.
    pub fn instance(&self) -> u8 {
        self.instance
    }
}

/// Why no slot was claimed.
#[derive(Debug, thiserror::Error)]
#[error(
    "no free PX4 instance slot on this machine: instances {tried} are in use (by other prgenuav flights, \
     holding {dir}/prgenuav-px4-slot-<i>.lock, or by PX4s started by hand on their UDP ports, or, for --sim \
     iris, by another simulator on TCP 4560+i); wait for \
     them, or run fewer flights at once"
)]
pub struct NoFreeSlot {
    tried: String,
    dir: String,
}

/// Claims the lowest free slot from `from` on (for SIH).
pub fn claim(from: u8) -> Result<Slot, NoFreeSlot> {
    claim_with(from, VehicleSim::Sih)
}

/// Claims the lowest free slot from `from` on whose ports `sim` needs are free.
pub fn claim_with(from: u8, sim: VehicleSim) -> Result<Slot, NoFreeSlot> {
    for instance in from..SLOTS {
        if let Some(slot) = try_claim(instance, sim) {
            return Ok(slot);
        }
    }
    Err(NoFreeSlot {
        tried: format!("{from}-{}", SLOTS - 1),
        dir: std::env::temp_dir().display().to_string(),
    })
}

/// Claims `k` distinct slots, lowest first (for SIH).
pub fn claim_many(k: usize) -> Result<Vec<Slot>, NoFreeSlot> {
    claim_many_with(k, VehicleSim::Sih)
}

/// Claims `k` distinct slots whose ports `sim` needs are free, lowest first.
pub fn claim_many_with(k: usize, sim: VehicleSim) -> Result<Vec<Slot>, NoFreeSlot> {
    let mut slots: Vec<Slot> = Vec::with_capacity(k);
    while slots.len() < k {
        let from = slots.last().map_or(0, |s| s.instance + 1);
        slots.push(claim_with(from, sim)?);
    }
    Ok(slots)
}

fn lock_path(instance: u8) -> PathBuf {
    std::env::temp_dir().join(format!("prgenuav-px4-slot-{instance}.lock"))
}

fn try_claim(instance: u8, sim: VehicleSim) -> Option<Slot> {
    let file = OpenOptions::new()
        .create(true)
        .write(true)
        .truncate(false)
        .open(lock_path(instance))
        .ok()?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock | TryLockError::Error(_)) => return None,
    }
    // Held by nobody of ours; a PX4 or a bridge started by hand may still own the ports.
    let free = ports(instance).iter().all(|p| UdpSocket::bind(("0.0.0.0", *p)).is_ok());
    // Another simulator (Gazebo, jMAVSim, prgenuav-sim) serving this instance's TCP port.
    let simulator_port = 4560 + u16::from(instance);
    let tcp_free = sim == VehicleSim::Sih || TcpListener::bind(("127.0.0.1", simulator_port)).is_ok();
    (free && tcp_free).then_some(Slot { instance, _lock: file })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One test, so no other test of this process claims a slot between its steps.
    #[test]
    fn slots_are_distinct_until_dropped_and_skip_ports_bound_by_others() {
        let a = claim_many(2).expect("two free slots");
        assert_ne!(a[0].instance(), a[1].instance());
        let held: Vec<u8> = a.iter().map(Slot::instance).collect();
        let b = claim(0).expect("a third free slot");
        assert!(!held.contains(&b.instance()), "{held:?} {}", b.instance());
        let freed = a[0].instance();
        drop(a);
        drop(b);
        let c = claim(freed).expect("the freed slot");
        assert_eq!(c.instance(), freed);
        drop(c);
        // Someone else's bridge on a free slot's port: that slot is not handed out.
        let squatter = UdpSocket::bind(("0.0.0.0", 14540 + u16::from(freed))).expect("bind");
        let got = claim(freed).expect("another slot");
        assert_ne!(got.instance(), freed);
        drop(squatter);
        drop(got);
        // A simulator already serving a slot's TCP port: that slot is not handed out for the iris.
        let tcp = TcpListener::bind(("127.0.0.1", 4560 + u16::from(freed))).expect("bind");
        let iris = claim_with(freed, VehicleSim::Iris).expect("another slot");
        assert_ne!(iris.instance(), freed);
        drop(iris);
        let sih = claim_with(freed, VehicleSim::Sih).expect("SIH does not need it");
        assert_eq!(sih.instance(), freed);
        drop(tcp);
    }
}
