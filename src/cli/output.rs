//! A command's output on standard output: [`out!`] and [`outln!`], like
//! `print!` and `println!`, for a reader that may go away.

/// Writes a command's output to standard output, like `print!` (and
/// [`outln!`] like `println!`). A reader that went away
/// (`weft presets | head`) ends the output, not the command: the rest is
/// dropped, and the command still finishes its work and exits with its own
/// code (a `weft compare --fail-if` gate still fails). Any other failure to
/// write ends the process with `error: …` and code 2.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::output::write_out(format_args!($($arg)*))
    };
}
pub(crate) use out;

/// [`out!`] with a newline, like `println!`.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::output::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use outln;

/// [`out!`]'s writer.
pub(crate) fn write_out(args: std::fmt::Arguments) {
    use std::io::Write;
    use std::sync::atomic::{AtomicBool, Ordering};
    /// Set once the reader has gone away.
    static GONE: AtomicBool = AtomicBool::new(false);
    if GONE.load(Ordering::Relaxed) {
        return;
    }
    let mut stdout = std::io::stdout().lock();
    match stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => GONE.store(true, Ordering::Relaxed),
        Err(e) => {
            eprintln!("error: writing to standard output: {e}");
            std::process::exit(2);
        }
    }
}
