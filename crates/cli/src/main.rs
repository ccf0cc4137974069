//! `haze`: render Mitsuba 3 scenes with participating media.

mod bench;
mod compare;
mod cut_image;
mod limits;
mod output;
mod render_cmd;
mod report;
mod results;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "haze",
    version,
    about = "A renderer for participating media built around virtual ray lights"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a Mitsuba 3 XML scene to OUT.exr (linear RGB) and OUT.png (sRGB preview).
    Render(render_cmd::RenderArgs),
    /// Measure rendering throughput on scenes and print a table.
    Bench(bench::BenchArgs),
    /// Equal-time comparison of methods against a reference: a table, images, an HTML report.
    Compare(compare::CompareArgs),
    /// Render a reference image with volpath for a time budget (for `haze compare`).
    Reference(compare::ReferenceArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Reference(args) => compare::reference(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
