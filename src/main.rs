//! The `render` command: parses the command line and dispatches to the library's commands
//! (`trilux::cli`). No rendering logic lives here.

use std::process::ExitCode;

use trilux::cli::{self, Cli, Command};
use trilux::generate;

fn main() -> ExitCode {
    let cli = Cli::parse_args();
    let result = match &cli.command {
        None => cli::render::run(&cli.render),
        Some(Command::BenchAccel(args)) => cli::tools::bench_accel(args),
        Some(Command::Report(args)) => cli::tools::report(args),
        Some(Command::Compare {
            image,
            reference,
            heatmap,
        }) => cli::tools::compare(image, reference, heatmap.as_deref()),
        Some(Command::Farm(args)) => cli::farm::run(args),
        Some(Command::View { words }) => trilux::viewer::run(words),
        Some(Command::Merge {
            parts,
            output,
            variance,
        }) => cli::tools::merge(parts, output, variance.as_deref()),
        Some(Command::Man { output }) => cli::tools::man(output.as_deref()),
        Some(Command::GenTerrain { triangles, output }) => generate::check_size(
            "gen-terrain",
            "triangles",
            *triangles,
            generate::MAX_PRIMITIVES,
        )
        .and_then(|_| {
            generate::write_obj(&generate::terrain(*triangles), output).map_err(|e| e.to_string())
        }),
        Some(Command::GenRoom { patches, output }) => {
            generate::check_size("gen-room", "quads", *patches, generate::MAX_PRIMITIVES).and_then(
                |_| {
                    generate::write_dialect(&generate::room(*patches), output)
                        .map_err(|e| e.to_string())
                },
            )
        }
        Some(Command::GenTexture { kind, size, output }) => generate::check_size(
            "gen-texture --size",
            "pixels a side",
            *size as usize,
            generate::MAX_TEXTURE_SIDE,
        )
        .and_then(|_| {
            let rgb = generate::texture(*kind, *size);
            generate::write_ppm(&rgb, *size, output).map_err(|e| e.to_string())
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
