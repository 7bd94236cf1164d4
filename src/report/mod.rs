//! `render report`: each engine's error against run time, and Embree against the BVH.
//!
//! Every engine renders the scene at a doubling sequence of budgets (samples per pixel for the
//! ray and path tracers, photons for the photon engine, mesh subdivision for radiosity), with a
//! few seeds, on each Accel; every run is timed and measured against a reference — a converged
//! path-traced image, rendered once and cached in the output directory, or `--reference FILE`.
//! The results go to a CSV, a log-log plot of relMSE against wall time and a markdown summary
//! with the fitted slope of each curve and, per engine, how the two Accels' images and times
//! compare. The whole run stays within a time limit: each engine and Accel gets an equal share,
//! and a budget is started only when the time it is expected to take (twice the previous one)
//! still fits.

mod plot;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::accel::{self, AccelKind, AccelOptions};
use crate::engines::{self, EngineKind, RenderSettings};
use crate::film::metrics::{self, Metrics};
use crate::film::Film;
use crate::output::write_text_atomically;
use crate::scene::Scene;

/// What `render report` is asked to do.
#[derive(Clone, Debug)]
pub struct ReportSettings {
    /// Engines to measure (`--engines`, default raytrace,radiosity,photon,path).
    pub engines: Vec<EngineKind>,
    /// Accels to run each engine on (`--accel`, default every one this build has).
    pub accels: Vec<AccelKind>,
    /// Image size (`--size W H`, default 96 96).
    pub width: u32,
    pub height: u32,
    /// Seeds per budget (`--seeds`, default 2); errors are averaged over them, a budget's time
    /// is the fastest of them.
    pub seeds: u32,
    /// Wall-time limit of the whole report, reference included (`--time-limit`, default
    /// 600 s).
    pub time_limit: f64,
    /// The reference image (`--reference FILE`); default: a path-traced render cached in the
    /// output directory.
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the path-traced reference (`--reference-samples`, default 4096).
    pub reference_samples: u32,
    /// Where the CSV, the plot and the summary go (`-o DIR`, default `report-<scene>`).
    pub output: PathBuf,
    /// No progress bar (`--quiet`).
    pub quiet: bool,
}

/// One timed render and its error against the reference.
#[derive(Clone, Debug)]
pub struct Run {
    pub engine: EngineKind,
    pub accel: AccelKind,
    /// What the budget counts (`spp`, `photons`, `subdivide`) and its value.
    pub budget_kind: &'static str,
    pub budget: u64,
    pub seed: u64,
    /// Wall time of one render; for renders shorter than [`MIN_TIMED_SECONDS`], the fastest
    /// of its repetitions.
    pub seconds: f64,
    pub metrics: Metrics,
}

/// A curve of the plot: one engine on one Accel, each budget's error averaged over the seeds
/// and its time the fastest seed's: noise on a shared machine only ever adds time (a thread
/// woken late, another process), and at the few-millisecond budgets it can double a mean.
#[derive(Clone, Debug)]
pub struct Series {
    pub engine: EngineKind,
    pub accel: AccelKind,
    /// (budget, least seconds, mean relMSE, mean RMSE) per budget, in increasing budget.
    pub points: Vec<(u64, f64, f64, f64)>,
    /// Least-squares slope of ln relMSE against ln seconds (None with fewer than 2 budgets).
    pub slope: Option<f64>,
}

/// How the two Accels compare on one engine, over the runs both made.
#[derive(Clone, Debug)]
pub struct AccelComparison {
    pub engine: EngineKind,
    /// Runs both Accels made (same budget and seed).
    pub pairs: usize,
    /// Pixels that differ, over all pairs, and the largest difference of a channel.
    pub differing_pixels: usize,
    pub total_pixels: usize,
    pub max_difference: f32,
    /// BVH time over Embree time, summed over the pairs.
    pub bvh_over_embree: f64,
}

/// Everything the report measured.
pub struct Report {
    pub scene: PathBuf,
    pub runs: Vec<Run>,
    pub series: Vec<Series>,
    pub comparisons: Vec<AccelComparison>,
    /// Where the reference came from, and seconds spent making it (0 when read).
    pub reference: String,
    pub reference_seconds: f64,
    pub total_seconds: f64,
}

/// The relMSE levels whose time the report gives per curve.
const TARGET_ERRORS: [f64; 2] = [1e-2, 2e-3];

/// `y` at `x` on the curve through `points` (x increasing), interpolated on log-log axes;
/// None outside the curve.
fn log_log_at(points: &[(f64, f64)], x: f64) -> Option<f64> {
    let i = points.windows(2).position(|w| w[0].0 <= x && x <= w[1].0)?;
    let ((x0, y0), (x1, y1)) = (points[i], points[i + 1]);
    if x1 <= x0 {
        return Some(y0);
    }
    let f = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
    Some((y0.ln() + f * (y1.ln() - y0.ln())).exp())
}

/// The time at which the curve through `points` (time, relMSE) first comes down to `error`,
/// interpolated on log-log axes; None when it never does.
fn time_to(points: &[(f64, f64)], error: f64) -> Option<f64> {
    if points.first()?.1 <= error {
        return Some(points[0].0);
    }
    let i = points.windows(2).position(|w| w[1].1 <= error)?;
    let ((t0, e0), (t1, e1)) = (points[i], points[i + 1]);
    let f = (error.ln() - e0.ln()) / (e1.ln() - e0.ln());
    Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
}

/// The engines compared at equal time: each curve's relMSE at powers of two seconds (read off
/// the curve between its measured points), and the time each needs for the target errors.
fn equal_time(md: &mut String, series: &[Series]) {
    let curves: Vec<(&Series, Vec<(f64, f64)>)> = series
        .iter()
        .map(|s| {
            let mut c: Vec<(f64, f64)> = s.points.iter().map(|p| (p.1, p.2)).collect();
            c.sort_by(|a, b| a.0.total_cmp(&b.0));
            (s, c)
        })
        .filter(|(_, c)| c.len() >= 2)
        .collect();
    let longest = curves
        .iter()
        .filter_map(|(_, c)| c.last().map(|p| p.0))
        .fold(0.0f64, f64::max);
    if longest <= 0.0 {
        return;
    }
    let times: Vec<f64> = (-6..=10)
        .map(|k| 2f64.powi(k))
        .filter(|&t| t <= longest)
        .collect();
    let _ = writeln!(
        md,
        "\n## At equal time\n\nEach curve's relMSE read off it (log-log between its measured points; – outside them), and the time it needs for the relMSE on the right.\n"
    );
    let mut header = "| engine | accel |".to_string();
    let mut rule = "|---|---|".to_string();
    for t in &times {
        header += &format!(" {t} s |");
        rule += "---|";
    }
    for e in TARGET_ERRORS {
        header += &format!(" time to {e:.0e} (s) |");
        rule += "---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    for (s, c) in &curves {
        let mut row = format!("| {} | {} |", s.engine.name(), s.accel);
        for &t in &times {
            row += &log_log_at(c, t).map_or(" – |".to_string(), |e| format!(" {e:.2e} |"));
        }
        for e in TARGET_ERRORS {
            row += &time_to(c, e).map_or(" – |".to_string(), |t| format!(" {t:.3} |"));
        }
        let _ = writeln!(md, "{row}");
    }
}

/// Renders shorter than this are repeated (same seed, same image) until this much time has
/// passed, and timed by their fastest repetition. A 24×24 path-traced image at 1 spp takes
/// 0.6–2 ms here from one run to the next: single timings that short are mostly the machine's
/// scheduling, and they bent the path tracer's fitted slope from −1 to −1.2.
pub const MIN_TIMED_SECONDS: f64 = 0.05;

/// The seed of the reference render: apart from every seed the measured runs use.
const REFERENCE_SEED: u64 = 0x5eed_f00d;

/// Runs the report on the scene file and writes `report.csv`, `report.png` and `report.md`
/// into the output directory.
pub fn run(scene_path: &Path, settings: &ReportSettings) -> Result<Report, String> {
    let clock = Instant::now();
    let mut scene = Scene::load(scene_path).map_err(|e| e.to_string())?;
    scene.filter_textures_for(settings.width, settings.height);
    std::fs::create_dir_all(&settings.output)
        .map_err(|e| format!("{}: {e}", settings.output.display()))?;
    let base = RenderSettings {
        width: settings.width,
        height: settings.height,
        quiet: true,
        ..RenderSettings::default()
    };
    let (reference, reference_note, reference_seconds) = reference_image(&scene, &base, settings)?;
    if (reference.width, reference.height) != (settings.width, settings.height) {
        return Err(format!(
            "the reference is {}×{}, the report renders {}×{} (--size)",
            reference.width, reference.height, settings.width, settings.height
        ));
    }
    let bar = crate::progress::bar(settings.time_limit.ceil() as u64, "report", settings.quiet);
    let shares = (settings.engines.len() * settings.accels.len()).max(1) as f64;
    let mut runs = Vec::new();
    let mut films = Vec::new();
    for &accel_kind in &settings.accels {
        let accel = accel::build(&scene, accel_kind, &AccelOptions::default())
            .map_err(|e| e.to_string())?;
        for &engine in &settings.engines {
            let share = (settings.time_limit - clock.elapsed().as_secs_f64()).max(0.0)
                / (shares - (runs_started(&runs, &settings.accels, &settings.engines)) as f64);
            let started = Instant::now();
            // Seconds per seed of the last two budgets: the next one is predicted to grow by
            // their ratio (at least 2: budgets double; radiosity's N² cost grows 16×).
            let (mut last, mut growth) = (0.0f64, 2.0f64);
            for level in 0.. {
                let Some(engines::Budget {
                    counts: budget_kind,
                    value: budget,
                    settings: mut s,
                }) = engines::engine(engine).budget(level, &base)
                else {
                    break;
                };
                let predicted = growth * last * settings.seeds as f64;
                let over_share = started.elapsed().as_secs_f64() + predicted > share;
                let over_limit = clock.elapsed().as_secs_f64() + predicted > settings.time_limit;
                if (level > 0 && (over_share || over_limit)) || crate::interrupt::requested() {
                    break;
                }
                if engine == EngineKind::Path && budget * 16 > settings.reference_samples as u64 {
                    // Beyond this the reference's own noise would flatten the curve.
                    break;
                }
                let mut seconds = 0.0;
                for seed in 0..settings.seeds as u64 {
                    s.seed = seed;
                    bar.set_message(format!(
                        "{} {accel_kind} {budget_kind} {budget}",
                        engine.name()
                    ));
                    let timed_render = || {
                        let t = Instant::now();
                        let rendered = engines::render(engine, &scene, accel.as_ref(), &s)?;
                        Ok::<_, String>((rendered, t.elapsed().as_secs_f64()))
                    };
                    let (rendered, mut elapsed) = timed_render()?;
                    if crate::interrupt::requested() {
                        // The run in flight was cut short: its image is not what its
                        // budget renders, so it is left out.
                        break;
                    }
                    let mut spent = elapsed;
                    while spent < MIN_TIMED_SECONDS && !crate::interrupt::requested() {
                        let (_, again) = timed_render()?;
                        if crate::interrupt::requested() {
                            break; // a repetition cut short is not the run's time
                        }
                        elapsed = elapsed.min(again);
                        spent += again;
                    }
                    seconds += elapsed;
                    runs.push(Run {
                        engine,
                        accel: accel_kind,
                        budget_kind,
                        budget,
                        seed,
                        seconds: elapsed,
                        metrics: metrics::compare(&rendered.film, &reference)?,
                    });
                    films.push(rendered.film);
                    bar.set_position(clock.elapsed().as_secs().min(settings.time_limit as u64));
                }
                let per_seed = seconds / settings.seeds.max(1) as f64;
                if last > 0.0 {
                    growth = (per_seed / last).max(2.0);
                }
                last = per_seed;
            }
        }
    }
    bar.finish_and_clear();
    let series = series_of(&runs);
    let comparisons = compare_accels(&runs, &films);
    let report = Report {
        scene: scene_path.to_path_buf(),
        runs,
        series,
        comparisons,
        reference: reference_note,
        reference_seconds,
        total_seconds: clock.elapsed().as_secs_f64(),
    };
    write_report(&report, settings)?;
    Ok(report)
}

/// (Engine, Accel) pairs that have at least one run: the shares already spent.
fn runs_started(runs: &[Run], accels: &[AccelKind], engines: &[EngineKind]) -> usize {
    accels
        .iter()
        .flat_map(|a| engines.iter().map(move |e| (*a, *e)))
        .filter(|(a, e)| runs.iter().any(|r| r.accel == *a && r.engine == *e))
        .count()
}

/// The reference image: `--reference`, else the cached path-traced render, else a new one
/// (written to the cache). Returns it, where it came from, and the seconds spent rendering.
fn reference_image(
    scene: &Scene,
    base: &RenderSettings,
    settings: &ReportSettings,
) -> Result<(Film, String, f64), String> {
    if let Some(path) = &settings.reference {
        return Ok((metrics::read_image(path)?, path.display().to_string(), 0.0));
    }
    let stem = scene
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let cache = settings.output.join(format!(
        "reference-{stem}-{:016x}-{}x{}-{}spp.pfm",
        scene.file_hash(),
        settings.width,
        settings.height,
        settings.reference_samples
    ));
    if cache.exists() {
        return Ok((
            metrics::read_image(&cache)?,
            format!("{} (cached)", cache.display()),
            0.0,
        ));
    }
    let accel = accel::build(
        scene,
        AccelKind::default_available(),
        &AccelOptions::default(),
    )
    .map_err(|e| e.to_string())?;
    let s = RenderSettings {
        num_antialias_samples: settings.reference_samples,
        seed: REFERENCE_SEED,
        quiet: settings.quiet,
        ..base.clone()
    };
    let clock = Instant::now();
    let film = engines::render(EngineKind::Path, scene, accel.as_ref(), &s)?.film;
    let seconds = clock.elapsed().as_secs_f64();
    // A reference cut short by Ctrl-C is not the reference: caching it would spoil every
    // later report on the scene.
    if crate::interrupt::requested() {
        return Err("interrupted while rendering the reference: no report written".into());
    }
    film.write(&cache).map_err(|e| e.to_string())?;
    Ok((
        film,
        format!(
            "path tracer, {} spp, rendered in {seconds:.1} s and cached as {}",
            settings.reference_samples,
            cache.display()
        ),
        seconds,
    ))
}

/// The runs grouped into curves: per engine and Accel, per budget the mean over seeds.
fn series_of(runs: &[Run]) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in runs {
        if !out
            .iter()
            .any(|s| s.engine == r.engine && s.accel == r.accel)
        {
            out.push(Series {
                engine: r.engine,
                accel: r.accel,
                points: Vec::new(),
                slope: None,
            });
        }
    }
    for s in &mut out {
        let mine: Vec<&Run> = runs
            .iter()
            .filter(|r| r.engine == s.engine && r.accel == s.accel)
            .collect();
        let mut budgets: Vec<u64> = mine.iter().map(|r| r.budget).collect();
        budgets.dedup();
        for b in budgets {
            let at: Vec<&&Run> = mine.iter().filter(|r| r.budget == b).collect();
            let n = at.len() as f64;
            let mean = |f: &dyn Fn(&Run) -> f64| at.iter().map(|r| f(r)).sum::<f64>() / n;
            s.points.push((
                b,
                at.iter().map(|r| r.seconds).fold(f64::INFINITY, f64::min),
                mean(&|r| r.metrics.relmse),
                mean(&|r| r.metrics.rmse),
            ));
        }
        s.slope = log_log_slope(&s.points.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>());
    }
    out
}

/// Least-squares slope of ln y against ln x over the points with both positive.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let (mx, my) = (
        logs.iter().map(|p| p.0).sum::<f64>() / n,
        logs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Per engine, the runs that both Accels made (same budget and seed): their images compared
/// pixel by pixel, and their times.
fn compare_accels(runs: &[Run], films: &[Film]) -> Vec<AccelComparison> {
    let mut engines: Vec<EngineKind> = Vec::new();
    for r in runs {
        if !engines.contains(&r.engine) {
            engines.push(r.engine);
        }
    }
    let mut out = Vec::new();
    for engine in engines {
        let mut c = AccelComparison {
            engine,
            pairs: 0,
            differing_pixels: 0,
            total_pixels: 0,
            max_difference: 0.0,
            bvh_over_embree: 0.0,
        };
        let (mut embree_s, mut bvh_s) = (0.0, 0.0);
        for (i, e) in runs.iter().enumerate() {
            if e.engine != engine || e.accel != AccelKind::Embree {
                continue;
            }
            let Some(j) = runs.iter().position(|b| {
                b.engine == engine
                    && b.accel == AccelKind::Bvh
                    && b.budget == e.budget
                    && b.seed == e.seed
            }) else {
                continue;
            };
            c.pairs += 1;
            embree_s += e.seconds;
            bvh_s += runs[j].seconds;
            for (a, b) in films[i].pixels.iter().zip(&films[j].pixels) {
                let d = (*a - *b).abs().max_element();
                c.total_pixels += 1;
                if d > 0.0 {
                    c.differing_pixels += 1;
                }
                c.max_difference = c.max_difference.max(d);
            }
        }
        if c.pairs > 0 {
            c.bvh_over_embree = bvh_s / embree_s;
            out.push(c);
        }
    }
    out
}

/// Writes `report.csv`, `report.md` and `report.png` (each atomically).
fn write_report(report: &Report, settings: &ReportSettings) -> Result<(), String> {
    let dir = &settings.output;
    let mut csv = String::from("engine,accel,budget_kind,budget,seed,seconds,relmse,rmse,mape\n");
    for r in &report.runs {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.6},{:.6e},{:.6e},{:.6e}",
            r.engine.name(),
            r.accel,
            r.budget_kind,
            r.budget,
            r.seed,
            r.seconds,
            r.metrics.relmse,
            r.metrics.rmse,
            r.metrics.mape
        );
    }
    write_text_atomically(&dir.join("report.csv"), &csv).map_err(|e| e.to_string())?;
    write_text_atomically(&dir.join("report.md"), &summary(report, settings))
        .map_err(|e| e.to_string())?;
    plot::write(&dir.join("report.png"), report)
}

/// The markdown summary: per curve its last point and slope, per engine the Accel comparison.
pub fn summary(report: &Report, settings: &ReportSettings) -> String {
    let mut md = String::new();
    let name = report
        .scene
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let _ = writeln!(md, "# trilux report: {name}\n");
    let _ = writeln!(
        md,
        "{}×{} pixels, {} seed(s) per budget, time limit {:.0} s, used {:.0} s. Reference: {}.\n",
        settings.width,
        settings.height,
        settings.seeds,
        settings.time_limit,
        report.total_seconds,
        report.reference
    );
    let _ = writeln!(
        md,
        "| engine | accel | budgets | largest budget | its time (s) | its relMSE | its RMSE | slope of relMSE vs time |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for s in &report.series {
        let Some(last) = s.points.last() else {
            continue;
        };
        let kind = report
            .runs
            .iter()
            .find(|r| r.engine == s.engine)
            .map_or("", |r| r.budget_kind);
        let slope = s.slope.map_or("–".to_string(), |v| format!("{v:.2}"));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {kind} {} | {:.3} | {:.3e} | {:.3e} | {slope} |",
            s.engine.name(),
            s.accel,
            s.points.len(),
            last.0,
            last.1,
            last.2,
            last.3
        );
    }
    equal_time(&mut md, &report.series);
    if !report.comparisons.is_empty() {
        let _ = writeln!(
            md,
            "\n## Embree against the BVH (same budgets, same seeds)\n"
        );
        let _ = writeln!(
            md,
            "| engine | runs compared | pixels that differ | largest difference | BVH time / Embree time |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|");
        for c in &report.comparisons {
            let _ = writeln!(
                md,
                "| {} | {} | {} of {} | {:.3e} | {:.2} |",
                c.engine.name(),
                c.pairs,
                c.differing_pixels,
                c.total_pixels,
                c.max_difference,
                c.bvh_over_embree
            );
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the curve relMSE = 1/t (a Monte Carlo estimator's), read between points a factor 4
    /// apart: log-log interpolation is exact on it.
    #[test]
    fn equal_time_readings_are_exact_on_a_power_law() {
        let curve = [(1.0, 1.0), (4.0, 0.25), (16.0, 0.0625)];
        for t in [1.0, 2.0, 3.0, 8.0, 16.0] {
            let e = log_log_at(&curve, t).expect("inside the curve");
            assert!((e * t - 1.0).abs() < 1e-12, "{t}: {e}");
        }
        assert_eq!(log_log_at(&curve, 0.5), None);
        assert_eq!(log_log_at(&curve, 17.0), None);
        for e in [0.5, 0.1, 0.0625] {
            let t = time_to(&curve, e).expect("reached");
            assert!((e * t - 1.0).abs() < 1e-12, "{e}: {t}");
        }
        assert_eq!(time_to(&curve, 0.01), None);
        // A curve that rises before it falls is read at its first crossing.
        assert_eq!(
            time_to(&[(1.0, 0.2), (2.0, 0.4), (4.0, 0.1)], 0.1),
            Some(4.0)
        );
    }
}
