//! With `--features oidn`, the `oidn` crate links `-lOpenImageDenoise` from `$OIDN_DIR/lib`; this
//! records that folder as the run path of pathwave's binaries and tests, so that they find the
//! library without LD_LIBRARY_PATH (scripts/setup-oidn.sh installs it and prints OIDN_DIR).

fn main() {
    // Without these the script would run again whenever any file of the package changes.
    println!("cargo::rerun-if-changed=build.rs");
    if std::env::var_os("CARGO_FEATURE_OIDN").is_none() {
        return;
    }
    println!("cargo::rerun-if-env-changed=OIDN_DIR");
    // Without OIDN_DIR the crate looks for the library with pkg-config (a system install, found
    // by the loader's own paths).
    let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) else { return };
    let lib = std::path::Path::new(&dir).join("lib");
    let lib = std::fs::canonicalize(&lib).unwrap_or(lib);
    if std::env::var("CARGO_CFG_TARGET_FAMILY").is_ok_and(|f| f == "unix") {
        println!("cargo::rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
