//! `pathwave merge`: checkpoints of sample shares added into one image.

use crate::checkpoint::{self, Checkpoint};
use crate::io::{self, LinearImage};
use crate::look::{Look, LookArgs};
use std::path::{Path, PathBuf};

/// `pathwave merge`'s flags.
#[derive(clap::Args, Debug)]
pub struct MergeCommand {
    /// Checkpoints (OUT.ckpt files) to merge.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The image; the extension picks the format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// How a PNG shows the image.
    #[command(flatten)]
    pub look: LookArgs,
}

/// Merges the checkpoints `parts` (shares of one render's samples) into `output` and, when
/// they make one run of samples, its checkpoint.
pub fn merge(parts: &[PathBuf], output: &Path, look: &Look) -> Result<(), String> {
    let inputs: Vec<&Path> = parts.iter().map(PathBuf::as_path).collect();
    io::check_output(output, &inputs, false)?;
    let ckpt = checkpoint::path_for(output);
    if let Some(p) = parts.iter().find(|p| io::same_file(p, &ckpt)) {
        return Err(format!(
            "{}: the merged checkpoint would replace the part {}",
            ckpt.display(),
            p.display()
        ));
    }
    // One part in memory at a time, added to the sum as it is read.
    let mut merger = checkpoint::Merger::default();
    for p in parts {
        merger.add(Checkpoint::load(p)?)?;
    }
    let (merged, hi) = merger.finish()?;
    let f = &merged.film;
    io::write(output, &LinearImage { width: f.width, height: f.height, pixels: f.mean() }, look)?;
    let lo = merged.first_sample;
    if lo + f.spp == hi {
        merged.save(&ckpt)?;
        eprintln!(
            "{}: samples {lo}..{hi} of {} from {} parts{}; checkpoint {}",
            output.display(),
            merged.target_spp,
            parts.len(),
            if (lo, hi) == (0, merged.target_spp) { " (all of them)" } else { "" },
            ckpt.display()
        );
    } else {
        eprintln!(
            "{}: {} samples between {lo} and {hi} of {}, with gaps (no checkpoint written: \
             a checkpoint holds one run of samples)",
            output.display(),
            f.spp,
            merged.target_spp
        );
    }
    Ok(())
}
