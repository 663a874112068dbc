//! Accuracy against independent ground-truth renders (`../shared/refs`, linear EXR made with
//! another renderer): block means must agree within the noise estimated from the render itself,
//! and the same test must reject the scene with one albedo changed by 5%.

mod common;
use common::*;

fn check(scene_file: &str, reference_file: &str, ref_spp: u32, spp: u32, material: &str) {
    let reference = reference(reference_file);
    let mut desc = scene(scene_file);
    desc.render.spp = spp.try_into().unwrap();
    let stats = block_z(&render(&desc), &reference, 16, ref_spp);
    eprintln!("{scene_file}: {stats:?}");
    assert!(stats.agrees(), "{scene_file} disagrees with its reference: {stats:?}");

    // The same test must be able to fail: 5% more albedo on one material.
    scale_albedo(&mut desc, material, 1.05);
    let stats = block_z(&render(&desc), &reference, 16, ref_spp);
    eprintln!("{scene_file} with {material} albedo +5%: {stats:?}");
    assert!(!stats.agrees(), "a 5% albedo error in {material} went unnoticed: {stats:?}");
}

#[test]
fn cornell_matches_reference() {
    check("cornell.ron", "cornell.exr", 4096, 128, "white");
}

#[test]
fn cornell_diffuse_matches_reference() {
    check("cornell-diffuse.ron", "cornell-diffuse.exr", 4096, 64, "white");
}

#[test]
fn spheres_sky_matches_reference() {
    check("spheres-sky.ron", "spheres-sky.exr", 2048, 64, "ground");
}
