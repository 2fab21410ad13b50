use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = weft::cli::Cli::parse();
    match weft::cli::run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
