use std::process::ExitCode;

use clap::Parser;

/// The heap, counted: the window's viewer keeps what it holds under its
/// memory limit by this count (`weft gui --memory-limit`), which a graphics
/// driver's own mappings do not enter.
#[cfg(feature = "viewer")]
#[global_allocator]
static HEAP: re_memory::AccountingAllocator<std::alloc::System> =
    re_memory::AccountingAllocator::new(std::alloc::System);

fn main() -> ExitCode {
    // Warnings (wgpu, the viewer, weft) go to stderr and the viewer's
    // notifications; `RUST_LOG` overrides the level, e.g. `RUST_LOG=info
    // weft gui`.
    re_log::setup_logging_with_filter(&re_log::log_filter_from_env_or_default("warn"));
    let cli = weft::cli::Cli::parse();
    match weft::cli::run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
