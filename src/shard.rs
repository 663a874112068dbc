//! Which share of the work this process does when a scheduler starts many copies of one
//! command: `animate --shard auto` and `render --samples auto` read the task's index and the
//! number of tasks from the environment of a Slurm job array task or of a Kubernetes Indexed
//! Job's pod.
//!
//! Slurm sets `SLURM_ARRAY_TASK_ID`, `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_STEP` and
//! `SLURM_ARRAY_TASK_COUNT` in every task of an array (sbatch(1), "OUTPUT ENVIRONMENT
//! VARIABLES", <https://slurm.schedmd.com/sbatch.html>). Kubernetes sets `JOB_COMPLETION_INDEX`
//! in every pod of a Job with `completionMode: Indexed`
//! (<https://kubernetes.io/docs/concepts/workloads/controllers/job/#completion-mode>) but not the
//! number of indices (the Job's `spec.completions`): that comes from `--shard-count` or
//! [`COUNT_VAR`].

use crate::limits::MAX_INDEX;

/// The environment variable holding the number of tasks where the scheduler does not say it
/// (a Kubernetes Indexed Job: set it to the Job's `spec.completions`).
pub const COUNT_VAR: &str = "PATHWAVE_SHARD_COUNT";

/// One task's place among the others: `index` of `count` (0 <= index < count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Task {
    /// This task, from 0.
    pub index: u32,
    /// How many tasks share the work.
    pub count: u32,
}

/// The task this process is, from the environment (`env` looks a variable up; the process's
/// own is [`process_env`]), with `count` from `--shard-count` when given. `flag` names the
/// option in errors (`--shard auto`).
pub fn from_env(
    env: impl Fn(&str) -> Option<String>,
    count: Option<u32>,
    flag: &str,
) -> Result<Task, String> {
    let number = |name: &str| -> Result<Option<u32>, String> {
        match env(name) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse()
                .map(Some)
                .map_err(|_| format!("{flag}: {name}={v:?} is not a whole number >= 0")),
        }
    };
    if count == Some(0) {
        return Err(format!("{flag}: --shard-count must be at least 1"));
    }
    let (index, count, said) = if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
        // An array submitted as --array=MIN-MAX:STEP numbers its tasks MIN, MIN+STEP, ...
        let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        let said = format!("SLURM_ARRAY_TASK_ID={id}, SLURM_ARRAY_TASK_MIN={min}, step {step}");
        if id < min || (id - min) % step != 0 {
            return Err(format!("{flag}: {said} is not a task of an array MIN-MAX:STEP"));
        }
        let slurm_count = number("SLURM_ARRAY_TASK_COUNT")?;
        let count = match (count, slurm_count) {
            (Some(c), Some(s)) if c != s => {
                return Err(format!(
                    "{flag}: --shard-count {c}, but the Slurm array has {s} tasks (SLURM_ARRAY_TASK_COUNT)"
                ));
            }
            (Some(c), _) | (None, Some(c)) => c,
            (None, None) => {
                return Err(format!(
                    "{flag}: SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT (a Slurm \
                     older than 17.11?): pass the number of tasks with --shard-count N"
                ));
            }
        };
        ((id - min) / step, count, said)
    } else if let Some(index) = number("JOB_COMPLETION_INDEX")? {
        let count = match (count, number(COUNT_VAR)?) {
            (Some(c), _) | (None, Some(c)) => c,
            (None, None) => {
                return Err(format!(
                    "{flag}: JOB_COMPLETION_INDEX={index} is set but not the number of tasks: \
                     pass --shard-count N or set {COUNT_VAR} to the Job's spec.completions"
                ));
            }
        };
        (index, count, format!("JOB_COMPLETION_INDEX={index}"))
    } else {
        let explicit = if flag.starts_with("--samples") { "--samples A..B" } else { "--shard I/N" };
        return Err(format!(
            "{flag} takes the task from the environment, and neither SLURM_ARRAY_TASK_ID (a task \
             of a Slurm job array) nor JOB_COMPLETION_INDEX (a pod of a Kubernetes Indexed Job) \
             is set; give the share itself ({explicit})"
        ));
    };
    if count == 0 || index >= count {
        return Err(format!("{flag}: task {index} ({said}) is not one of the {count} tasks"));
    }
    Ok(Task { index, count })
}

/// Looks a variable up in this process's environment (not set, or not Unicode: `None`).
pub fn process_env(name: &str) -> Option<String> {
    std::env::var(name).ok()
}

/// `--shard I/N`, or `--shard auto` with the task from the environment.
pub fn parse_shard(arg: &str, count: Option<u32>) -> Result<Task, String> {
    if arg.trim() == "auto" {
        return from_env(process_env, count, "--shard auto");
    }
    let bad = || format!("--shard takes I/N with 0 <= I < N, not {arg}");
    let (i, n) = arg.split_once('/').ok_or_else(bad)?;
    let (index, count): (u32, u32) =
        (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
    match index < count {
        true => Ok(Task { index, count }),
        false => Err(bad()),
    }
}

/// Parses `A..B` (B excluded) or `A..=B` given to `flag` (`--frames`, `--samples`), B at most
/// [`MAX_INDEX`].
pub fn parse_range(s: &str, flag: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{flag} takes A..B or A..=B, not {s}");
    let (a, b, inclusive) = match s.split_once("..=") {
        Some((a, b)) => (a, b, true),
        None => {
            let (a, b) = s.split_once("..").ok_or_else(bad)?;
            (a, b, false)
        }
    };
    let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    let b = if inclusive { b.checked_add(1) } else { Some(b) };
    match b {
        Some(b) if b > MAX_INDEX => {
            Err(format!("{flag} {s}: indices stop at {MAX_INDEX} (2^24, exact as f32)"))
        }
        Some(b) if b > a => Ok((a, b)),
        Some(_) => Err(format!("{flag} {s} is empty")),
        None => Err(format!("{flag} {s}: indices stop at {MAX_INDEX}")),
    }
}

/// What `render --samples` asks for: a range of sample indices, or this task's share of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Samples {
    /// `A..B`.
    Range(u32, u32),
    /// `auto`: this task's share of the samples per pixel ([`share`]).
    Share(Task),
}

impl Samples {
    /// Parses `--samples A..B` or `--samples auto` (the task from the environment).
    pub fn parse(arg: &str, count: Option<u32>) -> Result<Self, String> {
        match arg.trim() {
            "auto" => from_env(process_env, count, "--samples auto").map(Samples::Share),
            _ => parse_range(arg, "--samples").map(|(a, b)| Samples::Range(a, b)),
        }
    }

    /// The sample indices `[a, b)` of a render of `spp` samples per pixel.
    pub fn range(self, spp: u32) -> Result<(u32, u32), String> {
        match self {
            Samples::Range(a, b) => Ok((a, b)),
            Samples::Share(task) => {
                let (a, b) = share(task, spp);
                match a < b {
                    true => Ok((a, b)),
                    false => Err(format!(
                        "--samples auto: task {} of {} gets none of the {spp} samples per pixel \
                         (split them into at most {spp} tasks)",
                        task.index, task.count
                    )),
                }
            }
        }
    }
}

/// Task `task.index`'s share of `spp` samples per pixel split into `task.count` contiguous
/// ranges as even as whole samples allow: `[i spp / n, (i + 1) spp / n)`.
pub fn share(task: Task, spp: u32) -> (u32, u32) {
    let at = |i: u32| (i as u64 * spp as u64 / task.count.max(1) as u64) as u32;
    (at(task.index), at(task.index + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(vars: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let vars: Vec<(String, String)> = vars.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        move |name| vars.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone())
    }

    #[test]
    fn ranges_and_shards() {
        assert_eq!(parse_range("3..7", "--frames").unwrap(), (3, 7));
        assert_eq!(parse_range("3..=7", "--frames").unwrap(), (3, 8));
        assert!(parse_range("7..3", "--frames").is_err() && parse_range("x", "--frames").is_err());
        // Near u32::MAX nothing wraps; beyond 2^24 (exact f32 frame times) is refused.
        assert!(parse_range("0..=4294967295", "--frames").unwrap_err().contains("indices stop at"));
        assert!(parse_range("4294967290..=4294967295", "--frames").is_err());
        assert!(parse_range("0..16777217", "--frames").is_err());
        assert_eq!(parse_range("0..16777216", "--frames").unwrap(), (0, 1 << 24));
        assert_eq!(parse_shard("1/3", None).unwrap(), Task { index: 1, count: 3 });
        for bad in ["3/3", "1", "a/2"] {
            assert!(parse_shard(bad, None).is_err(), "{bad}");
        }
    }

    #[test]
    fn tasks_from_slurm_and_kubernetes() {
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_STEP", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]);
        assert_eq!(from_env(&slurm, None, "f").unwrap(), Task { index: 2, count: 4 });
        assert_eq!(from_env(&slurm, Some(4), "f").unwrap(), Task { index: 2, count: 4 });
        assert!(from_env(&slurm, Some(3), "f").unwrap_err().contains("the Slurm array has 4 tasks"));
        // --array=10-16:3 is tasks 10, 13, 16.
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "13"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_STEP", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert_eq!(from_env(&stepped, None, "f").unwrap(), Task { index: 1, count: 3 });
        // --array=0,7 has 2 tasks, the second numbered 7: no share can be inferred.
        let listed = env(&[("SLURM_ARRAY_TASK_ID", "7"), ("SLURM_ARRAY_TASK_COUNT", "2")]);
        assert!(from_env(&listed, None, "f").unwrap_err().contains("is not one of the 2 tasks"));
        let no_count = env(&[("SLURM_ARRAY_TASK_ID", "1")]);
        assert!(from_env(&no_count, None, "f").unwrap_err().contains("not SLURM_ARRAY_TASK_COUNT"));
        assert_eq!(from_env(&no_count, Some(2), "f").unwrap(), Task { index: 1, count: 2 });

        let k8s = env(&[("JOB_COMPLETION_INDEX", "3")]);
        let err = from_env(&k8s, None, "--shard auto").unwrap_err();
        assert!(err.contains("--shard-count") && err.contains(COUNT_VAR), "{err}");
        assert_eq!(from_env(&k8s, Some(5), "f").unwrap(), Task { index: 3, count: 5 });
        let k8s = env(&[("JOB_COMPLETION_INDEX", "3"), (COUNT_VAR, "4")]);
        assert_eq!(from_env(&k8s, None, "f").unwrap(), Task { index: 3, count: 4 });
        assert!(from_env(&k8s, Some(3), "f").unwrap_err().contains("not one of the 3 tasks"));

        let none = from_env(env(&[]), None, "--samples auto").unwrap_err();
        assert!(none.contains("SLURM_ARRAY_TASK_ID") && none.contains("JOB_COMPLETION_INDEX"), "{none}");
        let bad = from_env(env(&[("JOB_COMPLETION_INDEX", "x")]), Some(2), "f").unwrap_err();
        assert!(bad.contains("JOB_COMPLETION_INDEX=\"x\""), "{bad}");
        assert!(from_env(&k8s, Some(0), "f").unwrap_err().contains("at least 1"));
    }

    #[test]
    fn shares_cover_every_sample_once() {
        for (spp, n) in [(16, 4), (7, 3), (5, 5), (1 << 24, 7)] {
            let mut end = 0;
            for index in 0..n {
                let (a, b) = share(Task { index, count: n }, spp);
                assert!(a == end && b > a, "{spp} spp, task {index} of {n}: {a}..{b}");
                end = b;
            }
            assert_eq!(end, spp);
        }
        let empty = Samples::Share(Task { index: 0, count: 5 }).range(4).unwrap_err();
        assert!(empty.contains("at most 4 tasks"), "{empty}");
        assert_eq!(Samples::Share(Task { index: 1, count: 4 }).range(16).unwrap(), (4, 8));
    }
}
