//! The exit statuses every ttmanip program shares (`ttctl`, `ttdrive-sim`, and the `ttmanip`
//! command line in Python, `ttmanip.cli`): success, bad input, and a motion that could not be done.

/// The program did what it was asked (a motion completed, a check passed).
pub const SUCCESS: i32 = 0;

/// Bad input: a usage error (unknown option, a value that does not parse or is out of range), a
/// file that cannot be read or fails its checks. Nothing was moved.
pub const BAD_INPUT: i32 = 1;

/// The input was accepted but the motion was not done: stopped by a fault (`ttctl`), a hit that
/// cannot be planned or a simulated run that faulted (`ttmanip`).
pub const NOT_DONE: i32 = 2;

/// Parses the command line with clap, exiting with [`BAD_INPUT`] on a usage error (clap's own
/// status is 2, which here means a fault stop) and [`SUCCESS`] after `--help` or `--version`.
pub fn parse_args<T: clap::Parser>() -> T {
    T::try_parse().unwrap_or_else(|e| {
        let _ = e.print();
        std::process::exit(if e.use_stderr() { BAD_INPUT } else { SUCCESS })
    })
}
