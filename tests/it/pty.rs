//! A serial cable in software: two pseudo-terminal pairs whose master ends are joined by two copy threads, so
//! two programs can each open a `/dev/pts/N` path as a serial port (what `socat` does, without it).

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{FromRawFd, OwnedFd};

/// Both slave paths; the pairs' slave ends stay open here until dropped, so the relay outlives reopenings.
pub struct SerialCable {
    /// Path for one program.
    pub a: String,
    /// Path for the other.
    pub b: String,
    _slaves: [OwnedFd; 2],
}

fn raw_termios() -> libc::termios {
    // SAFETY: termios is plain old data; cfmakeraw only writes its fields.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    unsafe { libc::cfmakeraw(&mut t) };
    t.c_cflag |= libc::CREAD | libc::CLOCAL;
    unsafe {
        libc::cfsetspeed(&mut t, libc::B57600);
    }
    t
}

fn pty() -> std::io::Result<(OwnedFd, OwnedFd, String)> {
    let (mut master, mut slave) = (-1, -1);
    let mut name = [0 as libc::c_char; 256];
    let t = raw_termios();
    // SAFETY: every pointer is valid for the call; the name buffer is large enough for a pts path.
    let rc = unsafe { libc::openpty(&mut master, &mut slave, name.as_mut_ptr(), &t, std::ptr::null()) };
    if rc != 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: openpty returned two fresh descriptors we now own, and a NUL-terminated name.
    let (m, s) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    Ok((m, s, path))
}

/// One pseudo-terminal: its master end (the test plays the device through it) and the slave's path, which a
/// program opens as a serial port. Closing the master is the device going away.
pub fn lone_pty() -> std::io::Result<(File, String)> {
    let (master, slave, path) = pty()?;
    // The program opens the path itself; our slave handle would keep the device alive after the master goes.
    drop(slave);
    Ok((File::from(master), path))
}

fn copy(from: OwnedFd, to: OwnedFd) {
    std::thread::spawn(move || {
        let (mut r, mut w) = (File::from(from), File::from(to));
        let mut buf = [0u8; 4096];
        // Ends with EIO once every slave handle of the source is closed.
        while let Ok(n) = r.read(&mut buf) {
            if n == 0 || w.write_all(&buf[..n]).is_err() {
                break;
            }
        }
    });
}

impl SerialCable {
    /// Two joined pseudo-terminals.
    pub fn new() -> std::io::Result<Self> {
        let (ma, sa, a) = pty()?;
        let (mb, sb, b) = pty()?;
        copy(ma.try_clone()?, mb.try_clone()?);
        copy(mb, ma);
        Ok(Self {
            a,
            b,
            _slaves: [sa, sb],
        })
    }
}
