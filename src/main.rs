use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // Warnings (wgpu, the viewer, weft) go to stderr; `RUST_LOG` overrides
    // the level, e.g. `RUST_LOG=info weft gui`.
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
