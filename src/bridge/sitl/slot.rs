//! Instance slots: which PX4 instance numbers this process may start on this machine. Instance `i` owns a set
//! of UDP ports (the bridge listens on `14540 + i`; PX4 binds `14580 + i` and `18570 + i`), so two instances
//! with one number break each other's flights. Parallel flights on one machine (a campaign's `--px4` fleet,
//! `fly --px4` jobs of a Slurm node or of `xargs -P`) each claim a free slot: an exclusive lock on
//! `TMPDIR/prgenuav-px4-slot-<i>.lock`, held until the flight ends (the OS drops it if the process dies), and
//! ports nobody else (a PX4 started by hand) has bound.

use std::fs::{File, OpenOptions, TryLockError};
use std::net::UdpSocket;
use std::path::PathBuf;

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
     holding {dir}/prgenuav-px4-slot-<i>.lock, or by PX4s started by hand on their UDP ports); wait for \
     them, or run fewer flights at once"
)]
pub struct NoFreeSlot {
    tried: String,
    dir: String,
}

/// Claims the lowest free slot from `from` on.
pub fn claim(from: u8) -> Result<Slot, NoFreeSlot> {
    for instance in from..SLOTS {
        if let Some(slot) = try_claim(instance) {
            return Ok(slot);
        }
    }
    Err(NoFreeSlot {
        tried: format!("{from}-{}", SLOTS - 1),
        dir: std::env::temp_dir().display().to_string(),
    })
}

/// Claims `k` distinct slots, lowest first.
pub fn claim_many(k: usize) -> Result<Vec<Slot>, NoFreeSlot> {
    let mut slots: Vec<Slot> = Vec::with_capacity(k);
    while slots.len() < k {
        let from = slots.last().map_or(0, |s| s.instance + 1);
        slots.push(claim(from)?);
    }
    Ok(slots)
}

fn lock_path(instance: u8) -> PathBuf {
    std::env::temp_dir().join(format!("prgenuav-px4-slot-{instance}.lock"))
}

fn try_claim(instance: u8) -> Option<Slot> {
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
    free.then_some(Slot { instance, _lock: file })
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
    }
}
