//! The subcommands beside rendering: `bench-accel`, `report`, `compare` and `merge`.

use std::path::{Path, PathBuf};

use clap::Args;

use super::{default_accels, default_report_engines, emit};
use crate::accel::{AccelKind, AccelOptions};
use crate::engines::EngineKind;
use crate::scene::Scene;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// A scene file, or `terrain:N` for a generated terrain of N triangles.
    pub scene: String,
    /// Rays per ray set.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
    /// Timings per cell; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Worker threads for the "all threads" rows (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Embree's robust (watertight) mode, as for rendering.
    #[arg(long, default_value_t = true, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    pub embree_robust: bool,
    /// Embree's hits decided by trilux's exact routines, as for rendering (`false`: Embree's
    /// own test, what Embree alone costs).
    #[arg(long, default_value_t = true, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    pub embree_exact: bool,
    /// Backends to measure.
    #[arg(long, value_delimiter = ',', default_values_t = default_accels())]
    pub accel: Vec<AccelKind>,
    /// Ray sets to measure.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["camera", "incoherent", "shadow"])]
    pub sets: Vec<crate::bench::RaySet>,
    /// Queries to measure.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["closest", "occluded"])]
    pub queries: Vec<crate::bench::Query>,
    /// Single rays per call, batches, or both.
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["single", "batched"])]
    pub modes: Vec<crate::bench::Mode>,
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Engines to measure.
    #[arg(long, value_delimiter = ',', default_values_t = default_report_engines())]
    pub engines: Vec<EngineKind>,
    /// Accels to run each engine on.
    #[arg(long, value_delimiter = ',', default_values_t = default_accels())]
    pub accel: Vec<AccelKind>,
    /// Image width and height.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [96, 96])]
    pub size: Vec<u32>,
    /// Seeds per budget; errors are averaged over them, a budget's time is the fastest seed's.
    #[arg(long, default_value_t = 2)]
    pub seeds: u32,
    /// Wall-time limit of the whole report in seconds, reference render included.
    #[arg(long, default_value_t = 600.0)]
    pub time_limit: f64,
    /// Reference image (PFM, EXR or PNG); default: a path-traced render, cached in the
    /// output directory.
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_samples: u32,
    /// Output directory (default: `report-` and the scene's name, e.g. report-cornell_box).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn bench_accel(args: &BenchArgs) -> Result<(), String> {
    let scene = match args.scene.strip_prefix("terrain:") {
        Some(n) => crate::generate::terrain(
            n.parse()
                .map_err(|_| format!("terrain:N needs a number, found {n}"))?,
        ),
        None => Scene::load(Path::new(&args.scene)).map_err(|e| e.to_string())?,
    };
    let pool = crate::parallel::thread_pool(args.threads).map_err(|e| e.to_string())?;
    crate::parallel::worker_start();
    let threads = pool.current_num_threads();
    let options = AccelOptions {
        embree_robust: args.embree_robust,
        embree_exact: args.embree_exact,
        ..AccelOptions::default()
    };
    let report = pool
        .install(|| {
            crate::bench::bench_accel(
                &scene,
                &args.accel,
                &options,
                &crate::bench::Cells {
                    sets: args.sets.clone(),
                    queries: args.queries.clone(),
                    modes: args.modes.clone(),
                },
                args.rays,
                args.repeats,
                threads,
            )
        })
        .map_err(|e| e.to_string())?;
    let mut lines = vec![
        format!(
            "scene: {} ({} primitives), {} rays per set, median of {} runs, embree robust: {}, embree exact: {}",
            args.scene,
            scene.primitive_count(),
            args.rays,
            args.repeats,
            args.embree_robust,
            args.embree_exact
        ),
        String::new(),
        "| backend | build (s) |".into(),
        "|---|---|".into(),
    ];
    lines.extend(
        report
            .builds
            .iter()
            .map(|(name, s)| format!("| {name} | {s:.3} |")),
    );
    lines.push(String::new());
    lines.push("| backend | rays | query | mode | threads | Mrays/s |".into());
    lines.push("|---|---|---|---|---|---|".into());
    lines.extend(report.rows.iter().map(|r| {
        format!(
            "| {} | {} | {} | {} | {} | {:.2} |",
            r.backend, r.rays, r.query, r.mode, r.threads, r.mrays_per_s
        )
    }));
    lines.push(String::new());
    let ratios = report.ratios();
    if !ratios.is_empty() {
        lines.push("| rays | query | mode | threads | bvh / embree (Mrays/s) |".into());
        lines.push("|---|---|---|---|---|".into());
        lines.extend(ratios.iter().map(|(r, ratio)| {
            format!(
                "| {} | {} | {} | {} | {ratio:.2} |",
                r.rays, r.query, r.mode, r.threads
            )
        }));
        lines.push(String::new());
    }
    if let Some(build) = report.build_ratio() {
        lines.push(format!("build: bvh / embree = {build:.2} (time)"));
        lines.push(String::new());
    }
    emit(&lines.join("\n"))
}

pub fn report(args: &ReportArgs) -> Result<(), String> {
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let settings = crate::report::ReportSettings {
        engines: args.engines.clone(),
        accels: args.accel.clone(),
        width: args.size[0],
        height: args.size[1],
        seeds: args.seeds.max(1),
        time_limit: args.time_limit,
        reference: args.reference.clone(),
        reference_samples: args.reference_samples.max(1),
        output: args
            .output
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("report-{stem}"))),
        quiet: args.quiet,
    };
    if settings.width == 0 || settings.height == 0 {
        return Err("--size: both must be at least 1".into());
    }
    let pool = crate::parallel::thread_pool(args.threads).map_err(|e| e.to_string())?;
    crate::parallel::worker_start();
    crate::interrupt::install();
    let report = pool.install(|| crate::report::run(&args.scene, &settings))?;
    emit(&crate::report::summary(&report, &settings))?;
    let wrote = format!(
        "report.csv, report.png and report.md in {}",
        settings.output.display()
    );
    if crate::interrupt::requested() {
        return Err(format!(
            "interrupted: wrote {wrote} with the runs finished so far"
        ));
    }
    if !args.quiet {
        eprintln!("wrote {wrote}");
    }
    Ok(())
}

pub fn compare(image: &Path, reference: &Path, heatmap: Option<&Path>) -> Result<(), String> {
    use crate::film::metrics;
    let a = metrics::read_image(image)?;
    let b = metrics::read_image(reference)?;
    let m = metrics::compare(&a, &b)?;
    if let Some(path) = heatmap {
        metrics::heatmap(&a, &b)
            .write(path)
            .map_err(|e| e.to_string())?;
    }
    emit(&format!(
        "rmse {:.6e}\nrelmse {:.6e}\nmape {:.6e}\nmax_error {:.6e}\n",
        m.rmse, m.relmse, m.mape, m.max_error
    ))
}

/// `render merge PART... -o OUT [--variance FILE]`.
pub fn merge(parts: &[PathBuf], output: &Path, variance: Option<&Path>) -> Result<(), String> {
    crate::film::ImageFormat::check_output(output).map_err(|e| e.to_string())?;
    if let Some(path) = variance {
        super::args::check_variance_output(path).map_err(|e| format!("--variance: {e}"))?;
    }
    let read: Vec<(PathBuf, crate::film::part::Part)> = parts
        .iter()
        .map(|p| crate::film::part::read(p).map(|part| (p.clone(), part)))
        .collect::<Result<_, _>>()?;
    let film = crate::film::part::merge(read)?;
    film.write(output).map_err(|e| e.to_string())?;
    if let Some(path) = variance {
        super::render::write_variance(&film, path)?;
    }
    eprintln!("merged {} parts into {}", parts.len(), output.display());
    Ok(())
}

/// `render man`: the manual page, generated by `clap_mangen` from the definitions that make
/// `render --help`, so that the two cannot disagree. The render command's page comes first,
/// then one page per subcommand (`render-farm`, …), each with its own title, as `git`'s are.
pub fn man(output: Option<&Path>) -> Result<(), String> {
    use clap::CommandFactory;
    let mut command = super::Cli::command();
    command.build();
    let mut page = Vec::new();
    let write_error = |e: std::io::Error| format!("cannot write the manual page: {e}");
    clap_mangen::Man::new(command.clone())
        .render(&mut page)
        .map_err(write_error)?;
    let source = format!("render {}", env!("CARGO_PKG_VERSION"));
    for sub in command.get_subcommands().filter(|s| s.get_name() != "help") {
        let sub = sub
            .clone()
            .display_name(format!("render-{}", sub.get_name()))
            .bin_name(format!("render {}", sub.get_name()));
        clap_mangen::Man::new(sub)
            .source(source.clone())
            .render(&mut page)
            .map_err(write_error)?;
    }
    let text = String::from_utf8_lossy(&page);
    match output {
        None => emit(&text),
        Some(path) => std::fs::write(path, page.as_slice())
            .map_err(|e| format!("cannot write {}: {e}", path.display())),
    }
}
