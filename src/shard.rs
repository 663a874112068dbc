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
    let (index, count) = crate::animate::parse_shard(arg)?;
    Ok(Task { index, count })
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
            _ => crate::animate::parse_range(arg, "--samples").map(|(a, b)| Samples::Range(a, b)),
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
