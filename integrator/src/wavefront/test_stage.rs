//! A stage that exists to test the stage table (cargo feature `test-stage`): in this one file
//! and registered by one row of `stages!` (`wavefront/mod.rs`), after its `mod` line. Between
//! shading and the film it multiplies each finished path's radiance by [`EXPOSURE`] and counts
//! the paths it saw in [`SEEN`], so that a test can tell that the table put it in the tiles'
//! pipeline, in its place, on its queue, with its name and its statistics slot.

use super::queues::{Paths, Queues};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

/// The factor on finished paths' radiance, as `f32` bits (1 until a test sets it).
pub static EXPOSURE: AtomicU32 = AtomicU32::new(0x3f80_0000);

/// Finished paths the stage has taken, over the process's renders.
pub static SEEN: AtomicU64 = AtomicU64::new(0);

/// Scales the radiance of the paths in `q.finished`.
pub(super) fn expose(p: &mut Paths, q: &Queues) {
    let k = f32::from_bits(EXPOSURE.load(Relaxed));
    for &i in &q.finished {
        p.l[i as usize] *= k;
    }
    SEEN.fetch_add(q.finished.len() as u64, Relaxed);
}
