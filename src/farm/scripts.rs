//! The sbatch scripts of a farm's jobs: the training job's (path guiding), the render
//! array's and the merge job's.

use super::job::{Job, Work, sh, utf8};
use std::path::PathBuf;

impl Job {
    /// Where the training job writes the guides the tasks read ([`Job::guided`]).
    pub fn guides(&self) -> PathBuf {
        self.dir.join("guides.bin")
    }

    /// The training job's script, with path guiding: it learns the guides of the whole image
    /// once (`render --train-only`) for every task of the render array.
    pub fn train_script(&self) -> Result<String, String> {
        let mut s = String::from(
            "#!/bin/bash\n# pathwave farm: learns path guiding's guides of the image once; every task of the\n\
             # render array reads them (a re-run finds them there and does nothing).\n",
        );
        s += &format!("#SBATCH --job-name={}-train\n", self.name);
        s += &format!("#SBATCH --output={}/logs/train.log\n", utf8(&self.dir)?);
        s += "#SBATCH --open-mode=append\n#SBATCH --requeue\n";
        for d in &self.directives {
            s += &format!("#SBATCH {d}\n");
        }
        s += &format!(
            "exec {} render {} --train-only --guide-file {}",
            sh(utf8(&self.exe)?),
            sh(utf8(&self.scene)?),
            sh(utf8(&self.guides())?)
        );
        for a in &self.render_args {
            s += " ";
            s += &sh(a);
        }
        s += "\n";
        Ok(s)
    }

    /// The folder of the sample shares' checkpoints.
    pub fn parts(&self) -> PathBuf {
        self.dir.join("parts")
    }

    /// The job array's script: task `$SLURM_ARRAY_TASK_ID` renders its frames or its share.
    pub fn render_script(&self) -> Result<String, String> {
        let mut s = String::from("#!/bin/bash\n");
        let (what, run) = match self.work {
            Work::Samples { spp } => (
                format!(
                    "# pathwave farm: task I of this array renders share I of the {spp} samples per pixel of\n\
                     # {}\n# into {}/task-I.exr.ckpt;\n\
                     # a requeued or re-run task resumes it (a finished share is only written out again).\n",
                    self.output,
                    utf8(&self.parts())?
                ),
                // `render --samples auto` takes the same task from the environment.
                format!(
                    "exec {} render {} -o {}\"$SLURM_ARRAY_TASK_ID\".exr --samples auto --shard-count {} --resume{}",
                    sh(utf8(&self.exe)?),
                    sh(utf8(&self.scene)?),
                    sh(&format!("{}/task-", utf8(&self.parts())?)),
                    self.tasks,
                    match self.guided {
                        true => format!(" --guide-file {}", sh(utf8(&self.guides())?)),
                        false => String::new(),
                    }
                ),
            ),
            Work::Frames { first, end } => (
                format!(
                    "# pathwave farm: task I of this array renders frames {first}+I, {first}+I+{n}, ... \
                     (of {first}..{end}) to\n# {}; a requeued or re-run task skips the frames that are there.\n",
                    self.output,
                    n = self.tasks
                ),
                format!(
                    "exec {} animate {} -o {} --frames {first}..{end} --shard auto --shard-count {}",
                    sh(utf8(&self.exe)?),
                    sh(utf8(&self.scene)?),
                    sh(&self.output),
                    self.tasks
                ),
            ),
        };
        s += &what;
        s += &format!("#SBATCH --job-name={}\n", self.name);
        s += &format!("#SBATCH --array=0-{}\n", self.tasks - 1);
        s += &format!("#SBATCH --output={}/logs/task-%a.log\n", utf8(&self.dir)?);
        s += "#SBATCH --open-mode=append\n#SBATCH --requeue\n";
        for d in &self.directives {
            s += &format!("#SBATCH {d}\n");
        }
        s += &run;
        for a in &self.render_args {
            s += " ";
            s += &sh(a);
        }
        s += "\n";
        Ok(s)
    }

    /// The merge job's script.
    pub fn merge_script(&self) -> Result<String, String> {
        let mut s = String::from(
            "#!/bin/bash\n# pathwave farm: runs once every task of the render array has succeeded; checks that every\n\
             # share is there and whole, and names those that are not instead of writing a partial result.\n",
        );
        s += &format!("#SBATCH --job-name={}-merge\n", self.name);
        s += &format!("#SBATCH --output={}/logs/merge.log\n", utf8(&self.dir)?);
        s += "#SBATCH --open-mode=append\n";
        for d in &self.directives {
            s += &format!("#SBATCH {d}\n");
        }
        let exe = sh(utf8(&self.exe)?);
        let (out, n) = (sh(&self.output), self.tasks);
        s += &match self.work {
            Work::Samples { spp } => {
                let parts = sh(utf8(&self.parts())?);
                // The merged image looks as the render flags say.
                let look: String = (self.render_args.iter())
                    .filter(|a| a.starts_with("--exposure=") || a.starts_with("--view-transform="))
                    .map(|a| format!(" {}", sh(a)))
                    .collect();
                format!("exec {exe} farm merge -o {out} --tasks {n} --spp {spp} --parts {parts}{look}\n")
            }
            Work::Frames { first, end } => {
                format!("exec {exe} farm merge -o {out} --tasks {n} --frames {first}..{end}\n")
            }
        };
        Ok(s)
    }
}
