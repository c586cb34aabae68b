//! `pgvol`: meshes to compact implicit files and back. Argument parsing and printing only; the
//! work is the `pgvol` library's.

#![forbid(unsafe_code)]

mod commands;
mod output;
mod progress;
mod report;

use clap::Parser;

/// Turns triangle meshes into smooth implicit fields (coefficient volumes) and back into meshes.
///
/// Signed distance is negative inside and positive outside, in the units of the input mesh. The
/// grid is a cube of side 1.1 × the longest bounding-box extent, centred on the mesh, with N nodes
/// per axis (--res N) or a given spacing (--voxel H).
///
/// Example: pgvol remesh part.stl -o part.glb --res 256
#[derive(Parser)]
#[command(name = "pgvol", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: commands::Command,
}

fn main() {
    // Interrupted or terminated mid-write: remove the temporary files, keep the old outputs.
    // Without the handler the process still ends, only leaving the temporaries behind.
    let _ = ctrlc::set_handler(|| {
        pgvol::core::atomic::remove_pending_temporaries();
        eprintln!("pgvol: interrupted");
        std::process::exit(130);
    });
    let cli = Cli::parse();
    if let Err(e) = commands::run(cli.command) {
        eprintln!("error: {}", message(&e));
        std::process::exit(1);
    }
}

/// The error and its causes, joined by ": ", leaving out a cause whose text is already there:
/// the library's messages include their cause's sentence, which would otherwise print twice.
fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::message;

    #[test]
    fn a_cause_already_in_the_message_is_printed_once() {
        let cause = std::io::Error::other("5 points given; at least 10 are needed");
        let e = pgvol::Error::parameter(format!("fit: {cause}")).caused_by(cause);
        assert_eq!(
            message(&anyhow::Error::from(e).context("a.xyz")),
            "a.xyz: fit: 5 points given; at least 10 are needed"
        );
        // A cause the message does not repeat is kept.
        let e = anyhow::Error::from(std::io::Error::other("disk full")).context("writing b.pgv");
        assert_eq!(message(&e), "writing b.pgv: disk full");
    }
}
