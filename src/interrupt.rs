//! Ctrl-C for long headless jobs (`weft record`, `weft sweep`): the first
//! asks the job to stop at a clean point, a second quits at once with 130.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Installs the handler and returns the flag the first Ctrl-C sets. `first`
/// is printed when that happens (what the job will do now). If no handler
/// can be installed, says so on stderr: Ctrl-C then ends the process as
/// usual, without the clean stop.
pub fn stop_flag(first: Option<&'static str>) -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let installed = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            std::process::exit(130);
        }
        if let Some(text) = first {
            eprintln!("{text}");
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will end the job at once, without a clean stop ({e})");
    }
    stop
}
