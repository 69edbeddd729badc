//! Work bounded before it starts: the limits every entry point checks before it allocates or
//! loops (bytes of a result, steps of an integration or a control loop, the clock's resolution),
//! each refusal an [`Error::InvalidArgument`] naming the argument and saying what to change.
//!
//! The limits are documented in `docs/boundary.md`; they are far above any table-tennis use
//! (a stroke of a few seconds sampled at 1 kHz is 10⁴ samples) and far below what aborts the
//! process (an allocation that fails) or runs for minutes.

use crate::error::{Error, Result};

/// Most bytes one call may allocate for its result or working arrays: 512 MiB.
pub const MAX_BYTES: usize = 512 << 20;

/// Most integration or control-loop steps one call may take: 10⁸ (about 1–10 s of work).
pub const MAX_STEPS: f64 = 1e8;

/// Fewest distinct clock values a step must keep at time t: a step h at |t| must exceed
/// `CLOCK_BITS_RATIO` times the spacing of float64 numbers at |t| (h carried to 10 bits).
pub const CLOCK_BITS_RATIO: f64 = 1024.0;

/// Largest robot, URDF or hit file a reader accepts: 16 MiB (a 1000-joint URDF is about 1 MiB).
pub const MAX_FILE_BYTES: u64 = 16 << 20;

/// Deepest element nesting a URDF may have (a URDF is 4 levels deep; a parser recurses once a level).
pub const MAX_XML_DEPTH: usize = 64;

/// Most joints a URDF may declare.
pub const MAX_URDF_JOINTS: usize = 4096;

/// A caller's request to stop long work early (Ctrl-C seen by the Python binding), polled
/// between items (targets, balls) and every [`STOP_POLL_STEPS`] steps of a loop; `&|| false`
/// never stops. The work then ends with [`stopped`]'s error, which the caller replaces by its own
/// (Python's `KeyboardInterrupt`).
pub type Stop<'a> = &'a (dyn Fn() -> bool + Sync);

/// How many steps of an integration or control loop run between two polls of a [`Stop`]
/// (about 0.1–1 ms of work).
pub const STOP_POLL_STEPS: u64 = 1024;

/// The error of work that a [`Stop`] ended; `what` names the argument that set the work's size.
pub fn stopped(what: &str) -> Error {
    Error::invalid(what, "stopped by the caller before the end (an interrupt)")
}

/// Reads the text file at `path`, refusing more than [`MAX_FILE_BYTES`] (read no further: a
/// device such as `/dev/zero` ends the read) and bytes that are not UTF-8 (with their offset).
pub fn read_text(path: &std::path::Path) -> Result<String> {
    read_text_limited(path).map_err(|reason| Error::File {
        path: path.display().to_string(),
        reason,
    })
}

/// [`read_text`] with the reason of a failure as text (for readers of other files: the
/// controller's configuration and trajectory files).
pub fn read_text_limited(path: &std::path::Path) -> std::result::Result<String, String> {
    use std::io::Read;
    let f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    f.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(format!(
            "larger than {MAX_FILE_BYTES} bytes (16 MiB), the most a file may be"
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "not UTF-8 text: invalid byte at offset {}",
            e.utf8_error().valid_up_to()
        )
    })
}

/// Checks that `count` items of `bytes_per_item` bytes each fit in [`MAX_BYTES`] (a count that
/// is not finite or < 0 is refused too); returns the count. `what` names the argument that sets it.
pub fn check_bytes(what: &str, count: f64, bytes_per_item: usize) -> Result<usize> {
    let bytes = count * bytes_per_item.max(1) as f64;
    if !(count >= 0.0 && bytes <= MAX_BYTES as f64) {
        return Err(Error::invalid(
            what,
            format!(
                "asks for {count:.4e} items of {bytes_per_item} bytes ({:.3e} bytes); at most {MAX_BYTES} bytes \
                 (512 MiB) per call: ask for fewer samples or a shorter span",
                bytes
            ),
        ));
    }
    Ok(count as usize)
}

/// Checks that covering `span` (s) in steps of `step` (s) takes at most [`MAX_STEPS`] steps;
/// returns the number of steps (rounded up). `what` names the argument that sets the span.
pub fn check_steps(what: &str, span: f64, step: f64) -> Result<u64> {
    let steps = (span / step).ceil();
    if !(span.is_finite() && step > 0.0 && step.is_finite()) {
        return Err(Error::invalid(
            what,
            format!("a span of {span} s in steps of {step} s: both must be finite, the step > 0"),
        ));
    }
    if !(steps <= MAX_STEPS) {
        return Err(Error::invalid(
            what,
            format!(
                "{span} s in steps of {step} s is {steps:.3e} steps; at most {MAX_STEPS:e} steps per call: \
                 ask for a shorter span or a slower rate"
            ),
        ));
    }
    Ok(steps.max(0.0) as u64)
}

/// Checks that a clock at time `t` (s) still advances by a step of `step` (s) with
/// [`CLOCK_BITS_RATIO`] to spare: far from zero the spacing of float64 numbers grows (0.125 s at
/// 10¹⁵ s) and `t + step == t` would stop the clock. `what` names the time argument.
pub fn check_clock(what: &str, t: f64, step: f64) -> Result<()> {
    if !t.is_finite() {
        return Err(Error::NonFinite {
            what: what.to_string(),
            index: 0,
            value: t,
        });
    }
    let spacing = t.abs() * f64::EPSILON;
    if spacing * CLOCK_BITS_RATIO > step {
        return Err(Error::invalid(
            what,
            format!(
                "at t = {t:e} s float64 times are {spacing:.3e} s apart, too coarse for steps of {step:e} s; \
                 count times from a nearer origin (at most {:.3e} s from 0 at this step)",
                step / (CLOCK_BITS_RATIO * f64::EPSILON)
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_steps_and_clock_are_bounded() {
        assert_eq!(check_bytes("n", 10.0, 8).unwrap(), 10);
        assert!(check_bytes("n", 1e8, 19 * 8).is_err());
        assert!(check_bytes("n", f64::NAN, 8).is_err());
        assert!(check_bytes("n", -1.0, 8).is_err());
        assert!(check_bytes("n", f64::INFINITY, 8).is_err());
        assert_eq!(check_steps("d", 1.0, 0.25).unwrap(), 4);
        assert!(check_steps("d", 1e7, 0.002).is_err());
        assert!(check_steps("d", f64::NAN, 0.002).is_err());
        assert!(check_steps("d", 1.0, 0.0).is_err());
        // Unix times carry a 1 ms step; 1e15 s does not carry 2 ms.
        assert!(check_clock("t", 1.7e9, 1e-3).is_ok());
        assert!(check_clock("t", 1e15, 2e-3).is_err());
        assert!(check_clock("t", 1e17, 2e-3).is_err());
        assert!(check_clock("t", f64::NAN, 2e-3).is_err());
        let e = check_clock("t", 1e17, 2e-3).unwrap_err().to_string();
        assert!(e.contains("t") && e.contains("nearer origin"), "{e}");
    }
}
