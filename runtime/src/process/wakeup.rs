//! The CPU wake-up latency limit of a real-time run or driver (`--cpu-wakeup-us`):
//! Linux's PM QoS request through `/dev/cpu_dma_latency`, which holds while the file
//! stays open.
//!
//! An idle CPU sleeps in an idle state, and waking it (the plant's timer, a message's
//! event) first waits for the state's exit; a virtual CPU that halts is woken by its
//! host. A limit of `L` µs keeps idle CPUs in states that exit within `L` µs; 0 keeps them
//! polling. The same request `cyclictest` makes by default.

use std::fs::File;
use std::io::{Read, Write};
use std::path::Path;

use super::SystemError;

/// The PM QoS device of the CPU wake-up latency limit.
pub const DEVICE: &str = "/dev/cpu_dma_latency";

/// The largest limit the kernel takes \[µs\] (an `i32`).
const MAX_US: u32 = i32::MAX as u32;

/// The flag of `rig run`, `rig latency` and `rig sim-driver`.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Wakeup {
    /// Hold the machine's CPU wake-up latency limit at this many µs while the command
    /// runs (Linux PM QoS, /dev/cpu_dma_latency; needs root): idle CPUs then use only
    /// idle states they leave within the limit, and 0 keeps them polling, so that the
    /// plant's sampling timer and each message's wake-up do not wait for a CPU to leave
    /// a deep idle state. A polling idle CPU is a busy one: more power, and on a virtual
    /// machine time the host counts as used [default: the operating system's choice].
    #[cfg_attr(feature = "cli", arg(long, value_name = "US", value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_US))))]
    pub cpu_wakeup_us: Option<u32>,
}

/// A held limit: released when dropped (the device closed).
#[derive(Debug)]
pub struct WakeupLimit {
    _device: Option<File>,
}

impl Wakeup {
    /// Makes the request, if one is asked for; an error names the device and the flag.
    pub fn hold(&self) -> Result<WakeupLimit, SystemError> {
        hold_at(Path::new(DEVICE), self.cpu_wakeup_us)
    }
}

/// Requests a limit of `us` µs through `device` (nothing for `None`).
fn hold_at(device: &Path, us: Option<u32>) -> Result<WakeupLimit, SystemError> {
    let Some(us) = us else {
        return Ok(WakeupLimit { _device: None });
    };
    let value = i32::try_from(us).map_err(|_| SystemError::WakeupRange { us, max: MAX_US })?;
    let refused = |source| SystemError::Wakeup {
        us,
        device: device.to_path_buf(),
        source,
    };
    let mut file = File::options().write(true).open(device).map_err(refused)?;
    // The kernel reads a binary `s32` in the machine's byte order.
    file.write_all(&value.to_ne_bytes()).map_err(refused)?;
    Ok(WakeupLimit {
        _device: Some(file),
    })
}

/// The limit in force on this machine \[µs\] (the smallest request held), if it can be read.
pub fn current() -> Option<u32> {
    current_at(Path::new(DEVICE))
}

fn current_at(device: &Path) -> Option<u32> {
    let mut b = [0u8; 4];
    File::open(device).ok()?.read_exact(&mut b).ok()?;
    u32::try_from(i32::from_ne_bytes(b)).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_limit_asked_touches_nothing() {
        let missing = Path::new("/nonexistent/cpu_dma_latency");
        assert!(hold_at(missing, None).is_ok());
    }

    #[test]
    fn the_request_is_a_native_s32() {
        let dir = std::env::temp_dir().join(format!("wakeup-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("device");
        std::fs::write(&path, b"").unwrap();
        let held = hold_at(&path, Some(250)).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), 250i32.to_ne_bytes());
        assert_eq!(current_at(&path), Some(250));
        drop(held);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_device_that_cannot_be_opened_is_named_with_the_flag() {
        let e = hold_at(Path::new("/nonexistent/cpu_dma_latency"), Some(0)).unwrap_err();
        let e = format!("{e:#}");
        assert!(e.contains("--cpu-wakeup-us"), "{e}");
        assert!(e.contains("/nonexistent/cpu_dma_latency"), "{e}");
    }

    #[test]
    fn the_kernel_keeps_the_limit_while_it_is_held() {
        // Only where this process may make the request (root, PM QoS in the kernel).
        let Ok(held) = Wakeup {
            cpu_wakeup_us: Some(3),
        }
        .hold() else {
            return;
        };
        let now = current().expect("the limit in force is readable where it can be set");
        assert!(now <= 3, "limit {now} µs while 3 µs is held");
        drop(held);
    }
}
