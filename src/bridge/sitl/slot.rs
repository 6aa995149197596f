//! Instance slots: which PX4 instance numbers this process may start on this machine. Instance `i` owns a set
//! of UDP ports (the bridge listens on `14540 + i`; PX4 binds `14580 + i` and `18570 + i`), so two instances
//! with one number break each other's flights. Parallel flights on one machine (a campaign's `--px4` fleet,
//! `fly --px4` jobs of a Slurm node or of `xargs -P`) each claim a free slot: an exclusive lock on
//! `TMPDIR/prgenuav-px4-slot-<i>.lock`, held until the flight ends (the OS drops it if the process dies), and
//! ports nobody else has bound; with prgenuav's simulator, also TCP `4560 + i`, where PX4 connects to its
//! simulator. A PX4 started by hand holds its instance's own server lock, which PX4 checks before it starts
//! ("PX4 server already running for instance i"): such a slot is skipped too.

use std::fs::{File, OpenOptions, TryLockError};
use std::net::{TcpListener, UdpSocket};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};

use crate::bridge::options::VehicleSim;

/// Instances on one machine: instance 10's bridge port would be 14550, where every instance's GCS link sends
/// (QGroundControl's port), and PX4 (`px4-rc.mavlink`) sends the API link of instances above 9 to 14549.
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

/// Claims the lowest free slot from `from` on whose ports `sim` needs are free. The iris never gets instance 0:
/// PX4 v1.12.3 instance 0 in external-simulator mode sent the avoidance companion no request in 8 flights
/// (the mission refused: "Obstacle Avoidance system failed, loitering"), while instances 3, 4 and 5 flew.
pub fn claim_with(from: u8, sim: VehicleSim) -> Result<Slot, NoFreeSlot> {
    let from = if sim == VehicleSim::Iris {
        from.max(FIRST_IRIS)
    } else {
        from
    };
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

/// The lowest instance the iris flies on (see [`claim_with`]).
pub const FIRST_IRIS: u8 = 1;

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

/// The lock PX4 v1.14-v1.17 SITL holds while instance `i` runs (`platforms/posix/src/px4/common/main.cpp`:
/// the server takes a POSIX write lock on the whole file, and a second server of that instance, seeing it
/// with `F_GETLK`, refuses to start). Always under `/tmp`, whatever `TMPDIR` says.
fn px4_lock_path(instance: u8) -> PathBuf {
    PathBuf::from(format!("/tmp/px4_lock-{instance}"))
}

/// Whether a process holds a write lock on `path` as a running PX4 server holds its lock, asked as PX4 asks
/// (a missing file: nobody). A file that cannot be opened to ask counts as held: the slot is left alone.
pub fn px4_holds(path: &Path) -> bool {
    let file = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return false,
        Err(_) => return true,
    };
    // SAFETY: a zeroed flock is a valid value of the C struct.
    let mut lock: libc::flock = unsafe { std::mem::zeroed() };
    lock.l_type = libc::F_WRLCK as libc::c_short;
    lock.l_whence = libc::SEEK_SET as libc::c_short;
    // Open-file-description locks see a POSIX lock even when this process holds it (its own tests do).
    #[cfg(target_os = "linux")]
    let cmd = libc::F_OFD_GETLK;
    #[cfg(not(target_os = "linux"))]
    let cmd = libc::F_GETLK;
    // SAFETY: fcntl on an open descriptor with a pointer to a live flock, as F_GETLK takes.
    let rc = unsafe { libc::fcntl(file.as_raw_fd(), cmd, &mut lock) };
    rc != 0 || lock.l_type != libc::F_UNLCK as libc::c_short
}

/// Whether a PX4 (started by hand, or by anyone else) runs as instance `instance` ([`px4_holds`]).
pub fn held_by_px4(instance: u8) -> bool {
    px4_holds(&px4_lock_path(instance))
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
    // Held by nobody of ours; a PX4 or a bridge started by hand may still own the instance or its ports.
    let free = !held_by_px4(instance) && ports(instance).iter().all(|p| UdpSocket::bind(("0.0.0.0", *p)).is_ok());
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
        drop(sih);
        drop(tcp);
        let iris = claim_with(0, VehicleSim::Iris).expect("a slot for the iris");
        assert!(iris.instance() >= FIRST_IRIS, "the iris never flies instance 0");
        drop(iris);
        // A PX4 started by hand on the free slot: its server lock is held, so the slot is skipped.
        if let Some(px4) = hold_as_px4(&px4_lock_path(freed), false) {
            let got = claim(freed).expect("another slot");
            assert_ne!(got.instance(), freed, "the slot of a running PX4");
            drop(px4);
            drop(got);
            assert_eq!(claim(freed).expect("the slot again").instance(), freed);
        }
    }

    /// Takes a write lock on `path` as a PX4 server does (`posix`: PX4's own kind, released when this process
    /// closes any descriptor of the file, as every check does; else an open-file-description lock, which the
    /// checks leave alone); `None` when the file is not ours to lock.
    fn hold_as_px4(path: &Path, posix: bool) -> Option<File> {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .ok()?;
        // SAFETY: a zeroed flock is a valid value of the C struct.
        let mut lock: libc::flock = unsafe { std::mem::zeroed() };
        lock.l_type = libc::F_WRLCK as libc::c_short;
        lock.l_whence = libc::SEEK_SET as libc::c_short;
        let cmd = if posix { libc::F_SETLK } else { libc::F_OFD_SETLK };
        // SAFETY: fcntl on an open descriptor with a pointer to a live flock.
        let rc = unsafe { libc::fcntl(file.as_raw_fd(), cmd, &lock) };
        (rc == 0).then_some(file)
    }

    #[test]
    fn a_lock_held_as_px4_holds_it_is_seen_and_a_missing_file_is_free() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("px4_lock-0");
        assert!(!px4_holds(&path), "no file: no PX4");
        std::fs::write(&path, "").unwrap();
        assert!(!px4_holds(&path), "a file nobody locks: PX4 left it behind");
        let held = hold_as_px4(&path, true).unwrap();
        assert!(px4_holds(&path), "PX4's own kind of lock");
        drop(held);
        let held = hold_as_px4(&path, false).unwrap();
        assert!(px4_holds(&path) && px4_holds(&path));
        drop(held);
        assert!(!px4_holds(&path));
    }
}
