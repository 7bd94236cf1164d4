//! Hostile scene files: seeded mutants of every scene of `scenes/` and, when `../shared` is
//! there, of the course's and the MGF scenes (bytes flipped or cut, lines doubled, numbers
//! swapped for nan, inf, 1e38 or 2^64). Each mutant is loaded, and each that loads is rendered
//! at 8×8 by every engine with both Accels, each render in a child process (the built `render`)
//! under a time limit and an address-space limit, so that a panic, an abort, a runaway
//! allocation or a render without end is caught and reported with the mutant that caused it,
//! not suffered by the test.
//!
//! `TRILUX_FUZZ_CASES` sets the number of mutants (default `CASES`), `TRILUX_FUZZ_SEED` the
//! seed (default fixed), `TRILUX_FUZZ_ADDRESS_SPACE` each render's address-space limit in
//! bytes (default 4 GiB). The summary counts panics, aborts, failed allocations and renders
//! killed; failing mutants are kept, and their paths printed. Without `../shared` its scenes
//! are skipped (failed instead when `TRILUX_REQUIRE_SHARED` is set).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// Mutants CI makes (`TRILUX_FUZZ_CASES` sets more).
const CASES: usize = 1000;

/// The engines every mutant that loads is rendered by.
const ENGINES: [&str; 5] = ["raytrace", "path", "radiosity", "photon", "sppm"];

/// A render past this is a runaway: every engine's defaults finish an 8×8 image of these
/// scenes in a few seconds.
const KILL_AFTER_S: u32 = 20;

/// The address space a render may take (`TRILUX_FUZZ_ADDRESS_SPACE` bytes, default 4 GiB): a
/// runaway allocation fails under it instead of taking the machine's memory.
fn address_space() -> u64 {
    env_or("TRILUX_FUZZ_ADDRESS_SPACE", 4 << 30)
}

/// The environment variable `name` as a number, or `default`.
fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// SplitMix64: a small seeded generator, the same on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// What a number is swapped for.
const HOSTILE_NUMBERS: [&str; 8] = [
    "nan",
    "inf",
    "-inf",
    "1e38",
    "-1e38",
    "18446744073709551616",
    "0",
    "1e-38",
];

/// One to three mutations of `text`: a byte flipped, the text cut, a line doubled or removed,
/// a number swapped for a hostile one.
fn mutate(text: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut bytes = text.to_vec();
    for _ in 0..1 + rng.below(3) {
        match rng.below(6) {
            0 if !bytes.is_empty() => {
                let at = rng.below(bytes.len());
                bytes[at] ^= 1 << rng.below(8);
            }
            1 if !bytes.is_empty() => {
                let at = rng.below(bytes.len());
                bytes.truncate(at);
            }
            2 | 3 => {
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let mut lines: Vec<&str> = text.lines().collect();
                if lines.is_empty() {
                    continue;
                }
                let k = rng.below(lines.len());
                if rng.below(4) == 0 {
                    lines.remove(k);
                } else {
                    lines.insert(k, lines[k]);
                }
                bytes = (lines.join("\n") + "\n").into_bytes();
            }
            _ => {
                // Numbers: runs of digits, signs, dots and exponents between separators.
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let numbers: Vec<(usize, usize)> = words(&text)
                    .filter(|&(a, b)| text[a..b].parse::<f64>().is_ok())
                    .collect();
                if numbers.is_empty() {
                    continue;
                }
                let (a, b) = numbers[rng.below(numbers.len())];
                let with = HOSTILE_NUMBERS[rng.below(HOSTILE_NUMBERS.len())];
                bytes = format!("{}{with}{}", &text[..a], &text[b..]).into_bytes();
            }
        }
    }
    bytes
}

/// The byte ranges of the whitespace-separated words of `text`.
fn words(text: &str) -> impl Iterator<Item = (usize, usize)> + '_ {
    let mut start = None;
    text.char_indices()
        .chain(std::iter::once((text.len(), ' ')))
        .filter_map(move |(i, c)| {
            if c.is_whitespace() {
                start.take().map(|s| (s, i))
            } else {
                start.get_or_insert(i);
                None
            }
        })
}

/// The scene files to mutate: `scenes/`'s, and the shared course and MGF scenes when present.
fn inputs() -> Vec<PathBuf> {
    let mut files = common::own_scenes();
    files.extend(
        std::fs::read_dir(common::own_scene_dir())
            .expect("scenes/")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mgf")),
    );
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared");
    let required = std::env::var_os("TRILUX_REQUIRE_SHARED").is_some();
    for (dir, ext) in [("course-scenes", "obj"), ("mgf-scenes", "mgf")] {
        let dir = shared.join(dir);
        if !dir.is_dir() {
            assert!(
                !required,
                "{} not found (TRILUX_REQUIRE_SHARED is set)",
                dir.display()
            );
            eprintln!("fuzz: {} not found: its scenes are skipped", dir.display());
            continue;
        }
        let mut found = Vec::new();
        collect(&dir, ext, &mut found);
        files.extend(found);
    }
    files.sort();
    files.dedup();
    files
}

fn collect(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, ext, out);
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
}

/// A folder that looks like `original`'s (every entry linked), for the mutant to sit in, so
/// that its includes, materials and textures are found as the original's are.
fn beside(original: &Path, work: &Path, case: usize) -> PathBuf {
    let dir = work.join(format!("case{case}"));
    std::fs::create_dir_all(&dir).expect("case folder");
    let from = original.parent().expect("a folder");
    for entry in std::fs::read_dir(from).into_iter().flatten().flatten() {
        let to = dir.join(entry.file_name());
        if !to.exists() {
            let _ = std::os::unix::fs::symlink(entry.path(), &to);
        }
    }
    let name = original.file_name().expect("a name").to_string_lossy();
    dir.join(format!("mutant-{name}"))
}

/// What went wrong with one mutant.
struct Failure {
    mutant: PathBuf,
    what: String,
}

/// Runs `render ARGS` in a child process under the time and address-space limits: Ok(true)
/// when it exits 0, Ok(false) when it exits 1 (a clear error), else what went wrong.
fn run_limited(args: &[&std::ffi::OsStr]) -> Result<bool, String> {
    let out = Command::new("timeout")
        .args(["-s", "KILL", &KILL_AFTER_S.to_string(), "prlimit"])
        .arg(format!("--as={}", address_space()))
        .arg(env!("CARGO_BIN_EXE_render"))
        .args(args)
        .output()
        .expect("timeout, prlimit and render run");
    let err = String::from_utf8_lossy(&out.stderr);
    let tail: String = err.lines().rev().take(4).collect::<Vec<_>>().join(" | ");
    use std::os::unix::process::ExitStatusExt;
    // `timeout -s KILL` dies by the signal it sends, as the render does by its abort.
    let status = match (out.status.code(), out.status.signal()) {
        (Some(code), _) => Some(code),
        (None, Some(signal)) => Some(128 + signal),
        (None, None) => None,
    };
    match status {
        _ if err.contains("panicked") => Err(format!("{PANIC}: {tail}")),
        _ if err.contains("memory allocation of") => Err(format!("{ALLOCATION}: {tail}")),
        Some(0) => Ok(true),
        Some(1) => Ok(false),
        Some(137) => Err(format!(
            "{KILLED} after {KILL_AFTER_S} s, or by the kernel: {tail}"
        )),
        Some(134) => Err(format!("{ABORT}: {tail}")),
        code => Err(format!("status {code:?}: {tail}")),
    }
}

/// The original a mutant was made from: its namesake in the folder its links point into.
fn original_of(mutant: &Path) -> PathBuf {
    let name = mutant.file_name().expect("a name").to_string_lossy();
    let name = name.strip_prefix("mutant-").expect("a mutant's name");
    let dir = mutant.parent().expect("a folder");
    std::fs::read_link(dir.join(name)).expect("the original linked beside the mutant")
}

/// The classes of failure, as the report counts them.
const PANIC: &str = "a panic";
const ALLOCATION: &str = "a failed allocation";
const KILLED: &str = "killed";
const ABORT: &str = "an abort";

/// Whether `mutant` loads (`render --plan` exits 0), in a child process: a loader that
/// panics or allocates without bound is caught there too.
fn loads(mutant: &Path) -> Result<bool, String> {
    let input = mutant.as_os_str();
    run_limited(&["--input".as_ref(), input, "--plan".as_ref()])
        .map_err(|e| format!("loading: {e}"))
}

/// Whether the radiosity engine renders `mutant`: at most `RADIOSITY_PRIMITIVES` primitives,
/// unless `TRILUX_FUZZ_ALL_RADIOSITY` is set. Radiosity on the large MGF scenes takes 15–40 s
/// at 8×8 unmutated (hierarchical refinement of millions of links, whether or not anything
/// emits), which a CI run cannot spend on each.
fn radiosity_renders(mutant: &Path) -> bool {
    if std::env::var_os("TRILUX_FUZZ_ALL_RADIOSITY").is_some() {
        return true;
    }
    match trilux::scene::Scene::load(mutant) {
        Ok(scene) => scene.primitive_count() <= RADIOSITY_PRIMITIVES,
        Err(_) => false,
    }
}

/// The most primitives a mutant may have for the radiosity engine to render it in CI.
const RADIOSITY_PRIMITIVES: usize = 2_000;

/// Renders `mutant` at 8×8 with `engine` and `accel` in a child process.
fn render(mutant: &Path, engine: &str, accel: &str) -> Result<(), String> {
    let output = mutant.with_extension(format!("{engine}-{accel}.pfm"));
    let mut args: Vec<&std::ffi::OsStr> = vec!["--input".as_ref(), mutant.as_os_str()];
    for a in [
        "--engine",
        engine,
        "--accel",
        accel,
        "--size",
        "8",
        "8",
        "--threads",
        "1",
        "--quiet",
        "-o",
    ] {
        args.push(a.as_ref());
    }
    args.push(output.as_os_str());
    let result = run_limited(&args);
    let _ = std::fs::remove_file(&output);
    result
        .map(|_| ())
        .map_err(|e| format!("{engine} --accel {accel}: {e}"))
}

#[test]
fn hostile_scene_files_never_panic_abort_or_run_away() {
    let cases = env_or("TRILUX_FUZZ_CASES", CASES as u64) as usize;
    let seed = env_or("TRILUX_FUZZ_SEED", 0x5eed_f022);
    let inputs = inputs();
    let work = common::temp_dir("fuzz");
    let mut rng = Rng(seed);
    let start = std::time::Instant::now();
    // Mutants made and loaded in this thread, in order (each from its own generator state, so
    // a case does not depend on the others' timing); renders in parallel.
    let mut loaded = Vec::new();
    let mut failures = Vec::new();
    for case in 0..cases {
        let original = &inputs[case % inputs.len()];
        let text = std::fs::read(original).expect("scene read");
        let mut case_rng = Rng(rng.next());
        let mutant = beside(original, &work, case);
        std::fs::write(&mutant, mutate(&text, &mut case_rng)).expect("mutant written");
        let began = std::time::Instant::now();
        let result = loads(&mutant);
        let took = began.elapsed().as_secs_f64();
        if took > 2.0 {
            println!(
                "fuzz: slow to load: {} ({}): {took:.1} s",
                mutant.display(),
                original.display()
            );
        }
        match result {
            Ok(true) => loaded.push(mutant),
            Ok(false) => {}
            Err(what) => failures.push(Failure { mutant, what }),
        }
    }
    let jobs: Vec<(PathBuf, &str, String)> = loaded
        .iter()
        .flat_map(|m| {
            let radiosity = radiosity_renders(m);
            ENGINES
                .iter()
                .filter(move |e| **e != "radiosity" || radiosity)
                .flat_map(move |e| {
                    common::backends()
                        .into_iter()
                        .map(move |k| (m.clone(), *e, k.to_string()))
                })
        })
        .collect();
    let next = Mutex::new(0usize);
    let found = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let k = {
                    let mut n = next.lock().expect("queue");
                    *n += 1;
                    *n - 1
                };
                let Some((mutant, engine, accel)) = jobs.get(k) else {
                    break;
                };
                let began = std::time::Instant::now();
                let result = render(mutant, engine, accel);
                let took = began.elapsed().as_secs_f64();
                if took > 5.0 {
                    println!(
                        "fuzz: slow: {} {engine} {accel}: {took:.1} s",
                        mutant.display()
                    );
                }
                // A mutant as slow as its original is not a runaway: some valid scenes take
                // long for other reasons (a hospital's radiosity at 8×8 takes 40 s).
                let slow_original = |what: &String| {
                    what.contains(KILLED) && {
                        let original = original_of(mutant);
                        render(&original, engine, accel).is_err_and(|e| e.contains(KILLED))
                    }
                };
                match result {
                    Err(what) if slow_original(&what) => {
                        println!(
                            "fuzz: {}: {what}, as its original: not counted",
                            mutant.display()
                        );
                    }
                    Err(what) => found.lock().expect("failures").push(Failure {
                        mutant: mutant.clone(),
                        what,
                    }),
                    Ok(()) => {}
                }
            });
        }
    });
    failures.extend(found.into_inner().expect("failures"));
    println!(
        "fuzz: seed {seed:#x}, {cases} mutants of {} scenes, {} loaded, {} renders in {:.1} s, {} failures",
        inputs.len(),
        loaded.len(),
        jobs.len(),
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    for f in &failures {
        println!("  {}: {}", f.mutant.display(), f.what);
    }
    let count = |class: &str| failures.iter().filter(|f| f.what.contains(class)).count();
    println!(
        "fuzz: {} panics, {} aborts, {} failed allocations, {} killed (past {KILL_AFTER_S} s or by the kernel)",
        count(PANIC),
        count(ABORT),
        count(ALLOCATION),
        count(KILLED)
    );
    assert!(
        failures.is_empty(),
        "{} mutants panicked, aborted or ran away (kept in {})",
        failures.len(),
        work.display()
    );
    std::fs::remove_dir_all(&work).ok();
}
