//! `pathwave convert`: a Mitsuba XML or glTF scene written as a RON scene that renders the same
//! image.

use crate::engine::scene::{self, gltf, mitsuba};
use crate::io;
use std::path::{Path, PathBuf};

/// `pathwave convert`'s flags.
#[derive(clap::Args, Debug)]
pub struct ConvertCommand {
    /// The Mitsuba scene (.xml) or glTF scene (.gltf, .glb).
    pub scene: PathBuf,
    /// The RON scene to write; file names in it are relative to its folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Set a parameter a Mitsuba scene declares with `<default>`: `-D spp=16` (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
}

/// Converts `c.scene` to RON at `c.output`, checking that the RON loads before writing it.
pub fn run(c: &ConvertCommand) -> Result<(), String> {
    let is_gltf = gltf::is_gltf_scene(&c.scene);
    if !mitsuba::is_xml(&c.scene) && !is_gltf {
        return Err(format!(
            "{}: convert reads Mitsuba XML scenes (.xml) and glTF scenes (.gltf, .glb)",
            c.scene.display()
        ));
    }
    if !c.output.extension().is_some_and(|e| e == "ron") {
        return Err(format!("{}: convert writes a RON scene (.ron)", c.output.display()));
    }
    if io::same_file(&c.output, &c.scene) {
        return Err(format!("{}: the output would replace the scene", c.output.display()));
    }
    let defines = scene::parse_defines(&c.define)?;
    let base = match c.output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    if !base.is_dir() {
        return Err(format!("{}: the folder {} does not exist", c.output.display(), base.display()));
    }
    let ron = match is_gltf {
        true if !defines.is_empty() => return Err("-D: a glTF scene declares no parameters".into()),
        true => gltf::to_ron(&c.scene, &base).map_err(|e| e.to_string())?.ron,
        false => mitsuba::to_ron(&c.scene, &defines, &base).map_err(|e| e.to_string())?.ron,
    };
    // The RON must load where it will be written (its file names are relative to that folder).
    scene::parse(&ron, &base.join(Path::new(c.output.file_name().unwrap_or_default())))
        .map_err(|e| format!("{e}\n(in the RON converted from {})", c.scene.display()))?;
    io::atomically(&c.output, ron.as_bytes())?;
    eprintln!("{}: written from {}", c.output.display(), c.scene.display());
    Ok(())
}
