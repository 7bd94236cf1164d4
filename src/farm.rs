//! `render farm`: a render split into parts — tiles of the image (`--crop-window`) or batches
//! of each pixel's samples (`--pixel-samples`) — run as a Slurm job array, then merged
//! (`render merge`). Nothing of Slurm is linked: the farm writes ordinary batch scripts into a
//! folder and, when asked, submits them with `sbatch` and waits with `squeue`.
//!
//! The folder holds:
//! - `prepass.sbatch`: where the engine has a pre-pass (photon maps, a radiosity solution),
//!   one job that computes it once (`--pre-pass-only --save-…`) into `prepass/`;
//! - `parts.sbatch`: the job array, one task per part, each loading the pre-pass and writing
//!   `parts/part-<task>.exr`, its exit status kept in `status/task-<task>`;
//! - `merge.sbatch`: `render merge` of every part into the output, run only if every task
//!   succeeded (`--dependency=afterok`, `--kill-on-invalid-dep=yes`);
//! - `submit.sh`: submits the three in order, each depending on the one before, and prints
//!   the job ids (what `--submit` runs);
//! - `logs/`: each job's output.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::engines::engine::PrePass;
use crate::film::part::Window;

/// How a render is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// A grid of this many tiles.
    Tiles(u32),
    /// This many batches of each pixel's samples.
    SampleBatches(u32),
}

/// One part: the flag that makes it, and what it covers (for messages).
#[derive(Clone, Debug, PartialEq)]
pub struct PartSpec {
    /// `--crop-window X0 X1 Y0 Y1` or `--pixel-samples A B`, as arguments.
    pub args: Vec<String>,
    /// "tile 2 of 4 (columns 0..128, rows 128..256)", "samples 8..16".
    pub describe: String,
}

/// The parts of a `width` × `height` render of `spp` samples per pixel split as asked.
/// Tiles form a grid of rows × columns, rows the largest divisor of N not above √N; a tile's
/// edges are whole pixels, written as fractions that `Window::from_fractions` gives back.
pub fn parts(split: Split, width: u32, height: u32, spp: u32) -> Result<Vec<PartSpec>, String> {
    match split {
        Split::Tiles(n) => {
            let rows = (1..=n)
                .filter(|r| n % r == 0 && r * r <= n)
                .max()
                .unwrap_or(1);
            let cols = n / rows;
            if n == 0 || cols > width || rows > height {
                return Err(format!(
                    "--tiles {n}: a {width}×{height} image cannot be cut into {n} tiles ({cols} columns × {rows} rows) of at least one pixel"
                ));
            }
            let edge = |k: u32, parts: u32, side: u32| {
                ((side as u64 * k as u64 + parts as u64 / 2) / parts as u64) as u32
            };
            let fraction = |e: u32, side: u32| format!("{:.12}", e as f64 / side as f64);
            Ok((0..n)
                .map(|i| {
                    let (r, c) = (i / cols, i % cols);
                    let (x0, x1) = (edge(c, cols, width), edge(c + 1, cols, width));
                    let (y0, y1) = (edge(r, rows, height), edge(r + 1, rows, height));
                    let window = Window { x0, y0, x1, y1 };
                    PartSpec {
                        args: vec![
                            "--crop-window".into(),
                            fraction(x0, width),
                            fraction(x1, width),
                            fraction(y0, height),
                            fraction(y1, height),
                        ],
                        describe: format!("tile {i} of {n} ({window})"),
                    }
                })
                .collect())
        }
        Split::SampleBatches(n) => {
            if n == 0 || n > spp {
                return Err(format!(
                    "--sample-batches {n}: expected 1 to -num_antialias_samples ({spp}) batches"
                ));
            }
            let edge = |b: u32| (spp as u64 * b as u64 / n as u64) as u32;
            Ok((0..n)
                .map(|b| {
                    let (a, z) = (edge(b), edge(b + 1));
                    PartSpec {
                        args: vec!["--pixel-samples".into(), a.to_string(), z.to_string()],
                        describe: format!("batch {b} of {n} (samples {a}..{z})"),
                    }
                })
                .collect())
        }
    }
}

/// Everything the farm's scripts are written from.
pub struct Farm {
    /// The folder of scripts, parts, logs and statuses (absolute).
    pub dir: PathBuf,
    /// The `render` program the jobs run (absolute).
    pub program: PathBuf,
    /// The scene (absolute) and the render flags every job passes, as the user gave them
    /// (without output, the split's own flags and the pre-pass files).
    pub scene: PathBuf,
    pub flags: Vec<String>,
    /// Whether the flags set `--threads` (else each job uses the CPUs Slurm gave it).
    pub threads_given: bool,
    /// The merged image (absolute).
    pub output: PathBuf,
    /// The variance of each pixel's samples, written by the merge (absolute) [default: none].
    pub variance: Option<PathBuf>,
    pub parts: Vec<PartSpec>,
    /// The engine's pre-pass, unless it needs none or the flags load one already.
    pub pre_pass: Option<PrePass>,
    /// Slurm requests: partition, time limit (minutes), CPUs and memory (MiB) per job.
    pub partition: Option<String>,
    pub time_minutes: Option<u32>,
    pub cpus_per_task: u32,
    pub memory_mib: u64,
    /// A name for the jobs (the scene's stem).
    pub name: String,
}

/// A word for bash, single-quoted.
fn quote(word: &str) -> String {
    format!("'{}'", word.replace('\'', r"'\''"))
}

fn quote_path(path: &Path) -> String {
    quote(&path.to_string_lossy())
}

impl Farm {
    /// Where the pre-pass is saved, if there is one.
    fn pre_pass_file(&self) -> Option<PathBuf> {
        self.pre_pass.map(|p| {
            self.dir.join("prepass").join(match p.save_flag {
                "--save-photons" => "photons.bin",
                _ => "radiosity.bin",
            })
        })
    }

    /// The status file of a job ("prepass", "task-3").
    pub fn status_file(&self, job: &str) -> PathBuf {
        self.dir.join("status").join(job)
    }

    pub fn part_file(&self, task: usize) -> PathBuf {
        self.dir.join("parts").join(format!("part-{task}.exr"))
    }

    /// The `#SBATCH` lines every job shares, and its name and log.
    fn header(&self, job: &str, log: &str, extra: &str) -> String {
        let mut s = String::from("#!/usr/bin/env bash\n");
        let _ = writeln!(s, "#SBATCH --job-name=trilux-{job}-{}", self.name);
        let _ = writeln!(
            s,
            "#SBATCH --output={}",
            self.dir.join("logs").join(log).display()
        );
        let _ = writeln!(s, "#SBATCH --cpus-per-task={}", self.cpus_per_task);
        let _ = writeln!(s, "#SBATCH --mem={}M", self.memory_mib);
        if let Some(p) = &self.partition {
            let _ = writeln!(s, "#SBATCH --partition={p}");
        }
        if let Some(t) = self.time_minutes {
            let _ = writeln!(s, "#SBATCH --time={t}");
        }
        s += extra;
        s
    }

    /// The render command every job starts from: program, scene, the user's flags, threads.
    fn render_command(&self) -> String {
        let mut words = vec![
            quote_path(&self.program),
            "-input".into(),
            quote_path(&self.scene),
        ];
        words.extend(self.flags.iter().map(|f| quote(f)));
        if !self.threads_given {
            words.push("--threads \"${SLURM_CPUS_PER_TASK:-1}\"".into());
        }
        // Not --quiet: the logs keep each job's summary (what was solved or loaded, what was
        // written); progress bars are not drawn into a log.
        words.join(" ")
    }

    /// Runs `command` and records its exit status in the status file `status_file` (a bash
    /// word), then exits with it.
    fn keep_status(command: &str, status_file: &str) -> String {
        format!(
            "status=0\n{command} || status=$?\necho \"$status\" > {status_file}\nexit \"$status\"\n"
        )
    }

    pub fn prepass_script(&self) -> Option<String> {
        let (pre, file) = (self.pre_pass?, self.pre_pass_file()?);
        let mut s = self.header(
            "prepass",
            "prepass.log",
            &format!("# The {}, computed once for every task.\n", pre.name),
        );
        let command = format!(
            "{} --pre-pass-only {} {}",
            self.render_command(),
            pre.save_flag,
            quote_path(&file)
        );
        s += &Farm::keep_status(&command, &quote_path(&self.status_file("prepass")));
        Some(s)
    }

    pub fn parts_script(&self) -> String {
        let n = self.parts.len();
        let mut s = self.header(
            "parts",
            "part-%a.log",
            &format!("#SBATCH --array=0-{}\n", n - 1),
        );
        s += "# What each task renders.\nparts=(\n";
        for p in &self.parts {
            let _ = writeln!(s, "  \"{}\"  # {}", p.args.join(" "), p.describe);
        }
        s += ")\ntask=${SLURM_ARRAY_TASK_ID:?run this as a Slurm array task}\n";
        let mut command = format!("{} ${{parts[$task]}}", self.render_command());
        if let (Some(pre), Some(file)) = (self.pre_pass, self.pre_pass_file()) {
            let _ = write!(command, " {} {}", pre.load_flag, quote_path(&file));
        }
        let _ = write!(
            command,
            " -o {}/part-\"$task\".exr",
            quote_path(&self.dir.join("parts"))
        );
        let status = format!("{}/task-\"$task\"", quote_path(&self.dir.join("status")));
        s += &Farm::keep_status(&command, &status);
        s
    }

    pub fn merge_script(&self) -> String {
        let mut s = self.header("merge", "merge.log", "");
        let mut command = format!("{} merge", quote_path(&self.program));
        for k in 0..self.parts.len() {
            let _ = write!(command, " {}", quote_path(&self.part_file(k)));
        }
        let _ = write!(command, " -o {}", quote_path(&self.output));
        if let Some(variance) = &self.variance {
            let _ = write!(command, " --variance {}", quote_path(variance));
        }
        s += &Farm::keep_status(&command, &quote_path(&self.status_file("merge")));
        s
    }

    /// Submits the jobs in order, each depending on the one before; prints "JOB ID" lines.
    pub fn submit_script(&self) -> String {
        let dir = quote_path(&self.dir);
        let mut s = String::from(
            "#!/usr/bin/env bash\n# Submits the farm's jobs; prints each job's id. Run it again to render again.\nset -euo pipefail\n",
        );
        let _ = writeln!(s, "cd {dir}\nrm -f status/*");
        let mut after = String::new();
        if self.pre_pass.is_some() {
            s += "prepass=$(sbatch --parsable prepass.sbatch)\necho \"prepass $prepass\"\n";
            after = " --dependency=afterok:$prepass --kill-on-invalid-dep=yes".into();
        }
        let _ = writeln!(
            s,
            "parts=$(sbatch --parsable{after} parts.sbatch)\necho \"parts $parts\""
        );
        s += "merge=$(sbatch --parsable --dependency=afterok:$parts --kill-on-invalid-dep=yes merge.sbatch)\necho \"merge $merge\"\n";
        s
    }

    /// Writes the folder: scripts, and the folders the jobs write into (status files of an
    /// earlier run are removed by `submit.sh`).
    pub fn write(&self) -> Result<(), String> {
        for sub in ["parts", "logs", "status", "prepass"] {
            let d = self.dir.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| format!("{}: {e}", d.display()))?;
        }
        let mut files = vec![
            ("parts.sbatch", self.parts_script()),
            ("merge.sbatch", self.merge_script()),
            ("submit.sh", self.submit_script()),
        ];
        if let Some(s) = self.prepass_script() {
            files.push(("prepass.sbatch", s));
        }
        for (name, text) in files {
            let path = self.dir.join(name);
            crate::output::write_text_atomically(&path, &text).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// Runs `submit.sh`: the job ids by job ("prepass", "parts", "merge").
    pub fn submit(&self) -> Result<Vec<(String, String)>, String> {
        let out = Command::new("bash")
            .arg(self.dir.join("submit.sh"))
            .output()
            .map_err(|e| format!("cannot run bash: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "submitting the farm failed (is Slurm's sbatch on PATH and SLURM_CONF set?): {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        Ok(String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| {
                let (job, id) = l.split_once(' ')?;
                Some((job.to_string(), id.trim().to_string()))
            })
            .collect())
    }

    /// Waits until Slurm has none of `ids` left (queued or running), polling `squeue`.
    pub fn wait(&self, ids: &[(String, String)]) -> Result<(), String> {
        let list: Vec<&str> = ids.iter().map(|(_, id)| id.as_str()).collect();
        loop {
            let out = Command::new("squeue")
                .args(["-h", "-o", "%i", "-j", &list.join(",")])
                .output()
                .map_err(|e| format!("cannot run squeue: {e}"))?;
            // squeue fails once every job it was asked about has left the controller.
            if !out.status.success() || out.stdout.iter().all(u8::is_ascii_whitespace) {
                return Ok(());
            }
            if crate::interrupt::requested() {
                return Err(
                    "interrupted while waiting (the jobs go on; scancel them to stop them)".into(),
                );
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    /// What became of the jobs, from their status files: Ok with the output when the merge
    /// ran and succeeded; else which job or task failed and where its log is.
    pub fn outcome(&self) -> Result<String, String> {
        let status = |job: &str| {
            std::fs::read_to_string(self.status_file(job))
                .ok()
                .and_then(|s| s.trim().parse::<i32>().ok())
        };
        let log = |name: &str| self.dir.join("logs").join(name);
        if self.pre_pass.is_some() && status("prepass") != Some(0) {
            return Err(format!(
                "the pre-pass failed ({}); see {}; no part was rendered",
                describe_status(status("prepass")),
                log("prepass.log").display()
            ));
        }
        let failed: Vec<String> = (0..self.parts.len())
            .filter_map(|k| {
                let s = status(&format!("task-{k}"));
                (s != Some(0)).then(|| {
                    format!(
                        "task {k}, {}, {}: see {}",
                        self.parts[k].describe,
                        describe_status(s),
                        log(&format!("part-{k}.log")).display()
                    )
                })
            })
            .collect();
        if !failed.is_empty() {
            return Err(format!(
                "{} of {} tasks failed, so the merge job did not run:\n  {}",
                failed.len(),
                self.parts.len(),
                failed.join("\n  ")
            ));
        }
        match status("merge") {
            Some(0) => Ok(format!(
                "merged {} parts into {}",
                self.parts.len(),
                self.output.display()
            )),
            s => Err(format!(
                "the merge {}; see {}",
                describe_status(s),
                log("merge.log").display()
            )),
        }
    }
}

fn describe_status(status: Option<i32>) -> String {
    match status {
        Some(code) => format!("exit status {code}"),
        None => "did not finish (cancelled, killed, or not run)".into(),
    }
}
