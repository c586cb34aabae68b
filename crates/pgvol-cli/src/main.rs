//! `pgvol`: meshes to compact implicit files and back. Argument parsing and printing only; the
//! work is the `pgvol` library's.

#![forbid(unsafe_code)]

mod commands;
mod output;
mod progress;

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
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
