use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // Warnings (wgpu, the viewer, weft) go to stderr and the viewer's
    // notifications; `RUST_LOG` overrides the level, e.g. `RUST_LOG=info
    // weft gui`. Left out by default: the viewer's notice that it limits its
    // memory by the process's resident size (weft installs no allocation
    // tracker; that limit works as it should).
    re_log::setup_logging_with_filter(&re_log::log_filter_from_env_or_default(
        "warn,re_memory::memory_limit=error",
    ));
    let cli = weft::cli::Cli::parse();
    match weft::cli::run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
