//! `pgvol`: meshes to compact implicit files and back. Argument parsing and printing only; the
//! work is the `pgvol` library's.

#![forbid(unsafe_code)]

mod commands;
mod field_text;
mod output;
mod parse;
mod progress;
mod remedy;
mod report;

use clap::{CommandFactory, FromArgMatches, Parser};

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

/// The command line, every option's value allowed to be a negative number: `--voxel -0.1` is
/// then refused by the option's own check ("must be positive") rather than read as an unknown
/// flag `-0`.
fn command_line() -> clap::Command {
    Cli::command().mut_subcommands(|sub| {
        let takes_values: Vec<clap::Id> = sub
            .get_arguments()
            .filter(|a| a.get_action().takes_values())
            .map(|a| a.get_id().clone())
            .collect();
        takes_values.into_iter().fold(sub, |sub, id| {
            sub.mut_arg(id, |a| a.allow_negative_numbers(true))
        })
    })
}

fn main() {
    // Interrupted or terminated mid-write: remove the temporary files, keep the old outputs.
    // Without the handler the process still ends, only leaving the temporaries behind.
    let _ = ctrlc::set_handler(|| {
        pgvol::core::atomic::remove_pending_temporaries();
        eprintln!("pgvol: interrupted");
        std::process::exit(130);
    });
    let matches = command_line().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    if let Err(e) = commands::run(cli.command) {
        match remedy::hint_for(&e) {
            Some(hint) => eprintln!("error: {} ({hint})", message(&e)),
            None => eprintln!("error: {}", message(&e)),
        }
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
    use super::*;
    use clap::CommandFactory;

    /// The command lines in a help text: lines that start with `pgvol `, or carry one after a
    /// label (`Example: pgvol …`), less a trailing remark in parentheses.
    fn example_lines(text: &str) -> Vec<String> {
        text.lines()
            .filter_map(|line| {
                let line = line.trim();
                let line = match line.find(": pgvol ") {
                    Some(at) => &line[at + 2..],
                    None if line.starts_with("pgvol ") => line,
                    None => return None,
                };
                let line = line.find("  (").map_or(line, |at| &line[..at]);
                Some(line.trim().to_string())
            })
            .collect()
    }

    /// A negative value reaches the option's own check, which names the option; flags that
    /// are not numbers stay flags.
    #[test]
    fn negative_values_are_values() {
        let parse = |words: &str| {
            let matches = command_line().try_get_matches_from(words.split_whitespace())?;
            Cli::from_arg_matches(&matches)
        };
        let cli = parse("pgvol encode m.obj -o x.pgv --voxel -0.1 -q").unwrap();
        let commands::Command::Encode(a) = cli.command else {
            panic!("not an encode")
        };
        assert_eq!(a.grid.voxel, Some(-0.1));
        assert!(a.out.quiet);
        let Err(e) = parse("pgvol encode m.obj -o x.pgv --res -5") else {
            panic!("--res -5 parsed")
        };
        assert!(e.to_string().contains("'-5' for '--res"), "{e}");
    }

    #[test]
    fn every_example_in_the_help_parses() {
        let root = Cli::command();
        let mut texts = vec![(
            "pgvol".to_string(),
            root.get_long_about()
                .or(root.get_about())
                .map(|t| t.to_string())
                .unwrap_or_default(),
        )];
        for sub in root.get_subcommands() {
            let name = sub.get_name().to_string();
            for text in [sub.get_after_help(), sub.get_after_long_help()]
                .into_iter()
                .flatten()
            {
                texts.push((name.clone(), text.to_string()));
            }
        }
        let mut parsed = 0;
        for (name, text) in &texts {
            let examples = example_lines(text);
            assert!(
                !text.contains("Example") || !examples.is_empty(),
                "{name}: no command line found in {text:?}"
            );
            for line in examples {
                let words: Vec<&str> = line.split_whitespace().collect();
                if let Err(e) = Cli::try_parse_from(&words) {
                    panic!("{name}: the example `{line}` does not parse:\n{e}");
                }
                parsed += 1;
            }
        }
        // Every subcommand but a few shows an example.
        assert!(parsed >= 15, "only {parsed} examples found");
    }

    #[test]
    fn comma_lists_may_start_with_a_minus() {
        for line in [
            "pgvol csg union sphere:0,0,0,1 plane:0,0,1,0 -o u.stl --box -1,-1,-1,1,1,1",
            "pgvol blend ipatch plane:1,0,0,0 plane:0,1,0,0 --bound plane:-1,0,0,1 \
             --bound plane:0,-1,0,1 --weights -1,2,-0.5 -o b.stl",
            "pgvol repair a.pgv -o b.pgv --mask -5,-5,20,5,5,32 --mask -1,-1,-1,0,0,0 --face -z",
            "pgvol shell a.stl -o b.stl --thickness 1 --hollow --drain -1,0,0,-1,0,0,0.5",
            "pgvol lattice a.stl -o b.stl --surface gyroid --cell 5 --thickness 0.5 \
             --grade-linear -1,0,0,1,0,0 --cell-far 3",
        ] {
            let words: Vec<&str> = line.split_whitespace().collect();
            if let Err(e) = Cli::try_parse_from(&words) {
                panic!("`{line}` does not parse:\n{e}");
            }
        }
    }

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

    #[test]
    fn coarse_samples_out_of_range_are_refused_by_the_parser() {
        for coarse in ["3", "9000", "100000000", "-1"] {
            let line = format!(
                "pgvol repair a.pgv -o b.pgv --mask 0,0,0,1,1,1 --denoise --coarse={coarse}"
            );
            let e = Cli::try_parse_from(line.split_whitespace())
                .err()
                .unwrap_or_else(|| panic!("--coarse {coarse} parsed"))
                .to_string();
            let range = format!("expected 4 to {}", pgvol::limits::MAX_RES);
            assert!(e.contains("--coarse") && e.contains(&range), "{e}");
        }
    }

    /// Tests that run a command take turns: the memory limit is global.
    static RUN: std::sync::Mutex<()> = std::sync::Mutex::new(());

    #[test]
    fn an_edit_written_dense_is_refused_before_work_with_its_figure() {
        let _turn = RUN.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("u.pgv");
        let cli = Cli::try_parse_from([
            "pgvol",
            "csg",
            "union",
            "sphere:0,0,0,1",
            "sphere:0.5,0,0,1",
            "--res",
            "600",
            "--max-memory",
            "100M",
            "--quiet",
            "-o",
            out.to_str().unwrap(),
        ])
        .unwrap();
        let e = commands::run(cli.command).unwrap_err().to_string();
        pgvol::limits::set_memory_limit(None);
        assert!(
            e.contains("600 x 600 x 600 grid needs about") && e.contains("100.0 MB allowed"),
            "{e}"
        );
        assert!(!out.exists());
    }

    #[test]
    fn an_ipatch_without_a_bound_per_primary_names_the_option() {
        let _turn = RUN.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("b.stl");
        let cli = Cli::try_parse_from([
            "pgvol",
            "blend",
            "ipatch",
            "plane:1,0,0,0",
            "plane:0,1,0,0",
            "--bound",
            "plane:-1,0,0,1",
            "--weights",
            "1,1,-0.5",
            "--box=-1,-1,-1,1,1,1",
            "--quiet",
            "-o",
            out.to_str().unwrap(),
        ])
        .unwrap();
        let e = commands::run(cli.command).unwrap_err().to_string();
        assert!(e.contains("one --bound per primary"), "{e}");
        assert!(!out.exists());
    }

    /// Runs `pgvol blend` with `args` into `out` (quietly, on the unit box at a small grid).
    fn run_blend(args: &[&str], out: &std::path::Path) -> anyhow::Result<()> {
        let mut words = vec!["pgvol", "blend"];
        words.extend_from_slice(args);
        words.extend(["--box=-1,-1,-1,1,1,1", "--res", "40", "--quiet", "-o"]);
        words.push(out.to_str().unwrap());
        let cli = Cli::try_parse_from(&words).map_err(anyhow::Error::from)?;
        commands::run(cli.command)
    }

    #[test]
    fn continuity_orders_out_of_range_are_refused_by_the_parser() {
        for order in ["0", "5", "-1", "x"] {
            let line = format!(
                "pgvol blend ipatch plane:1,0,0,0 plane:0,1,0,0 --bound plane:-1,0,0,1 \
                 --bound plane:0,-1,0,1 --weights 1,1,-0.5 --continuity={order} -o b.stl"
            );
            let e = Cli::try_parse_from(line.split_whitespace())
                .err()
                .unwrap_or_else(|| panic!("--continuity {order} parsed"))
                .to_string();
            assert!(e.contains("--continuity"), "{e}");
        }
    }

    #[test]
    fn an_ipatch_through_a_point_of_order_two_passes_through_it() {
        let _turn = RUN.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("b.pgv");
        let ipatch = [
            "ipatch",
            "plane:1,0,0,0",
            "plane:0,1,0,0",
            "--bound",
            "plane:-1,0,0,0.8",
            "--bound",
            "plane:0,-1,0,0.8",
            "--continuity",
            "2",
            "--through=-0.25,-0.35,0.1",
        ];
        run_blend(&ipatch, &out).unwrap();
        let shape = pgvol::Field::from_file(pgvol::io::read_pgv(&out).unwrap());
        let at = pgvol::glam::DVec3::new(-0.25, -0.35, 0.1);
        let v = shape.eval(&[at])[0].value;
        assert!(v.abs() < 0.02, "{v}");
        // Weights with --through are w1..wn only: n + 1 numbers are refused by name.
        let mut wrong = ipatch.to_vec();
        wrong.extend(["--weights", "1,1,0.5"]);
        let e = run_blend(&wrong, &out).unwrap_err().to_string();
        assert!(e.contains("--weights with --through"), "{e}");
        // The order belongs to I-patches.
        let e = run_blend(
            &[
                "spline",
                "plane:1,0,0,0",
                "plane:0,1,0,0",
                "--bound",
                "plane:-1,-1,0,1",
                "--continuity",
                "2",
            ],
            &out,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("ipatch only"), "{e}");
    }

    #[test]
    fn a_spline_of_three_primaries_and_one_bound_runs() {
        let _turn = RUN.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("v.pgv");
        run_blend(
            &[
                "spline",
                "plane:1,0,0,0",
                "plane:0,1,0,0",
                "plane:0,0,1,0",
                "--bound=plane:-1,-1,-1,1",
            ],
            &out,
        )
        .unwrap();
        let shape = pgvol::Field::from_file(pgvol::io::read_pgv(&out).unwrap());
        // The vertex is cut off; deep in the octant is inside.
        let values: Vec<f32> = shape
            .eval(&[
                pgvol::glam::DVec3::splat(-0.02),
                pgvol::glam::DVec3::splat(-0.5),
            ])
            .iter()
            .map(|e| e.value)
            .collect();
        assert!(values[0] > 0.0 && values[1] < 0.0, "{values:?}");
        // No bound is refused by name.
        let e = run_blend(&["spline", "plane:1,0,0,0", "plane:0,1,0,0"], &out)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--bound"), "{e}");
    }

    /// A text cloud of `n` points on the unit sphere with outward normals, in `dir`.
    fn sphere_cloud(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let mut text = String::new();
        for i in 0..n {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let rho = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            let (x, z) = (rho * phi.cos(), rho * phi.sin());
            text.push_str(&format!("{x} {y} {z} {x} {y} {z}\n"));
        }
        let path = dir.join("sphere.xyz");
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn sections_parse_as_an_axis_and_heights() {
        let parse = |extra: &[&str]| {
            let mut words = vec!["pgvol", "points", "c.xyz", "-o", "c.pgv"];
            words.extend_from_slice(extra);
            Cli::try_parse_from(&words).map(|cli| match cli.command {
                commands::Command::Points(a) => (a.sections, a.sections_out),
                _ => unreachable!(),
            })
        };
        let (sections, out) = parse(&["--sections", "z:-0.5,0, 0.5"]).unwrap();
        let sections = sections.unwrap();
        assert_eq!(sections.axis, pgvol::Axis::Z);
        assert_eq!(sections.heights, [-0.5, 0.0, 0.5]);
        assert_eq!(out, None);
        let (sections, out) = parse(&["--sections=X:-2", "--sections-out", "a.svg"]).unwrap();
        assert_eq!(sections.unwrap().axis, pgvol::Axis::X);
        assert_eq!(out.unwrap(), std::path::Path::new("a.svg"));
        for (bad, says) in [
            ("w:0", "the axis must be x, y or z"),
            ("0,1", "expected AXIS:H1,H2"),
            ("z:", "no heights after 'z:'"),
            ("z:0,,1", "the height ''"),
            ("y:inf", "not a finite number below 1e8"),
            ("y:1e9", "not a finite number below 1e8"),
            ("z:0,abc", "the height 'abc'"),
        ] {
            let e = parse(&["--sections", bad]).err().unwrap().to_string();
            assert!(e.contains("--sections") && e.contains(says), "{bad}: {e}");
        }
        // The output and the resolution need the sections.
        for extra in [
            ["--sections-out", "a.json"],
            ["--sections-resolution", "0.1"],
        ] {
            let e = parse(&extra).err().unwrap().to_string();
            assert!(e.contains("--sections <AXIS:H1,H2,...>"), "{e}");
        }
    }

    #[test]
    fn sections_are_written_beside_the_output_and_heights_outside_the_box_refused() {
        let _turn = RUN.lock().unwrap_or_else(|e| e.into_inner());
        let dir = tempfile::tempdir().unwrap();
        let cloud = sphere_cloud(dir.path(), 2000);
        let out = dir.path().join("s.pgv");
        let run = |sections: &str, extra: &[&str]| {
            let mut words = vec![
                "pgvol",
                "points",
                cloud.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--res",
                "40",
                "--quiet",
                "--sections",
                sections,
            ];
            words.extend_from_slice(extra);
            commands::run(Cli::try_parse_from(&words).unwrap().command)
        };
        // Refused before the fit, naming the option, the height and the box.
        let e = run("z:0,3", &[]).unwrap_err().to_string();
        assert!(
            e.contains("--sections:") && e.contains("z = 3") && e.contains("outside the grid box"),
            "{e}"
        );
        assert!(!out.exists());
        let e = run("z:0", &["--sections-out", "a.txt"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--sections-out") && e.contains(".json"), "{e}");
        let e = run("z:0", &["--sections-resolution", "0"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--sections-resolution"), "{e}");
        assert!(!out.exists());
        // Written to the default path, one layer per height, the empty one kept.
        run("z:0.5,-0.5,1.05", &[]).unwrap();
        let layers = pgvol::slicing::read_slice_json(&dir.path().join("s.sections.json")).unwrap();
        let heights: Vec<f32> = layers.iter().map(|l| l.height).collect();
        assert_eq!(heights, [-0.5, 0.5, 1.05]);
        let loops: Vec<usize> = layers.iter().map(|l| l.loops.len()).collect();
        assert_eq!(loops, [1, 1, 0]);
        let area = std::f64::consts::PI * 0.75;
        assert!(
            (layers[0].area() - area).abs() < 0.01 * area,
            "{}",
            layers[0].area()
        );
        // And to a file of another format.
        let svg = dir.path().join("cuts.svg");
        run("x:0", &["--sections-out", svg.to_str().unwrap()]).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        let layers = pgvol::slicing::read_svg(&text, &svg).unwrap();
        assert_eq!(layers.len(), 1);
        assert!((layers[0].area() - std::f64::consts::PI).abs() < 0.02 * std::f64::consts::PI);
    }
}
