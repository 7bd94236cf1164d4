//! The render command: checks the flags, loads the scene, plans, builds the Accel, runs the
//! engine, writes the image (and the ray tree, the convergence log), reports.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering::Relaxed;
use std::time::Instant;

use super::{emit, RenderArgs};
use crate::accel::{self, Accel};
use crate::engines::{self, raytrace, EngineKind, RenderSettings, Rendered};
use crate::film::Film;
use crate::plan::Plan;
use crate::scene::{RenderHints, Scene};

/// `render -input SCENE …`.
pub fn run(args: &RenderArgs) -> Result<(), String> {
    let input = args.common.input.as_ref().ok_or("missing -input")?;
    let mut settings = checked_settings(args)?;
    let pool = crate::parallel::thread_pool(args.common.threads).map_err(|e| e.to_string())?;
    crate::parallel::worker_start();

    let load_start = Instant::now();
    settings.deadline = args
        .common
        .time_limit
        .map(|t| load_start + std::time::Duration::from_secs_f64(t));
    let engine = args.engine();
    let mut scene = load_scene(args, input, engine)?;
    let from_scene = apply_scene_hints(args, &mut scene, &mut settings);
    let threads = pool.current_num_threads();
    if let Some(flag) = args.choose_volume_steps(&scene, threads, &mut settings) {
        if !settings.quiet {
            eprintln!("--time-limit: in the fog, chose {flag}");
        }
    }
    let load_s = load_start.elapsed().as_secs_f64();
    let kind = args.accel_kind(&scene);
    let plan = Plan::new(&scene, engine, kind, &settings);
    let unused = args.unused_flags();
    if args.common.plan {
        let (_, limit) = memory_limit(args);
        let mut notes: String = unused
            .iter()
            .map(|f| format!("note: {f} is ignored: the {engine} engine does not read it\n"))
            .collect();
        // What this engine reads of what the scene file chose.
        let chosen: Vec<&str> = from_scene
            .iter()
            .filter(|(id, _)| args.reads_flag(engine, id))
            .map(|(_, flag)| flag.as_str())
            .collect();
        if !chosen.is_empty() {
            notes += &format!(
                "note: the scene file chooses {} (flags given win)\n",
                chosen.join(", ")
            );
        }
        if let Some(note) = unfollowed_depth(args, engine, &from_scene) {
            notes += &format!("note: {note}\n");
        }
        if args.common.accel.is_none() {
            notes += &format!(
                "note: accel {kind} is the default for the {engine} engine on a scene of {} primitives (the BVH for radiosity and up to {} primitives, Embree above when built in); --accel chooses\n",
                scene.primitive_count(),
                accel::BVH_UP_TO_PRIMITIVES
            );
        }
        return emit(&format!(
            "scene: {}\n{plan}memory limit: {limit}\n{notes}",
            input.display()
        ));
    }
    // What the plan leaves of --max-memory bounds what the hierarchical solver refines.
    settings.radiosity.memory_budget = check_memory(&plan, args)?;
    let engine_impl = engines::engine(engine);
    if settings.pixel_samples.is_some() && !engine_impl.samples_pixels(&settings) {
        return Err(format!(
            "--pixel-samples: the {engine} engine's image{} is not a mean of pixel samples, so its samples cannot be split; split it into tiles with --crop-window instead",
            match engine {
                EngineKind::Raycast => "",
                _ => " with these display flags",
            }
        ));
    }
    if args.common.variance.is_some() && !engine_impl.samples_pixels(&settings) {
        return Err(format!(
            "--variance: the {engine} engine's image{} is not a mean of pixel samples, so it has no variance of samples",
            match engine {
                EngineKind::Raycast | EngineKind::Sppm => "",
                _ => " with these display flags",
            }
        ));
    }
    if args.part.pre_pass_only {
        match engine_impl.pre_pass(&settings) {
            None => {
                return Err(format!(
                    "--pre-pass-only: the {engine} engine has no pre-pass{}",
                    if engine == EngineKind::Raytrace {
                        " (only with --indirect radiosity)"
                    } else {
                        ""
                    }
                ))
            }
            Some(p) if !p.saved => {
                return Err(format!(
                    "--pre-pass-only: give {} FILE to keep the {} it computes",
                    p.save_flag, p.name
                ))
            }
            Some(_) => {}
        }
    }
    crate::interrupt::install();
    if let Some(note) = unfollowed_depth(args, engine, &from_scene) {
        eprintln!("note: {note}");
    }
    for flag in unused {
        eprintln!(
            "note: {flag} is accepted but has no effect: the {engine} engine does not read it"
        );
    }

    let build_start = Instant::now();
    let accel = pool
        .install(|| accel::build(&scene, kind, &args.accel_options()))
        .map_err(|e| e.to_string())?;
    let build_s = build_start.elapsed().as_secs_f64();
    let render_start = Instant::now();
    let accel = accel.as_ref();
    if args.part.pre_pass_only {
        let summary = pool.install(|| engine_impl.run_pre_pass(&scene, accel, &settings))?;
        if !settings.quiet {
            summary.iter().for_each(|line| eprintln!("{line}"));
        }
        if crate::interrupt::requested() {
            return Err("interrupted: the pre-pass was cut short and nothing was saved".into());
        }
        return Ok(());
    }
    let rendered = pool.install(|| engines::render(engine, &scene, accel, &settings))?;
    let render_s = render_start.elapsed().as_secs_f64();
    report(&rendered, &settings);
    if let (Some(path), Some(csv)) = (&args.radiosity.log_convergence, &rendered.convergence_log) {
        crate::output::write_text_atomically(path, csv).map_err(|e| e.to_string())?;
    }
    let Rendered {
        film,
        stats,
        counters,
        ..
    } = rendered;
    let output = args
        .common
        .output
        .clone()
        .unwrap_or_else(|| default_output(input));
    let interrupted = crate::interrupt::requested();
    write_image(&film, &scene, &settings, &output, !interrupted)?;
    if let Some(path) = &args.common.variance {
        write_variance(&film, path)?;
    }
    if interrupted {
        return Err(format!(
            "interrupted: wrote the image rendered so far to {}{}",
            output.display(),
            if settings.window.is_some() || settings.pixel_samples.is_some() {
                " (marked incomplete: render merge will not take it)"
            } else {
                ""
            }
        ));
    }
    if let Some(xy) = &args.ray_trace.ray_tree {
        write_ray_tree(&scene, accel, &settings, &film, &output, (xy[0], xy[1]))?;
    }
    if args.common.stats {
        let rays = stats.total_rays();
        let non_finite = stats.non_finite_samples.load(Relaxed);
        eprintln!("stats: scene load {load_s:.3} s, accel build ({kind}) {build_s:.3} s, render {render_s:.3} s");
        eprintln!(
            "stats: rays cast {rays} ({:.2} Mrays/s): camera {}, shadow {}, secondary {}, form factor {}, photon {}",
            rays as f64 / render_s / 1e6,
            stats.camera_rays.load(Relaxed),
            stats.shadow_rays.load(Relaxed),
            stats.secondary_rays.load(Relaxed),
            stats.form_factor_rays.load(Relaxed),
            stats.photon_rays.load(Relaxed)
        );
        eprintln!("stats: non-finite samples {non_finite}");
        if let Some((label, counters)) = &counters {
            let named: Vec<String> = counters.iter().map(|(n, c)| format!("{n} {c}")).collect();
            eprintln!("stats: {label}: {}", named.join(", "));
        }
        if let Some(kib) = peak_memory_kib() {
            eprintln!("stats: peak memory {:.1} MiB", kib as f64 / 1024.0);
        }
    }
    if !args.common.quiet {
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}

/// The settings of the flags, checked; with `--time-limit`, what it chose where flags were
/// not given (said on stderr unless `--quiet`). The viewer starts here too.
pub fn checked_settings(args: &RenderArgs) -> Result<RenderSettings, String> {
    args.validate()?;
    let mut settings = args.settings();
    let chosen = args.choose_for_time_limit(&mut settings);
    if !chosen.is_empty() && !args.common.quiet {
        eprintln!(
            "--time-limit: for the quality flags not given, chose {}",
            chosen.join(" ")
        );
    }
    let p = &settings.photon;
    if args.engine() == EngineKind::Photon && p.load.is_none() && settings.photons() == 0 {
        eprintln!(
            "warning: -num_photons_to_shoot 0: no photon map, so no indirect light but --ambient-light"
        );
    }
    Ok(settings)
}

/// What the scene file asks of the render (a Mitsuba scene's film size, samples per pixel,
/// path depth, lens, shadow rays, radiosity solver and no ambient light; an MGF scene's
/// reflection depth, shadow rays and radiosity solver), where the command line did not give
/// its own: the flags win. Returns the settings taken, each its flag's id and as a user would
/// type it, for `--plan` to say.
pub fn apply_scene_hints(
    args: &RenderArgs,
    scene: &mut Scene,
    settings: &mut RenderSettings,
) -> Vec<(&'static str, String)> {
    let given = |id: &str| args.flag_given(id);
    let hints = scene.render_hints.clone();
    let mut taken = Vec::new();
    if let (Some((w, h)), false) = (hints.size, given("size")) {
        settings.width = w;
        settings.height = h;
        settings.window = args.part.window(w, h);
        scene.filter_textures_for(w, h);
        taken.push(("size", format!("-size {w} {h}")));
    }
    if let (Some(n), false) = (hints.samples, given("num_antialias_samples")) {
        settings.num_antialias_samples = n;
        taken.push((
            "num_antialias_samples",
            format!("-num_antialias_samples {n}"),
        ));
    }
    if let (Some(n), false) = (hints.num_bounces, given("num_bounces")) {
        settings.num_bounces = n;
        taken.push(("num_bounces", format!("-num_bounces {n}")));
    }
    // A time limit chooses its own shadow rays (`RenderArgs::choose_for_time_limit`).
    let time_limited = args.common.time_limit.is_some();
    if let (Some(n), false) = (
        hints.num_shadow_samples,
        given("num_shadow_samples") || time_limited,
    ) {
        settings.num_shadow_samples = n;
        taken.push(("num_shadow_samples", format!("-num_shadow_samples {n}")));
    }
    if let (Some(a), false) = (hints.ambient_light, given("ambient_light")) {
        settings.ambient_light = a;
        taken.push((
            "ambient_light",
            format!("-ambient_light {} {} {}", a.x, a.y, a.z),
        ));
    }
    if hints.hierarchical_radiosity && !given("radiosity_solver") {
        settings.radiosity.solver = crate::engines::radiosity::SolverKind::Hierarchical;
        taken.push((
            "radiosity_solver",
            "--radiosity-solver hierarchical".to_string(),
        ));
    }
    if let (Some(depth), false) = (hints.max_depth, given("max_depth")) {
        settings.max_depth = Some(depth);
        taken.push(("max_depth", format!("--max-depth {depth}")));
    }
    engine_defaults(args, &hints, args.engine(), settings);
    if let Some((radius, focus)) = hints.lens {
        if !given("aperture") {
            settings.aperture = radius;
            taken.push(("aperture", format!("--aperture {radius}")));
        }
        if !given("focus_distance") && focus > 0.0 {
            settings.focus_distance = Some(focus);
            taken.push(("focus_distance", format!("--focus-distance {focus}")));
        }
    }
    taken
}

/// `-num_shadow_samples` and `-num_bounces` as `engine` takes them where neither the command
/// line, `--time-limit` nor the scene file (`hints`) chose them: its own defaults
/// (`EngineKind::default_shadow_samples`, `default_num_bounces`) over the course's. `render`
/// takes its engine's; the viewer each job's, whose offline command names the job's engine.
pub fn engine_defaults(
    args: &RenderArgs,
    hints: &RenderHints,
    engine: EngineKind,
    settings: &mut RenderSettings,
) {
    let given = |id: &str| args.flag_given(id);
    if !given("num_shadow_samples")
        && args.common.time_limit.is_none()
        && hints.num_shadow_samples.is_none()
    {
        settings.num_shadow_samples = engine.default_shadow_samples(settings.indirect);
    }
    if !given("num_bounces") && hints.num_bounces.is_none() {
        settings.num_bounces = engine.default_num_bounces();
    }
}

/// What to tell of a depth the scene file chose (Mitsuba's `max_depth`) that `engine` does
/// not follow: the photon engine, SPPM and radiosity carry the light over every bounce, so
/// their image of a scene limited to direct light has the indirect light too (10% of the
/// mean of a test scene lit by point, spot and directional lights).
fn unfollowed_depth(
    args: &RenderArgs,
    engine: EngineKind,
    from_scene: &[(&'static str, String)],
) -> Option<String> {
    let every_bounce = matches!(
        engine,
        EngineKind::Photon | EngineKind::Sppm | EngineKind::Radiosity
    );
    let (_, flag) = from_scene.iter().find(|(id, _)| *id == "max_depth")?;
    (every_bounce && !args.reads_flag(engine, "max_depth")).then(|| {
        format!(
            "the scene file limits the path tracer's depth ({flag}); the {engine} engine carries the light over every bounce (--engine path follows the limit)"
        )
    })
}

/// The scene as `render` reads it: loaded (its warnings printed), `--two-sided` and the
/// camera flags applied; refused if it has nothing to render or holds what `engine` would
/// leave out. The viewer loads its scene here too.
pub fn load_scene(args: &RenderArgs, input: &Path, engine: EngineKind) -> Result<Scene, String> {
    let mut scene = Scene::load_with(input, &args.common.define).map_err(|e| e.to_string())?;
    scene.two_sided_quads = args.common.two_sided;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    // What this engine approximates of the scene's Mitsuba BSDFs, once for each plugin in the
    // file (materials share plugins).
    let mut approximations: Vec<String> = Vec::new();
    for plugin in scene.mitsuba_bsdfs.values().flat_map(|b| &b.plugins) {
        if let Some(w) = plugin.warning(engine.name(), engine == EngineKind::Path) {
            if !approximations.contains(&w) {
                eprintln!("warning: {w}");
                approximations.push(w);
            }
        }
    }
    if args.camera.overrides() {
        let camera = args.camera(scene.camera())?;
        crate::scene::range::check_camera(&camera).map_err(|e| format!("the camera flags: {e}"))?;
        scene.camera = Some(camera);
    }
    scene.filter_textures_for(args.common.size[0], args.common.size[1]);
    if scene.primitive_count() == 0 {
        return Err(format!(
            "{}: the scene has no geometry (no quads, triangles, spheres or rings): nothing to render",
            input.display()
        ));
    }
    refuse_unrendered_media(args, input, engine, &scene)?;
    // Not an error: a component file (a chair, a desk) is a scene worth looking at, but
    // every engine's image of it is black or the background, which a user should be told once.
    if !scene.emits_light() {
        eprintln!(
            "warning: {}: nothing in the scene emits light (no emitting surface, no sky, no point, spot or directional light): the image shows only the background (and the ray tracer's --ambient-light)",
            input.display()
        );
    }
    Ok(scene)
}

/// What an engine does not render yet is refused, not left out: lights without area are
/// the path tracer's, the ray tracer's, the photon engine's, SPPM's and radiosity's (not in a
/// fog, whose single scattering the ray tracer takes from lights with area only and which
/// radiosity's light from outside the patches does not cross; not with radiosity as the ray
/// tracer's indirect light, whose solution would count the light they bring as direct); media (fog, a
/// material's `interior_medium`) and skies are the path tracer's, the ray tracer's (not with
/// radiosity as its indirect light, whose solution leaves them out) and the photon engine's
/// (final gathering included: its gather rays cross the media); radiosity takes a sky and a
/// fog, not a medium inside glass (behind a specular boundary its form factors do not cross);
/// SPPM takes a sky, not media (its visible points are on surfaces only). A heterogeneous
/// medium, a medium around the camera other than the fog and a shape's exterior medium are
/// the path tracer's alone.
fn refuse_unrendered_media(
    args: &RenderArgs,
    input: &Path,
    engine: EngineKind,
    scene: &Scene,
) -> Result<(), String> {
    let path_tracer = matches!(engine, EngineKind::Path | EngineKind::Raycast);
    let ray_traced = matches!(
        engine,
        EngineKind::Raytrace | EngineKind::Photon | EngineKind::Sppm
    ) && scene.fog.is_none()
        && args.ray_trace.indirect != engines::IndirectKind::Radiosity;
    let radiosity = engine == EngineKind::Radiosity && scene.fog.is_none();
    if !scene.delta_lights.is_empty() && !path_tracer && !ray_traced && !radiosity {
        return Err(format!(
            "{}: the scene has lights without area (Mitsuba's point, spot or directional lights), which the path tracer renders (--engine path), and the ray tracer, the photon engine, SPPM and radiosity outside a fog and without --indirect radiosity; the {engine} engine would leave them out",
            input.display()
        ));
    }
    // Media only the path tracer follows: the first, by its line, and what it is.
    let heterogeneous = scene
        .media
        .iter()
        .position(|m| m.heterogeneous.is_some())
        .map(|k| (k, "a heterogeneous medium (Mitsuba's heterogeneous)"));
    let beyond_fog = scene
        .camera_medium
        .into_iter()
        .chain(scene.materials.iter().filter_map(|m| m.exterior_medium))
        .next()
        .map(|k| (k, "a medium around the camera or outside a shape (Mitsuba's sensor medium or a shape's exterior)"));
    if let (Some((k, what)), false) = (heterogeneous.or(beyond_fog), path_tracer) {
        return Err(format!(
            "{}:{}: the scene has {what}, which only the path tracer renders so far (--engine path); the {engine} engine would leave it out",
            input.display(),
            scene.media[k].line
        ));
    }
    let radiosity_indirect = args.ray_trace.indirect == engines::IndirectKind::Radiosity;
    let (media, sky) = (scene.has_media(), scene.sky.is_some());
    let refused = match engine {
        EngineKind::Path | EngineKind::Raycast => None,
        EngineKind::Raytrace if radiosity_indirect && (media || sky) => {
            Some(" with --indirect radiosity")
        }
        EngineKind::Raytrace => None,
        EngineKind::Photon => None,
        EngineKind::Radiosity if media && !fog_only(scene) => Some(""),
        EngineKind::Radiosity => None,
        EngineKind::Sppm if media => Some(""),
        EngineKind::Sppm => None,
    };
    let Some(how) = refused else {
        return Ok(());
    };
    let what = if engine == EngineKind::Radiosity {
        "a medium inside glass (interior_medium)"
    } else if scene.fog.is_some() {
        "fog"
    } else if media {
        "a medium inside glass (interior_medium)"
    } else {
        "a sky"
    };
    Err(format!(
        "{}: the scene has {what}, which the path tracer, the ray tracer and the photon engine render so far (--engine path, raytrace without --indirect radiosity, photon; radiosity takes a sky and a fog, not a medium inside glass; sppm a sky); the {engine} engine{how} would leave it out",
        input.display(),
    ))
}

/// Whether the scene's only medium is its fog: what radiosity takes (a medium inside a glass
/// object is behind a specular boundary, which radiosity's form factors do not cross).
fn fog_only(scene: &Scene) -> bool {
    !scene.materials.iter().any(|m| m.interior_medium.is_some())
}

/// `--max-memory` in bytes (default: 80% of this machine's), and as the messages name it.
fn memory_limit(args: &RenderArgs) -> (u64, String) {
    let max_memory = args
        .common
        .max_memory
        .unwrap_or_else(crate::plan::default_max_memory);
    let limit = format!(
        "--max-memory {}{}",
        crate::bytes::human_bytes(max_memory),
        if args.common.max_memory.is_none() {
            " (80% of this machine's memory)"
        } else {
            ""
        }
    );
    (max_memory, limit)
}

/// Refuses a plan above `--max-memory`; returns what the limit leaves beside the plan (what
/// the hierarchical solver may refine into).
pub fn check_memory(plan: &Plan, args: &RenderArgs) -> Result<u64, String> {
    let (max_memory, limit) = memory_limit(args);
    if plan.memory > max_memory {
        return Err(format!(
            "this render would need about {}, more than {limit}; ask for less (-size, -num_photons_to_shoot, --subdivide) or raise --max-memory",
            plan.memory_summary(),
        ));
    }
    Ok(max_memory - plan.memory)
}

/// Writes the image. A part of a split render (`--crop-window`, `--pixel-samples`) written as
/// EXR is a part file for `render merge` (its sums, its window, its samples, the fingerprint
/// of scene and settings, and whether the render ran to its end); in another format, a window
/// is written alone.
fn write_image(
    film: &Film,
    scene: &Scene,
    settings: &RenderSettings,
    output: &Path,
    complete: bool,
) -> Result<(), String> {
    let image = settings.image();
    if !image.is_part() {
        return film.write(output).map_err(|e| e.to_string());
    }
    let window = image.window();
    if crate::film::ImageFormat::from_path(output) != Some(crate::film::ImageFormat::Exr) {
        return film
            .cropped(window)
            .write(output)
            .map_err(|e| e.to_string());
    }
    let sums = match &film.samples {
        Some(sums) => sums.clone(),
        None => crate::film::part::SampleSums::of_pixels(film, window),
    };
    let range = image.sample_range();
    let info = crate::film::part::PartInfo {
        width: settings.width,
        height: settings.height,
        samples: (range.start, range.end),
        spp: settings.num_antialias_samples.max(1),
        fingerprint: settings.fingerprint(scene),
        complete,
    };
    crate::film::part::write(output, film, &sums, &info).map_err(|e| e.to_string())
}

/// Writes the variance of each pixel's samples (`--variance`, `render merge --variance`)
/// from the sums the film kept.
pub fn write_variance(film: &Film, path: &Path) -> Result<(), String> {
    let sums = film.samples.as_ref().ok_or_else(|| {
        format!(
            "--variance {}: the render kept no sums of samples",
            path.display()
        )
    })?;
    sums.variance(film.width, film.height)
        .write(path)
        .map_err(|e| e.to_string())
}

/// What the engine had to say, and the samples that came out NaN or infinite.
fn report(rendered: &Rendered, settings: &RenderSettings) {
    for w in &rendered.warnings {
        eprintln!("warning: {w}");
    }
    if !settings.quiet {
        for line in &rendered.summary {
            eprintln!("{line}");
        }
        let reached = rendered.stats.samples_reached.load(Relaxed);
        if let (Some(deadline), true) = (settings.deadline, reached > 0) {
            let over = std::time::Instant::now().saturating_duration_since(deadline);
            eprintln!(
                "time limit: {reached} samples per pixel{}",
                if over.as_secs_f64() >= 0.005 {
                    format!(
                        " (the last pass ended {:.2} s past the limit)",
                        over.as_secs_f64()
                    )
                } else {
                    String::new()
                }
            );
        }
    }
    let non_finite = rendered.stats.non_finite_samples.load(Relaxed);
    if non_finite > 0 {
        eprintln!(
            "warning: {non_finite} samples were NaN or infinite and were left out of the image"
        );
    }
}

/// `<scene stem>.png` in the current folder.
fn default_output(input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map_or("render".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(format!("{stem}.png"))
}

/// Writes the ray tree of one pixel beside the image (`--ray-tree X Y`; the pixel was
/// checked to be inside the image before the render).
fn write_ray_tree(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    film: &Film,
    output: &Path,
    (x, y): (u32, u32),
) -> Result<(), String> {
    let segments = raytrace::ray_tree(scene, &scene.camera(), accel, settings, (x, y));
    let stem = output.with_extension("");
    let png = PathBuf::from(format!("{}.raytree.png", stem.display()));
    let obj = PathBuf::from(format!("{}.raytree.obj", stem.display()));
    crate::film::ray_tree::overlay(film, &scene.camera(), &segments)
        .write(&png)
        .map_err(|e| e.to_string())?;
    crate::film::ray_tree::write_obj(&segments, &obj).map_err(|e| e.to_string())?;
    if !settings.quiet {
        eprintln!(
            "wrote {} and {} ({} rays)",
            png.display(),
            obj.display(),
            segments.len()
        );
    }
    Ok(())
}

/// The process's peak resident memory (Linux: VmHWM of /proc/self/status), in KiB.
pub fn peak_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::super::flag_name;

    #[test]
    fn flag_names_are_spelled_as_the_user_types_them() {
        assert_eq!(flag_name("num_bounces"), "-num_bounces");
        assert_eq!(flag_name("max_photon_depth"), "--max-photon-depth");
    }
}
