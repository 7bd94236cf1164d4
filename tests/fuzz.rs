//! Hostile scene files: seeded mutants of every scene of `scenes/` and, when `../shared` is
//! there, of the course's, the MGF and Mitsuba 3's test scenes, of Mitsuba's PLY meshes and of
//! a small `serialized` mesh this test writes (bytes flipped or cut, lines doubled, numbers
//! swapped for nan, inf, 1e38 or 2^64). A Mitsuba scene's mutant sits in a copy of the tree
//! its relative paths climb (`../../../common`); a fragment it includes is mutated under its
//! own name there and rendered through a scene that reads it; a mesh's mutant through a small
//! scene that names it. Each mutant is loaded, and each that loads is rendered at 8×8 by every
//! engine with both Accels, each render in a child process (the built `render`) under a time
//! limit and an address-space limit, so that a panic, an abort, a runaway allocation or a
//! render without end is caught and reported with the mutant that caused it, not suffered by
//! the test.
//!
//! `TRILUX_FUZZ_CASES` sets the number of mutants (default `CASES`), `TRILUX_FUZZ_ONLY` the
//! inputs (comma-separated parts of their paths, e.g. `mitsuba,serialized`; default all),
//! `TRILUX_FUZZ_SEED` the seed (default fixed), `TRILUX_FUZZ_ADDRESS_SPACE` each render's
//! address-space limit in bytes (default 4 GiB). The summary counts panics, aborts, failed
//! allocations and renders killed; failing mutants are kept (each in its case's folder), and
//! their paths printed. Without `../shared` its scenes are skipped (failed instead when
//! `TRILUX_REQUIRE_SHARED` is set).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
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

/// One to three mutations of `bytes`: a byte flipped, the bytes cut, a line doubled or
/// removed, a number swapped for a hostile one. Lines and numbers are found in the bytes as
/// they are, so that a binary mesh keeps its body but where a mutation hits it.
fn mutate(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut bytes = bytes.to_vec();
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
                let mut lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
                if lines.is_empty() {
                    continue;
                }
                let k = rng.below(lines.len());
                if rng.below(4) == 0 {
                    lines.remove(k);
                } else {
                    lines.insert(k, lines[k]);
                }
                bytes = lines.concat();
            }
            _ => {
                // Numbers: runs of digits, signs, dots and exponents between separators.
                let numbers: Vec<(usize, usize)> = words(&bytes)
                    .filter(|&(a, b)| {
                        std::str::from_utf8(&bytes[a..b]).is_ok_and(|w| w.parse::<f64>().is_ok())
                    })
                    .collect();
                if numbers.is_empty() {
                    continue;
                }
                let (a, b) = numbers[rng.below(numbers.len())];
                let with = HOSTILE_NUMBERS[rng.below(HOSTILE_NUMBERS.len())];
                bytes = [&bytes[..a], with.as_bytes(), &bytes[b..]].concat();
            }
        }
    }
    bytes
}

/// The byte ranges of the words of `bytes`: runs between ASCII whitespace, quotes, commas
/// and angle brackets (an XML attribute's numbers are words).
fn words(bytes: &[u8]) -> impl Iterator<Item = (usize, usize)> + '_ {
    let mut start = None;
    bytes
        .iter()
        .chain(std::iter::once(&b' '))
        .enumerate()
        .filter_map(move |(i, &c)| {
            if c.is_ascii_whitespace() || b"\"',<>=".contains(&c) {
                start.take().map(|s| (s, i))
            } else {
                start.get_or_insert(i);
                None
            }
        })
}

/// What a mutant is made from.
enum Input {
    /// A scene file, its mutant in a copy of the tree from `root` down to the file's folder
    /// (every other entry linked), so that its includes, meshes and textures, and a Mitsuba
    /// scene's `<path value="../../../common"/>`, resolve as the original's do. A file that
    /// is only ever included (Mitsuba's fragments) is rendered `via` a scene that includes
    /// it, in a folder above it: the mutant takes the file's own name there.
    Scene {
        file: PathBuf,
        root: PathBuf,
        via: Option<PathBuf>,
    },
    /// A mesh of Mitsuba's (`shape` `ply` or `serialized`), its mutant rendered through a
    /// small scene that names it.
    Mesh { file: PathBuf, shape: &'static str },
}

impl Input {
    fn file(&self) -> &Path {
        match self {
            Input::Scene { file, .. } | Input::Mesh { file, .. } => file,
        }
    }
}

/// The inputs to mutate: `scenes/`'s, and when `../shared` is there the course's, the MGF and
/// Mitsuba's test scenes and Mitsuba's PLY meshes; and a `serialized` mesh written into `work`.
fn inputs(work: &Path) -> Vec<Input> {
    let own = common::own_scene_dir();
    let mut files = common::own_scenes();
    files.extend(
        std::fs::read_dir(&own)
            .expect("scenes/")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mgf")),
    );
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared");
    let required = std::env::var_os("TRILUX_REQUIRE_SHARED").is_some();
    for (dir, ext) in [
        ("course-scenes", "obj"),
        ("mgf-scenes", "mgf"),
        ("mitsuba-tests/tests", "xml"),
        ("mitsuba-tests/common/meshes", "ply"),
    ] {
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
    // Mitsuba's test scenes climb to the folder that holds `common/`; those of a group's
    // folder are scenes, those in its subfolders fragments they include.
    let mitsuba = shared.join("mitsuba-tests");
    let groups = mitsuba.join("tests/scenes");
    let scenes: Vec<PathBuf> = files
        .iter()
        .filter(|f| f.parent().and_then(Path::parent) == Some(&groups))
        .cloned()
        .collect();
    let mut inputs: Vec<Input> = files
        .into_iter()
        .map(|file| {
            if file.extension().is_some_and(|e| e == "ply") {
                Input::Mesh { file, shape: "ply" }
            } else if file.starts_with(&mitsuba) {
                let via = (!scenes.contains(&file)).then(|| including(&file, &scenes));
                Input::Scene {
                    file,
                    root: mitsuba.clone(),
                    via,
                }
            } else {
                let root = file.parent().expect("a folder").to_path_buf();
                Input::Scene {
                    file,
                    root,
                    via: None,
                }
            }
        })
        .collect();
    let file = work.join("tetrahedron.serialized");
    std::fs::write(&file, serialized(&tetrahedron())).expect("serialized mesh written");
    inputs.push(Input::Mesh {
        file,
        shape: "serialized",
    });
    // `TRILUX_FUZZ_ONLY`: comma-separated parts of the paths to keep.
    if let Ok(only) = std::env::var("TRILUX_FUZZ_ONLY") {
        let path = |i: &Input| i.file().to_string_lossy().into_owned();
        inputs.retain(|i| only.split(',').any(|part| path(i).contains(part)));
        assert!(!inputs.is_empty(), "TRILUX_FUZZ_ONLY={only} keeps no input");
    }
    inputs
}

/// The first of `scenes` in a folder above `fragment` that reads it (names it, or names a
/// fragment beside it that does) and loads.
fn including(fragment: &Path, scenes: &[PathBuf]) -> PathBuf {
    let folder = fragment.parent().expect("a folder");
    let mut beside = Vec::new();
    collect(folder, "xml", &mut beside);
    let names = |file: &Path, named: &Path| {
        let name = named.file_name().expect("a name").to_string_lossy();
        std::fs::read_to_string(file).is_ok_and(|t| t.contains(name.as_ref()))
    };
    let reads = |scene: &Path| {
        names(scene, fragment)
            || beside
                .iter()
                .any(|b| b != fragment && names(scene, b) && names(b, fragment))
    };
    scenes
        .iter()
        .filter(|s| fragment.starts_with(s.parent().expect("a folder")) && reads(s))
        .find(|s| trilux::scene::Scene::load(s).is_ok())
        .unwrap_or_else(|| panic!("no scene reads {} and loads", fragment.display()))
        .clone()
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

/// The decompressed record of Mitsuba's `serialized` format (version 4, as
/// `src/scene/mitsuba/meshes.rs` reads it) of a tetrahedron with normals and texture
/// coordinates: flags, a NUL-terminated name, the vertex and triangle counts, then positions,
/// normals, texture coordinates and indices, little-endian.
fn tetrahedron() -> Vec<u8> {
    const HAS_NORMALS: u32 = 0x0001;
    const HAS_TEX_COORDS: u32 = 0x0002;
    let positions = [
        [0.0f32, 0.0, 1.0],
        [1.0, 0.0, -0.5],
        [-0.5, 0.9, -0.5],
        [-0.5, -0.9, -0.5],
    ];
    let indices = [[0u32, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]];
    let mut record = (HAS_NORMALS | HAS_TEX_COORDS).to_le_bytes().to_vec();
    record.extend_from_slice(b"tetrahedron\0");
    record.extend_from_slice(&(positions.len() as u64).to_le_bytes());
    record.extend_from_slice(&(indices.len() as u64).to_le_bytes());
    // A vertex's normal points away from the centre, as its position does.
    for v in positions.iter().chain(&positions).flatten() {
        record.extend_from_slice(&v.to_le_bytes());
    }
    for v in positions.iter().flat_map(|p| [p[0].abs(), p[1].abs()]) {
        record.extend_from_slice(&v.to_le_bytes());
    }
    for i in indices.iter().flatten() {
        record.extend_from_slice(&i.to_le_bytes());
    }
    record
}

/// A `serialized` file of one mesh: the format's tag and version, the zlib-compressed
/// `record`, then the table of the meshes' offsets (u64 each) and their count.
fn serialized(record: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut file = [0x041Cu16.to_le_bytes(), 4u16.to_le_bytes()].concat();
    let mut zlib = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    zlib.write_all(record).expect("compressed in memory");
    file.extend(zlib.finish().expect("compressed in memory"));
    file.extend_from_slice(&0u64.to_le_bytes());
    file.extend_from_slice(&1u32.to_le_bytes());
    file
}

/// A mutant of a `serialized` file: half the time its bytes as they are (where the zlib
/// stream's checksum catches most), half the time its decompressed record, compressed again,
/// so that the counts, flags and numbers the reader decodes are what is hostile.
fn mutate_serialized(file: &[u8], rng: &mut Rng) -> Vec<u8> {
    if rng.below(2) == 0 {
        return mutate(file, rng);
    }
    let mut record = Vec::new();
    use std::io::Read;
    flate2::read::ZlibDecoder::new(&file[4..])
        .read_to_end(&mut record)
        .expect("the test's own serialized file");
    serialized(&mutate(&record, rng))
}

/// A small Mitsuba scene that shows the mesh `file` (relative to the scene) in front of a
/// camera, lit by a sky and a point light.
fn mesh_scene(file: &str, shape: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
    <emitter type="point"><point name="position" x="2" y="2" z="4"/><rgb name="intensity" value="20"/></emitter>
    <shape type="{shape}"><string name="filename" value="{file}"/></shape>
</scene>
"#
    )
}

/// One mutant: the file `render` is given, and the unmutated file it stands for (rendered
/// when the mutant is killed, to tell a runaway from a scene that is slow as it is).
struct Mutant {
    input: PathBuf,
    original: PathBuf,
}

/// Writes case `case`'s mutant of `input` under `work`.
fn make(input: &Input, work: &Path, case: usize, rng: &mut Rng) -> Mutant {
    let dir = work.join(format!("case{case}"));
    let bytes = std::fs::read(input.file()).expect("input read");
    let name = input.file().file_name().expect("a name").to_string_lossy();
    match input {
        Input::Scene { file, root, via } => {
            let folder = mirror(root, file.parent().expect("a folder"), &dir);
            let mutated = mutate(&bytes, rng);
            match via {
                None => {
                    let mutant = folder.join(format!("mutant-{name}"));
                    std::fs::write(&mutant, mutated).expect("mutant written");
                    Mutant {
                        input: mutant,
                        original: file.clone(),
                    }
                }
                Some(scene) => {
                    let mutant = folder.join(name.as_ref());
                    std::fs::remove_file(&mutant).expect("the fragment's link");
                    std::fs::write(&mutant, mutated).expect("mutant written");
                    let below = scene
                        .strip_prefix(root)
                        .expect("the scene is under its root");
                    Mutant {
                        input: dir.join(below),
                        original: scene.clone(),
                    }
                }
            }
        }
        Input::Mesh { file, shape } => {
            std::fs::create_dir_all(&dir).expect("case folder");
            let mutated = match *shape {
                "serialized" => mutate_serialized(&bytes, rng),
                _ => mutate(&bytes, rng),
            };
            std::fs::write(dir.join(format!("mutant-{name}")), mutated).expect("mutant written");
            let scene = |mesh: &str, to: &str| {
                let path = dir.join(to);
                std::fs::write(&path, mesh_scene(mesh, shape)).expect("scene written");
                path
            };
            Mutant {
                input: scene(&format!("mutant-{name}"), "mutant.xml"),
                original: scene(&file.to_string_lossy(), "original.xml"),
            }
        }
    }
}

/// A copy under `to` of the tree from `root` down to its folder `folder`: every entry of each
/// folder on the way linked, except the one the way goes through, which is made. Returns the
/// copy of `folder`.
fn mirror(root: &Path, folder: &Path, to: &Path) -> PathBuf {
    let below = folder
        .strip_prefix(root)
        .expect("the folder is under its root");
    let (mut from, mut into) = (root.to_path_buf(), to.to_path_buf());
    let mut steps = below.components();
    loop {
        std::fs::create_dir_all(&into).expect("case folder");
        let next = steps.next();
        for entry in std::fs::read_dir(&from).into_iter().flatten().flatten() {
            let name = entry.file_name();
            if next.is_some_and(|n| n.as_os_str() == name) {
                continue;
            }
            let _ = std::os::unix::fs::symlink(entry.path(), into.join(&name));
        }
        match next {
            Some(step) => {
                from.push(step);
                into.push(step);
            }
            None => return into,
        }
    }
}

/// `f` of each of `items` on two threads (the cores CI has), the results in the items' order.
fn in_parallel<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::with_capacity(items.len()));
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(k) else { break };
                let r = f(item);
                results.lock().expect("results").push((k, r));
            });
        }
    });
    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|&(k, _)| k);
    results.into_iter().map(|(_, r)| r).collect()
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
    // The photon engine's own count at 8×8 is its floor of 100,000 (and as many aimed at
    // mirrors): a few thousand trace the mutant as surely, in a CI run's time.
    if engine == "photon" {
        args.extend(["-num_photons_to_shoot", "4000"].map(std::ffi::OsStr::new));
    }
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
    let work = common::temp_dir("fuzz");
    let inputs = inputs(&work);
    let mut rng = Rng(seed);
    let start = std::time::Instant::now();
    // Mutants made in this thread, in order (each from its own generator state, so that a
    // case does not depend on the others' timing); loaded and rendered in parallel.
    let mutants: Vec<Mutant> = (0..cases)
        .map(|case| {
            let mut case_rng = Rng(rng.next());
            make(&inputs[case % inputs.len()], &work, case, &mut case_rng)
        })
        .collect();
    let results = in_parallel(&mutants, |mutant| {
        let began = std::time::Instant::now();
        let result = loads(&mutant.input);
        let took = began.elapsed().as_secs_f64();
        if took > 2.0 {
            println!(
                "fuzz: slow to load: {} ({}): {took:.1} s",
                mutant.input.display(),
                mutant.original.display()
            );
        }
        result
    });
    let mut loaded = Vec::new();
    let mut failures = Vec::new();
    for (mutant, result) in mutants.iter().zip(results) {
        match result {
            Ok(true) => loaded.push(mutant),
            Ok(false) => {}
            Err(what) => failures.push(Failure {
                mutant: mutant.input.clone(),
                what,
            }),
        }
    }
    let jobs: Vec<(&Mutant, &str, String)> = loaded
        .iter()
        .flat_map(|&m| {
            let radiosity = radiosity_renders(&m.input);
            ENGINES
                .iter()
                .filter(move |e| **e != "radiosity" || radiosity)
                .flat_map(move |e| {
                    common::backends()
                        .into_iter()
                        .map(move |k| (m, *e, k.to_string()))
                })
        })
        .collect();
    let found = in_parallel(&jobs, |(mutant, engine, accel)| {
        let began = std::time::Instant::now();
        let result = render(&mutant.input, engine, accel);
        let took = began.elapsed().as_secs_f64();
        if took > 5.0 {
            println!(
                "fuzz: slow: {} {engine} {accel}: {took:.1} s",
                mutant.input.display()
            );
        }
        // A mutant as slow as its original is not a runaway: some valid scenes take long for
        // other reasons (a hospital's radiosity at 8×8 takes 40 s).
        let slow_original = |what: &String| {
            what.contains(KILLED)
                && render(&mutant.original, engine, accel).is_err_and(|e| e.contains(KILLED))
        };
        match result {
            Err(what) if slow_original(&what) => {
                println!(
                    "fuzz: {}: {what}, as its original: not counted",
                    mutant.input.display()
                );
                None
            }
            Err(what) => Some(Failure {
                mutant: mutant.input.clone(),
                what,
            }),
            Ok(()) => None,
        }
    });
    failures.extend(found.into_iter().flatten());
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
