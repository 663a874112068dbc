//! The jobs of `pathwave farm slurm` (their scripts and submission) and the checks of `farm
//! merge`.

use crate::animate::sequence;
use crate::checkpoint::{self, Checkpoint};
use crate::io;
use crate::shard::{self, Task};
use std::path::{Path, PathBuf};
use std::process::Command;

/// `pathwave farm slurm`'s own options; the render's come from the flags `render` and
/// `animate` share, which every task is given.
#[derive(clap::Args, Debug)]
pub struct SlurmArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The frames' pattern (e.g. out/frame_{frame:04}.png), or with --split-samples the image.
    #[arg(short, long, visible_alias = "outfile")]
    pub output: String,
    /// Tasks in the job array.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub tasks: u32,
    /// Frames A..B (B excluded) or A..=B of the sequence (default: the scene's animation).
    #[arg(long, conflicts_with = "split_samples")]
    pub frames: Option<String>,
    /// Render one image, its samples split among the tasks, then merged.
    #[arg(long)]
    pub split_samples: bool,
    /// Frames per second (default: the scene's), as `animate --fps`.
    #[arg(long, conflicts_with = "split_samples")]
    pub fps: Option<f32>,
    /// Shutter as a fraction of the frame interval, as `animate --shutter`.
    #[arg(long, conflicts_with = "split_samples")]
    pub shutter: Option<f32>,
    /// The Slurm partition of both jobs (sbatch --partition).
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit of each task and of the merge job (sbatch --time, e.g. 2:00:00).
    #[arg(long, value_name = "LIMIT")]
    pub time: Option<String>,
    /// The folder of the job scripts, the logs and the sample shares (default: beside the
    /// output, its name with `.farm` appended, `{frame:04}` read as `frames`).
    #[arg(long, value_name = "DIR")]
    pub job_dir: Option<PathBuf>,
    /// Print the scripts and the commands that would submit them; write and submit nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Further options for sbatch, given to both jobs (e.g. -- --cpus-per-task=8 --mem=16G).
    #[arg(last = true, value_name = "SBATCH OPTIONS")]
    pub sbatch: Vec<String>,
}

/// `pathwave farm merge`: the merge job's work (also run by hand, e.g. after a Kubernetes
/// Indexed Job).
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("work").required(true).args(["spp", "frames"])))]
pub struct MergeArgs {
    /// The image the shares add up to, or the frames' pattern.
    #[arg(short, long, visible_alias = "outfile")]
    pub output: String,
    /// How many tasks shared the work.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub tasks: u32,
    /// Sample shares of a render of SPP samples per pixel: task I rendered share I of them
    /// (`render --samples auto`) into PARTS/task-I.exr.ckpt.
    #[arg(long, requires = "parts")]
    pub spp: Option<u32>,
    /// The folder of the shares (with --spp).
    #[arg(long, value_name = "PARTS")]
    pub parts: Option<PathBuf>,
    /// Frames A..B or A..=B, task I having rendered every N-th from the I-th (`animate --shard
    /// auto`): check that every one is there.
    #[arg(long, conflicts_with = "parts")]
    pub frames: Option<String>,
    /// How a PNG of the merged samples shows the image (the render's flags, passed on).
    #[command(flatten)]
    pub look: crate::look::LookArgs,
}

/// What the tasks split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Work {
    /// One image's `spp` samples per pixel.
    Samples {
        /// Samples per pixel of the whole render.
        spp: u32,
    },
    /// Frames `[first, end)`.
    Frames {
        /// The first frame.
        first: u32,
        /// One past the last.
        end: u32,
    },
}

/// A job ready to write and submit, every path absolute.
#[derive(Clone, Debug)]
pub struct Job {
    /// The pathwave binary the tasks run.
    pub exe: PathBuf,
    /// The scene file.
    pub scene: PathBuf,
    /// The image, or the frames' pattern.
    pub output: String,
    /// What the tasks split.
    pub work: Work,
    /// How many tasks.
    pub tasks: u32,
    /// Render flags every task gets (`--spp=16`, ...).
    pub render_args: Vec<String>,
    /// Scripts, logs and shares.
    pub dir: PathBuf,
    /// Name of the jobs in the queue.
    pub name: String,
    /// `#SBATCH` lines besides the job's own (partition, time limit).
    pub directives: Vec<String>,
    /// sbatch options for every submission.
    pub sbatch: Vec<String>,
    /// One image's shares with path guiding: a job learns the guides first
    /// ([`Job::train_script`]), which every task reads.
    pub guided: bool,
}

impl Job {
    /// Checks the farm's options against the scene (`spp` samples per pixel, its animation's
    /// frames `scene_frames`, path guiding on or not: `guided`) and settles every path;
    /// `render_args` are the render flags to pass on (see [`forwarded`]).
    pub fn plan(
        args: &SlurmArgs,
        spp: u32,
        scene_frames: (u32, u32),
        guided: bool,
        mut render_args: Vec<String>,
    ) -> Result<Job, String> {
        if render_args.iter().any(|a| a.starts_with("--guide-file")) {
            return Err("--guide-file: a farm keeps the guides in its job folder (guides.bin)".into());
        }
        let absolute = |p: &Path| std::path::absolute(p).map_err(|e| format!("{}: {e}", p.display()));
        let scene = absolute(&args.scene)?;
        let output = utf8(&absolute(Path::new(&args.output))?)?.to_owned();
        let tasks = args.tasks;
        let work = match args.split_samples {
            true => {
                io::check_output(Path::new(&output), &[&scene], false)?;
                if tasks > spp {
                    return Err(format!(
                        "--tasks {tasks}: the {spp} samples per pixel make at most {spp} shares \
                         (more samples with --spp, or fewer tasks)"
                    ));
                }
                Work::Samples { spp }
            }
            false => {
                let (first, end) = match &args.frames {
                    Some(f) => shard::parse_range(f, "--frames")?,
                    None => scene_frames,
                };
                if !output.contains("{frame") {
                    return Err(format!(
                        "{}: the tasks write frame files, so the output needs {{frame}} or \
                         {{frame:04}} (e.g. out/frame_{{frame:04}}.png); --split-samples splits \
                         one image",
                        args.output
                    ));
                }
                let path = sequence::frame_path(&output, first)?;
                let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
                if !matches!(ext.as_deref(), Some("png" | "exr")) {
                    return Err(format!(
                        "{}: a farm writes frame files: use a pattern such as out/frame_{{frame:04}}.png \
                         or .exr (or --split-samples and one image)",
                        args.output
                    ));
                }
                if io::same_file(&scene, &path) {
                    return Err(format!("{}: the output would replace the scene", args.output));
                }
                if tasks > end - first {
                    return Err(format!(
                        "--tasks {tasks}: frames {first}..{end} keep at most {} busy (or \
                         --split-samples to split one image's samples)",
                        match end - first {
                            1 => "1 task".to_string(),
                            n => format!("{n} tasks"),
                        }
                    ));
                }
                if let Some(fps) = args.fps {
                    if !(fps.is_finite() && fps > 0.0) {
                        return Err(format!("--fps takes a number > 0, not {fps}"));
                    }
                    render_args.push(format!("--fps={fps}"));
                }
                if let Some(shutter) = args.shutter {
                    if !(0.0..=1.0).contains(&shutter) {
                        return Err(format!(
                            "--shutter takes a fraction of the frame interval in [0, 1], not {shutter}"
                        ));
                    }
                    render_args.push(format!("--shutter={shutter}"));
                }
                Work::Frames { first, end }
            }
        };
        let dir = match &args.job_dir {
            Some(d) => absolute(d)?,
            None => PathBuf::from(format!("{}.farm", without_frame_field(&output))),
        };
        // The log paths go into #SBATCH lines, which Slurm splits at spaces and in which `%`
        // starts a file name pattern (sbatch(1), "filename pattern").
        let d = utf8(&dir)?;
        if d.chars().any(|c| c.is_whitespace() || "%'\"\\".contains(c)) {
            return Err(format!(
                "{d}: the job folder's path holds a space, quote, backslash or %, which #SBATCH \
                 lines cannot carry; choose another with --job-dir"
            ));
        }
        let mut directives = Vec::new();
        for (option, value) in [("partition", &args.partition), ("time", &args.time)] {
            if let Some(v) = value {
                if v.is_empty() || v.chars().any(|c| c.is_whitespace() || "'\"\\#".contains(c)) {
                    return Err(format!("--{option} {v:?}: not a Slurm {option}"));
                }
                directives.push(format!("--{option}={v}"));
            }
        }
        let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let name: String = stem
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
            .collect();
        let exe = std::env::current_exe().map_err(|e| format!("cannot find the pathwave binary: {e}"))?;
        Ok(Job {
            exe,
            scene,
            output,
            work,
            tasks,
            render_args,
            dir,
            name: format!("pathwave-{name}"),
            directives,
            sbatch: args.sbatch.clone(),
            guided: guided && args.split_samples,
        })
    }

    /// Writes the scripts into the job folder and submits the array (after the training job,
    /// with path guiding), then the merge job depending on it; prints how to follow them. With
    /// `dry_run`, prints the scripts and the commands instead.
    pub fn submit(&self, dry_run: bool) -> Result<(), String> {
        let (render, merge) = (self.render_script()?, self.merge_script()?);
        let (render_path, merge_path) = (self.dir.join("render.sbatch"), self.dir.join("merge.sbatch"));
        let train = self.guided.then(|| self.train_script()).transpose()?;
        let train_path = self.dir.join("train.sbatch");
        let extra: Vec<String> = self.sbatch.iter().map(|a| sh(a)).collect();
        let extra = extra.iter().map(|a| format!(" {a}")).collect::<String>();
        let mut folders = vec![self.dir.join("logs")];
        match self.work {
            Work::Samples { .. } => folders.push(self.parts()),
            Work::Frames { first, .. } => {
                let frame = sequence::frame_path(&self.output, first)?;
                folders.extend(frame.parent().map(Path::to_path_buf));
            }
        }
        if dry_run {
            if let Some(t) = &train {
                println!("# {}\n{t}", train_path.display());
            }
            println!("# {}\n{render}\n# {}\n{merge}", render_path.display(), merge_path.display());
            let folders: Vec<String> = folders.iter().map(|f| utf8(f).map(sh)).collect::<Result<_, _>>()?;
            println!("# to submit them:\nmkdir -p {}", folders.join(" "));
            let after = match &train {
                Some(_) => {
                    println!("TRAIN=$(sbatch --parsable{extra} {})", sh(utf8(&train_path)?));
                    " --dependency=afterok:$TRAIN --kill-on-invalid-dep=yes"
                }
                None => "",
            };
            println!("RENDER=$(sbatch --parsable{after}{extra} {})", sh(utf8(&render_path)?));
            println!(
                "sbatch --dependency=afterok:$RENDER --kill-on-invalid-dep=yes{extra} {}",
                sh(utf8(&merge_path)?)
            );
            return Ok(());
        }
        for f in &folders {
            std::fs::create_dir_all(f).map_err(|e| format!("{}: {e}", f.display()))?;
        }
        io::atomically(&render_path, render.as_bytes())?;
        io::atomically(&merge_path, merge.as_bytes())?;
        // With path guiding, the array waits for the job that learns its guides.
        let after = match &train {
            Some(t) => {
                io::atomically(&train_path, t.as_bytes())?;
                let id = sbatch(&[&self.sbatch[..], &[utf8(&train_path)?.to_owned()]].concat())?;
                println!("submitted training job {id} (path guiding's guides, {})", self.guides().display());
                vec![format!("--dependency=afterok:{id}"), "--kill-on-invalid-dep=yes".into()]
            }
            None => Vec::new(),
        };
        let render_id = sbatch(&[&after[..], &self.sbatch[..], &[utf8(&render_path)?.to_owned()]].concat())?;
        let dependency = format!("--dependency=afterok:{render_id}");
        let merge_args = [
            &[dependency, "--kill-on-invalid-dep=yes".into()],
            &self.sbatch[..],
            &[utf8(&merge_path)?.to_owned()],
        ]
        .concat();
        let merge_id = sbatch(&merge_args).map_err(|e| {
            format!(
                "the render array is job {render_id}, but the merge job was not submitted ({e}); \
                 submit it with: sbatch --dependency=afterok:{render_id} {}",
                merge_path.display()
            )
        })?;
        let what = match self.work {
            Work::Samples { spp } => format!("{spp} samples per pixel"),
            Work::Frames { first, end } => format!("frames {first}..{end}"),
        };
        println!(
            "submitted render array {render_id} ({} tasks, {what}) and merge job {merge_id}",
            self.tasks
        );
        println!("  follow them: squeue -j {render_id},{merge_id}");
        println!("  logs:        {}/logs/ (task-I.log, merge.log)", self.dir.display());
        let result = match self.work {
            Work::Samples { .. } => "the image",
            Work::Frames { .. } => "the frames",
        };
        println!("  {result}:  {} (complete once job {merge_id} has succeeded)", self.output);
        println!(
            "  a failed task cancels the merge job: `sh {}` names what is missing, and submitting \
             the same command again renders only that",
            merge_path.display()
        );
        Ok(())
    }
}

/// Runs `sbatch --parsable ARGS` and returns the job id it prints (`ID` or `ID;CLUSTER`).
fn sbatch(args: &[String]) -> Result<String, String> {
    let out = Command::new("sbatch").arg("--parsable").args(args).output().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => {
            "sbatch not found: submit from a Slurm login node (--dry-run prints the scripts)".to_string()
        }
        _ => format!("sbatch: {e}"),
    })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let id = stdout.trim().split(';').next().unwrap_or("").to_string();
    if !out.status.success() || id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("sbatch {} failed ({}): {}", args.join(" "), out.status, stderr.trim()));
    }
    Ok(id)
}

/// Where task `index` keeps its share of the samples (the checkpoint is this path with
/// `.ckpt` appended).
pub fn part_path(parts: &Path, index: u32) -> PathBuf {
    parts.join(format!("task-{index}.exr"))
}

/// Checks that each of `tasks` shares of a render of `spp` samples per pixel is in `parts`,
/// whole; returns their checkpoints in task order, or names every share that is missing,
/// unreadable, of another split or unfinished.
pub fn check_samples(parts: &Path, tasks: u32, spp: u32) -> Result<Vec<PathBuf>, String> {
    if tasks == 0 || tasks > spp {
        return Err(format!("--tasks {tasks}: {spp} samples per pixel make 1 to {spp} shares"));
    }
    let mut found = Vec::new();
    let mut problems = Vec::new();
    for index in 0..tasks {
        let (a, b) = shard::share(Task { index, count: tasks }, spp);
        let ckpt = checkpoint::path_for(&part_path(parts, index));
        let what = format!("task {index} (samples {a}..{b})");
        if !ckpt.exists() {
            problems.push(format!("{what}: {} is missing", ckpt.display()));
            continue;
        }
        match Checkpoint::load(&ckpt) {
            Err(e) => problems.push(format!("{what}: {e}")),
            Ok(c) if (c.target_spp, c.first_sample) != (spp, a) => problems.push(format!(
                "{what}: {} holds samples from {} of {} per pixel, not this split's",
                ckpt.display(),
                c.first_sample,
                c.target_spp
            )),
            Ok(c) if c.film.spp != b - a => problems.push(format!(
                "{what}: unfinished, {} of its {} samples per pixel in {}",
                c.film.spp,
                b - a,
                ckpt.display()
            )),
            Ok(_) => found.push(ckpt),
        }
    }
    match problems.is_empty() {
        true => Ok(found),
        false => Err(format!(
            "shares not ready ({} of {tasks}), so nothing is merged:\n  {}",
            problems.len(),
            listed(problems.iter().cloned(), problems.len(), "\n  ")
        )),
    }
}

/// How many entries an error lists before it says how many more there are: two million
/// missing frames make a few lines, not 112 MB.
const LISTED: usize = 12;

/// `items` joined by `sep`, the first [`LISTED`] of `count` of them, then how many are left out.
fn listed(items: impl Iterator<Item = String>, count: usize, sep: &str) -> String {
    let shown: Vec<String> = items.take(LISTED).collect();
    match count - shown.len() {
        0 => shown.join(sep),
        more => format!("{}{sep}and {more} more", shown.join(sep)),
    }
}

/// Checks that every frame `[first, end)` of `pattern` is there; otherwise names the missing
/// ones by the task of `tasks` that renders them (the first few of each task, the first few
/// tasks, and how many more).
pub fn check_frames(pattern: &str, (first, end): (u32, u32), tasks: u32) -> Result<(), String> {
    if tasks == 0 {
        return Err("--tasks must be at least 1".into());
    }
    /// A task's missing frames: how many, the first few, and the first one's file.
    #[derive(Clone, Default)]
    struct Missing {
        count: usize,
        frames: Vec<u32>,
        path: PathBuf,
    }
    let mut missing = vec![Missing::default(); tasks.min(end - first) as usize];
    for frame in first..end {
        let path = sequence::frame_path(pattern, frame)?;
        if !sequence::frame_written(&path) {
            let m = &mut missing[((frame - first) % tasks) as usize];
            if m.count == 0 {
                m.path = path;
            }
            if m.frames.len() < LISTED {
                m.frames.push(frame);
            }
            m.count += 1;
        }
    }
    let tasks_missing = missing.iter().filter(|m| m.count > 0).count();
    if tasks_missing == 0 {
        return Ok(());
    }
    let lines = (missing.iter().enumerate()).filter(|(_, m)| m.count > 0).map(|(task, m)| {
        format!(
            "task {task} (frame {} and every {tasks} after it): frames {} missing (the first: {})",
            first + task as u32,
            listed(m.frames.iter().map(u32::to_string), m.count, ", "),
            m.path.display()
        )
    });
    let lines = listed(lines, tasks_missing, "\n  ");
    Err(format!("frames of {first}..{end} are missing, of {tasks_missing} tasks:\n  {lines}"))
}

/// The render flags of `matches` that were given on the command line, written back as
/// arguments for the tasks (`--name=value`, `-Xvalue` for short-only flags, a repeated flag
/// repeated); `flags` is a command holding those flags' definitions.
pub fn forwarded(flags: &clap::Command, matches: &clap::ArgMatches) -> Result<Vec<String>, String> {
    use clap::ArgAction;
    let mut out = Vec::new();
    for arg in flags.get_arguments() {
        let id = arg.get_id().as_str();
        if matches.value_source(id) != Some(clap::parser::ValueSource::CommandLine) {
            continue;
        }
        let (name, long) = match (arg.get_long(), arg.get_short()) {
            (Some(l), _) => (format!("--{l}"), true),
            (None, Some(s)) => (format!("-{s}"), false),
            (None, None) => continue,
        };
        match arg.get_action() {
            ArgAction::SetTrue => out.push(name),
            ArgAction::Count => out.extend(std::iter::repeat_n(name, matches.get_count(id) as usize)),
            _ => {
                for occurrence in matches.get_raw_occurrences(id).into_iter().flatten() {
                    let values = occurrence
                        .map(|v| v.to_str().ok_or_else(|| format!("{name} {v:?}: not Unicode")))
                        .collect::<Result<Vec<&str>, String>>()?;
                    let joined = match (values.len(), arg.get_value_delimiter()) {
                        (0, _) => {
                            out.push(name.clone());
                            continue;
                        }
                        (_, Some(d)) => values.join(&d.to_string()),
                        (_, None) => values.join(" "),
                    };
                    out.push(if long { format!("{name}={joined}") } else { format!("{name}{joined}") });
                }
            }
        }
    }
    Ok(out)
}

/// `path` as text for a script: UTF-8, without control characters (a line break would end a
/// comment line of the script).
pub(super) fn utf8(path: &Path) -> Result<&str, String> {
    match path.to_str() {
        Some(s) if !s.chars().any(char::is_control) => Ok(s),
        _ => Err(format!("{}: a farm needs paths in UTF-8 without control characters", path.display())),
    }
}

/// `pattern` with its `{frame...}` field written as `frames` (the default job folder's name).
fn without_frame_field(pattern: &str) -> String {
    match pattern.find("{frame").and_then(|s| pattern[s..].find('}').map(|e| (s, s + e))) {
        Some((start, end)) => format!("{}frames{}", &pattern[..start], &pattern[end + 1..]),
        None => pattern.to_string(),
    }
}

/// `s` as one word of a POSIX shell command: as it is when it holds only characters no shell
/// treats specially, else in single quotes (a quote inside written `'\''`).
pub fn sh(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    match !s.is_empty() && s.chars().all(plain) {
        true => s.to_string(),
        false => format!("'{}'", s.replace('\'', r"'\''")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_words_and_folder_names() {
        assert_eq!(sh("--spp=16"), "--spp=16");
        assert_eq!(sh("out/f_{frame:04}.png"), "'out/f_{frame:04}.png'");
        assert_eq!(sh("it's"), r"'it'\''s'");
        assert_eq!(sh(""), "''");
        assert_eq!(without_frame_field("/o/f_{frame:04}.png"), "/o/f_frames.png");
        assert_eq!(without_frame_field("/o/a.png"), "/o/a.png");
    }

    #[test]
    fn missing_frames_are_named_by_task() {
        let dir = tempfile::tempdir().unwrap();
        let pattern = format!("{}/f{{frame}}.png", dir.path().display());
        for f in [0, 1, 2, 3, 5, 6] {
            std::fs::write(dir.path().join(format!("f{f}.png")), b"frame").unwrap();
        }
        check_frames(&pattern, (0, 4), 3).unwrap();
        let err = check_frames(&pattern, (0, 9), 3).unwrap_err();
        assert!(err.contains("task 1 (frame 1 and every 3 after it): frames 4, 7 missing"), "{err}");
        assert!(err.contains("task 2 (frame 2 and every 3 after it): frames 8 missing"), "{err}");
        assert!(!err.contains("task 0"), "{err}");
        // Many missing frames: the first few of each task, the first few tasks, and how many
        // more (two million missing frames once made an error of 112 MB).
        let err = check_frames(&pattern, (0, 100_000), 40).unwrap_err();
        assert!(err.len() < 4000, "{} bytes", err.len());
        assert!(err.contains("of 40 tasks"), "{err}");
        assert!(err.contains("task 1 (frame 1 and every 40 after it): frames 41, 81, "), "{err}");
        assert!(err.contains(", and 2487 more missing"), "{err}");
        assert!(err.ends_with("\n  and 28 more"), "{err}");
    }
}
