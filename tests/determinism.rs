//! Every random number derives from (seed, pixel, sample index, dimension): the image must be
//! bit-identical whatever the thread count, and change with the seed.

mod common;
use common::*;

fn small_cornell(seed: u64) -> pathwave::engine::scene::SceneDesc {
    let mut desc = scene("cornell.ron");
    desc.render.width = 48.try_into().unwrap();
    desc.render.height = 40.try_into().unwrap();
    desc.render.spp = 12.try_into().unwrap();
    desc.render.seed = seed;
    desc
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    let desc = small_cornell(3);
    let a = render_threads(&desc, 1);
    let b = render_threads(&desc, 2);
    let c = render_threads(&desc, 2);
    assert!(a.pixels.iter().any(|p| p.sum()[0] > 0.0), "the image is not black");
    assert_eq!(a, b, "1 vs 2 threads");
    assert_eq!(b, c, "two runs on 2 threads");
}

#[test]
fn the_seed_changes_the_noise() {
    let a = render_threads(&small_cornell(1), 2);
    let b = render_threads(&small_cornell(2), 2);
    let differing = a.pixels.iter().zip(&b.pixels).filter(|(x, y)| x != y).count();
    assert!(differing > a.pixels.len() / 2, "only {differing} pixels differ");
}
